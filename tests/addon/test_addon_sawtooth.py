"""Saw-tooth and fluted lamps in Blender: their lenses built on the analytic surfaces (written out
here again from the model (docs/model.md), not taken from the mesh code) with closed glass, the Cuts
panel showing the type's fields and the tooth angle's limit, and the rebuild when the cut type
changes."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import PRESETS
from test_addon_panels import _status, draw

pytestmark = pytest.mark.blender

VERTEX_TOL_MM = 1e-3  # float32 metres


def _lens(bl_scene):
    coll = next(c for c in bl_scene.collection.children if c.name.startswith("Lamp Design"))
    return next(obj for obj in coll.objects if obj.name.endswith("Lens"))


def _build(lamp_addon, bl_scene, scene: dict) -> None:
    import bpy

    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    assert bpy.ops.lamp.build() == {"FINISHED"}


@pytest.mark.parametrize("orientation", [0.0, 30.0, -115.0])
def test_the_lens_is_built_on_the_analytic_facets(lamp_addon, addon_core, bl_scene, orientation):
    scene = addon_core.scene.load_scene(PRESETS / "sawtooth-stop-lamp.json")
    lamp = scene["lamps"][0]
    lamp["cuts"]["orientation"] = orientation
    _build(lamp_addon, bl_scene, scene)
    mesh = _lens(bl_scene).data
    R, t = lamp["lens"]["radius"], lamp["lens"]["thickness"]
    p, alpha = lamp["cuts"]["pitch"], math.radians(lamp["cuts"]["tooth_angle"])
    th = math.radians(orientation)
    a = np.array([-math.sin(th), math.cos(th)])  # across the ridges, the way the facets rise
    h = p * math.tan(alpha)

    co = np.array([v.co[:] for v in mesh.vertices]) * 1000.0  # lamp-local mm (the lens sits on the axis)
    mat = np.array([q.material_index for q in mesh.polygons])
    normal = np.array([q.normal[:] for q in mesh.polygons])
    center = np.array([q.center[:] for q in mesh.polygons]) * 1000.0
    outer = (mat == 0) & (np.abs(center[:, 1]) < 1e-6)
    facet_n = np.array([-math.sin(alpha) * a[0], math.cos(alpha), -math.sin(alpha) * a[1]])
    inclined = (mat == 0) & ~outer & np.all(np.abs(normal - facet_n) < 1e-5, axis=1)
    returns = (mat == 0) & ~outer & np.all(np.abs(normal - [a[0], 0.0, a[1]]) < 1e-5, axis=1)
    assert outer.sum() == 1 and np.array_equal(inclined | returns | outer, mat == 0)  # nothing else is glass

    s_of = co[:, [0, 2]] @ a
    for k in np.flatnonzero(inclined):
        vi = list(mesh.polygons[k].vertices)
        strip = math.floor(float(center[k, [0, 2]] @ a) / p + 0.5)
        y = t + math.tan(alpha) * (s_of[vi] - (strip - 0.5) * p)
        assert np.abs(co[vi, 1] - y).max() < VERTEX_TOL_MM
    for k in np.flatnonzero(returns):
        vi = list(mesh.polygons[k].vertices)
        border = (math.floor(float(s_of[vi].mean()) / p) + 0.5) * p
        assert np.abs(s_of[vi] - border).max() < VERTEX_TOL_MM
        assert sorted({round(y, 3) for y in co[vi, 1]}) == pytest.approx([t, t + h], abs=VERTEX_TOL_MM)
    # The inclined facets cover the lens (the outer face, the rim polygon) once, without gaps or overlaps.
    area = sum(mesh.polygons[k].area for k in np.flatnonzero(inclined)) * math.cos(alpha)
    disk = mesh.polygons[int(np.flatnonzero(outer)[0])].area
    assert area == pytest.approx(disk, rel=1e-6)
    assert disk * 1e6 == pytest.approx(math.pi * R * R, rel=2e-3)  # a polygon within the chord tolerance
    strips = math.floor(R / p + 0.5) - math.floor(-R / p + 0.5) + 1
    assert inclined.sum() == strips and returns.sum() == strips - 1
    assert not any(mesh.polygons[k].use_smooth for k in np.flatnonzero(mat == 0))  # planar: flat shaded
    assert co[:, 1].max() == pytest.approx(t + h, abs=VERTEX_TOL_MM)  # the collar up to the apex plane


@pytest.mark.slow
def test_changing_the_cut_type_rebuilds_the_lens_and_back(lamp_addon, addon_core, bl_scene):
    import bpy

    scene = addon_core.scene.load_scene(PRESETS / "paper-baseline.json")
    _build(lamp_addon, bl_scene, scene)
    fisheye = np.array([v.co[:] for v in _lens(bl_scene).data.vertices])
    design = bl_scene.lamp_design
    design.lamps[0].cuts.type = "sawtooth"
    assert bpy.ops.lamp.build() == {"FINISHED"}
    saw = _lens(bl_scene).data
    assert len(saw.vertices) < len(fisheye) / 4  # one polygon per facet
    design.lamps[0].cuts.tooth_angle = 30.0
    assert bpy.ops.lamp.build() == {"FINISHED"}
    ys = np.array([v.co[1] for v in _lens(bl_scene).data.vertices]) * 1000.0
    assert ys.max() == pytest.approx(3.0 + 9.0 * math.tan(math.radians(30.0)), abs=1e-3)
    design.lamps[0].cuts.type = "fisheye"
    assert bpy.ops.lamp.build() == {"FINISHED"}
    assert np.array_equal(np.array([v.co[:] for v in _lens(bl_scene).data.vertices]), fisheye)


def test_the_cuts_panel_shows_the_saw_tooth_fields_and_the_tooth_angle_limit(lamp_addon, addon_core, bl_scene):
    import bpy

    scene = addon_core.scene.load_scene(PRESETS / "paper-baseline.json")
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    design = bl_scene.lamp_design
    shown = draw(bpy.types.LAMP_PT_cuts, bl_scene)
    assert [e[2] for e in shown.props()] == ["type", "pitch", "height"]
    design.lamps[0].cuts.type = "sawtooth"
    design.lamps[0].cuts.pitch = 90.0
    shown = draw(bpy.types.LAMP_PT_cuts, bl_scene)
    assert [e[2] for e in shown.props()] == ["type", "pitch", "tooth_angle", "orientation"]
    assert "At most 48.01 deg for pitch 90 mm (ridges at most 100 mm high)" in shown.labels()
    assert "ridges" in design.lamps[0].cuts.bl_rna.properties["orientation"].description

    design.lamps[0].cuts.tooth_angle = 55.0  # too steep at this pitch: named, with its range
    props, labels = _status(bl_scene).alerts()
    assert props == ["lamps[0].cuts.tooth_angle"]
    assert "allowed [0, 48.01] deg" in " ".join(labels)
    sub_props, _ = draw(bpy.types.LAMP_PT_cuts, bl_scene).alerts()
    assert sub_props == ["lamps[0].cuts.tooth_angle"]


def _polygon_area(xz: np.ndarray) -> float:
    x, z = xz[:, 0], xz[:, 1]
    return 0.5 * float(np.dot(x, np.roll(z, -1)) - np.dot(z, np.roll(x, -1)))


def _flush_rectangle(across: tuple[float, float], pitch: float) -> np.ndarray:
    """A rectangle whose two sides lie on the borders s = ±4.5 pitch, with points along its sides
    as a rectangular lens's rim has (the strips or flutes beyond a side only touch it)."""
    across = np.array(across)
    along = np.array([-across[1], across[0]])
    s, w = 4.5 * pitch, 30.0
    ends = np.array([[-s, -w], [s, -w], [s, w], [-s, w]])
    f = np.arange(6)[:, None] / 6
    st = np.concatenate([ends[i] + f * (ends[(i + 1) % 4] - ends[i]) for i in range(4)])
    return st[:, :1] * across + st[:, 1:] * along


@pytest.mark.parametrize("outline", ["round", "square", "hexagon", "flush"])
def test_the_glass_is_closed_and_the_facets_cover_any_convex_outline(lamp_addon, addon_core, outline):
    """The lens glass (outer face, facets, return facets, side wall below the cuts) is a closed
    surface: every edge is shared by exactly two of its faces; the inclined facets cover the outline."""
    import collections
    import importlib

    mesh_module = importlib.import_module(f"{lamp_addon.__name__}.convert.meshes.sawtooth")
    lamp = addon_core.scene.load_scene(PRESETS / "sawtooth-stop-lamp.json")["lamps"][0]
    orientation = 0.0 if outline == "flush" else 17.0  # ridges along x: s = z exactly, on the border
    lamp["cuts"]["orientation"] = orientation
    R = lamp["lens"]["radius"]
    corners = {"round": 64, "square": 4, "hexagon": 6, "flush": 4}[outline]
    a = 2 * np.pi * np.arange(corners) / corners + (0.3 if corners < 64 else 0.0)
    rim = np.column_stack([R * np.cos(a), R * np.sin(a)])
    if outline == "flush":
        rim = _flush_rectangle(mesh_module.ridge_across(orientation), lamp["cuts"]["pitch"])
    data = mesh_module.sawtooth_lens_mesh(lamp, 64, rim=rim)
    v = data.verts
    glass = [f for f, m in zip(data.faces, data.material, strict=True)
             if m == 0 or v[list(f), 1].min() == 0.0]  # the side wall's glass part reaches y = 0
    edges = collections.Counter(tuple(sorted((f[i], f[(i + 1) % len(f)]))) for f in glass for i in range(len(f)))
    assert set(edges.values()) == {2}
    m = math.tan(math.radians(lamp["cuts"]["tooth_angle"]))
    inclined = [f for f, mat in zip(data.faces, data.material, strict=True)
                if mat == 0 and _is_inclined(v[list(f)], m)]
    area = sum(abs(_polygon_area(v[list(f)][:, [0, 2]])) for f in inclined)
    assert area == pytest.approx(_polygon_area(rim), rel=1e-9)
    # every vertex of a facet on its strip's plane y = t + tan(alpha) (s - (k - 1/2) p)
    t, p, th = lamp["lens"]["thickness"], lamp["cuts"]["pitch"], math.radians(orientation)
    for f in inclined:
        q = v[list(f)]
        s = q[:, 0] * -math.sin(th) + q[:, 2] * math.cos(th)
        k = math.floor(float(s.mean()) / p + 0.5)
        assert np.abs(q[:, 1] - t - m * (s - (k - 0.5) * p)).max() < 1e-9


def _is_inclined(points: np.ndarray, slope: float) -> bool:
    """A polygon whose plane rises at the facets' slope (not a vertical return facet)."""
    n = np.cross(points, np.roll(points, -1, axis=0)).sum(axis=0)  # Newell's: collinear corners are fine
    return abs(n[1]) > 1e-9 * np.linalg.norm(n) and math.isclose(math.hypot(n[0], n[2]) / abs(n[1]), slope,
                                                                   rel_tol=1e-6)


@pytest.mark.parametrize("orientation", [0.0, 60.0])
def test_a_fluted_lens_is_built_within_the_chord_tolerance_of_its_cylinders(lamp_addon, addon_core, bl_scene,
                                                                           orientation):
    scene = addon_core.scene.load_scene(PRESETS / "paper-baseline.json")
    lamp = scene["lamps"][0]
    lamp["cuts"].update(type="flutes", pitch=6.0, height=2.0, orientation=orientation)
    _build(lamp_addon, bl_scene, scene)
    mesh = _lens(bl_scene).data
    t, p, h = lamp["lens"]["thickness"], 6.0, 2.0
    rho = (p * p / 4 + h * h) / (2 * h)
    th = math.radians(orientation)
    a = np.array([-math.sin(th), math.cos(th)])
    mat = np.array([q.material_index for q in mesh.polygons])
    center = np.array([q.center[:] for q in mesh.polygons]) * 1000.0
    cut = (mat == 0) & (np.abs(center[:, 1]) > 1e-6)
    co = np.array([v.co[:] for v in mesh.vertices]) * 1000.0

    def distance(q):
        s = q[:, [0, 2]] @ a
        u = s - np.floor(s / p + 0.5) * p
        return np.abs(np.hypot(u, q[:, 1] - (t + h - rho)) - rho)

    vi = np.unique(np.concatenate([mesh.polygons[k].vertices[:] for k in np.flatnonzero(cut)]))
    # The bands span the lens: their corners are where the band lines (on the cylinders) cross the rim,
    # and between them the rim polygon's corners, on the planar bands.
    on_cylinder = distance(co[vi]) < VERTEX_TOL_MM
    assert on_cylinder.mean() > 0.6 and distance(co[vi]).max() <= 0.05
    mesh.calc_loop_triangles()
    tris = np.array([tri.vertices[:] for tri in mesh.loop_triangles if cut[tri.polygon_index]])
    w = np.array([(1 - i / 6 - j / 6, i / 6, j / 6) for i in range(7) for j in range(7 - i)])
    samples = np.matmul(w, co[tris]).reshape(-1, 3)
    assert distance(samples).max() <= 0.05  # the chord tolerance
    assert all(mesh.polygons[k].use_smooth for k in np.flatnonzero(cut))  # smooth across a flute's bands
    assert co[:, 1].max() == pytest.approx(t + h, abs=VERTEX_TOL_MM)


@pytest.mark.parametrize("outline", ["round", "square", "flush"])
def test_a_fluted_glass_is_closed_and_its_bands_cover_the_outline(lamp_addon, addon_core, outline):
    import collections
    import importlib

    flutes_mesh = importlib.import_module(f"{lamp_addon.__name__}.convert.meshes.flutes")
    lamp = addon_core.scene.load_scene(PRESETS / "paper-baseline.json")["lamps"][0]
    lamp["cuts"].update(type="flutes", pitch=7.0, height=2.5, orientation=-25.0)
    builder = importlib.import_module(f"{lamp_addon.__name__}.convert.meshes.builder")
    # the round lens: within the tolerance
    corners = {"round": builder.circle_segments(45.0), "square": 4, "flush": 4}[outline]
    a = 2 * np.pi * np.arange(corners) / corners + (0.3 if corners == 4 else 0.0)
    rim = np.column_stack([45.0 * np.cos(a), 45.0 * np.sin(a)])
    if outline == "flush":  # two sides on the creases between flutes, as a 150 mm lens of 6 mm flutes has
        rim = _flush_rectangle(flutes_mesh.ridge_across(-25.0), 7.0)
        corners = len(rim)
    data = flutes_mesh.flutes_lens_mesh(lamp, corners, rim=rim)
    v = data.verts
    glass = [f for f, m in zip(data.faces, data.material, strict=True) if m == 0 or v[list(f), 1].min() == 0.0]
    edges = collections.Counter(tuple(sorted((f[i], f[(i + 1) % len(f)]))) for f in glass for i in range(len(f)))
    assert set(edges.values()) == {2}
    bands = [f for f, m in zip(data.faces, data.material, strict=True) if m == 0 and v[list(f), 1].min() > 0]
    assert sum(abs(_polygon_area(v[list(f)][:, [0, 2]])) for f in bands) == pytest.approx(_polygon_area(rim),
                                                                                           rel=1e-9)
    if outline == "round":  # (the side wall is measured against the round lens's cylinder)
        assert data.max_deviation <= 0.05


@pytest.mark.slow
@pytest.mark.parametrize("cut_type", ["fisheye", "sawtooth", "flutes"])
def test_a_rectangular_lens_s_side_wall_reaches_the_reflector_edge(lamp_addon, addon_core, cut_type):
    """The side wall of a rectangular lens stands up to the trimmed reflector's edge, whatever the
    cuts: no gap between them through which rays would leave the lamp (docs/model.md §3, the tracer's
    side wall reaches the reflector's edge)."""
    import json

    meshes = lamp_addon.convert.meshes
    doc = json.loads((PRESETS / "square-tail-lamp.json").read_text())
    doc["lamps"][0]["cuts"] = {"fisheye": {"pitch": 8.0, "height": 1.2},
                               "sawtooth": {"type": "sawtooth", "pitch": 6.0, "tooth_angle": 20.0, "orientation": 0.0},
                               "flutes": {"type": "flutes", "pitch": 6.0, "height": 1.0, "orientation": 90.0}}[cut_type]
    lamp = addon_core.scene.parse_scene(doc)["lamps"][0]
    rim = meshes.builder.outline_rim(lamp)
    lens = meshes.lens.lens_mesh(lamp, len(rim), rim=rim)
    wall = np.unique([i for f, m in zip(lens.faces, lens.material, strict=True) if m == meshes.builder.LENS_SIDE_WALL
                      for i in f])
    reflector = meshes.parts.trimmed_reflector_mesh(lamp, rim).verts
    r = np.hypot(reflector[:, 0], reflector[:, 2])
    edge = reflector[r > 0.999 * np.hypot(rim[:, 0], rim[:, 1]).min()]
    edge = edge[np.abs(meshes.builder.Outline.of_lens(lamp["lens"]).signed_distance(edge[:, 0], edge[:, 2])) < 1e-9]
    assert len(edge) == len(rim)
    gap = np.linalg.norm(edge[:, None, :] - lens.verts[wall][None, :, :], axis=2).min(axis=1)
    assert gap.max() < 1e-9

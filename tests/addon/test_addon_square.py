"""A square lamp built as Blender objects: the lens, its side wall, the trimmed reflector and the
body's opening follow the rectangular outline, within the chord tolerance of the analytic surfaces.

The surfaces are written out here from the model (docs/model.md) (the outline's rounded rectangle, the
paraboloid of docs/model.md §3.2 meeting the rim plane at the outline's farthest point), not taken from
the add-on's mesh code."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from helpers import PRESETS, assert_lens_materials
from test_addon_builder import (
    TOL_MM,
    VERTEX_TOL_MM,
    _build,
    _cut_distance,
    _local,
    _objects,
    _paraboloid_distance,
    _poly_array,
    _triangle_samples,
    _world_mm,
)
from test_addon_compare import assert_bulb_through_a_flat_lens

import core_tracer

pytestmark = pytest.mark.blender


def _outline_distance(x, z, lens: dict) -> np.ndarray:
    """Signed distance to the rounded rectangle (negative inside)."""
    r = lens["corner_radius"]
    qx, qz = np.abs(x) - (lens["width"] / 2 - r), np.abs(z) - (lens["height"] / 2 - r)
    return np.hypot(np.maximum(qx, 0), np.maximum(qz, 0)) + np.minimum(np.maximum(qx, qz), 0) - r


@pytest.fixture
def square(lamp_addon, bl_scene, addon_core):
    scene = addon_core.scene.load_scene(PRESETS / "square-tail-lamp.json")
    _build(lamp_addon, bl_scene, scene)
    return scene, _objects(bl_scene)


@pytest.mark.slow
def test_square_lamp_parts_lie_on_their_surfaces(square, addon_core):
    scene, objs = square
    lamp = scene["lamps"][0]
    lens_doc, f = lamp["lens"], lamp["reflector"]["focal_length"]
    g = addon_core.scene.lamp_geometry(lamp)
    r = lens_doc["corner_radius"]
    reach = math.hypot(lens_doc["width"] / 2 - r, lens_doc["height"] / 2 - r) + r
    assert g["vertex"] == pytest.approx(g["rim"] + reach ** 2 / (4 * f))

    lens = objs["Lamp 1 Lens"]
    v = _local(_world_mm(lens), lamp)
    mat = _poly_array(lens.data, "material_index", np.int32)
    center = np.array([p.center[:] for p in lens.data.polygons]) * 1000.0
    outer = (mat == 0) & (np.abs(center[:, 1]) < 1e-6)
    cut = (mat == 0) & ~outer
    assert outer.sum() == 1
    cut_vi = np.unique(np.concatenate([lens.data.polygons[k].vertices[:] for k in np.flatnonzero(cut)]))
    assert _cut_distance(v[cut_vi], lamp, addon_core.scene).max() < VERTEX_TOL_MM
    assert _outline_distance(v[cut_vi, 0], v[cut_vi, 2], lens_doc).max() < VERTEX_TOL_MM  # clipped by the wall
    cut_dev = _cut_distance(_local(_triangle_samples(lens, lambda p: cut[p]), lamp), lamp, addon_core.scene).max()
    assert cut_dev <= TOL_MM

    # The side wall: on the extruded outline, from the outer face back to the reflector's edge.
    wall = mat == 1
    wall_vi = np.unique(np.concatenate([lens.data.polygons[k].vertices[:] for k in np.flatnonzero(wall)]))
    d = _outline_distance(v[wall_vi, 0], v[wall_vi, 2], lens_doc)
    assert d.max() < VERTEX_TOL_MM and d.min() > -TOL_MM
    samples = _local(_triangle_samples(lens, lambda p: wall[p]), lamp)
    assert np.abs(_outline_distance(samples[:, 0], samples[:, 2], lens_doc)).max() <= TOL_MM
    top = v[wall_vi][v[wall_vi, 1] > g["plane_b"] + 1e-6]
    edge_y = g["vertex"] - (top[:, 0] ** 2 + top[:, 2] ** 2) / (4 * f)
    assert np.abs(top[:, 1] - edge_y).max() < VERTEX_TOL_MM
    assert v[wall_vi, 1].min() == pytest.approx(0.0, abs=1e-6)
    assert v[wall_vi, 1].max() > g["plane_b"] + 5  # behind the rim plane along the straight sides

    # The reflector: on the paraboloid, trimmed to the outline; its edge is the wall's top.
    refl = objs["Lamp 1 Reflector"]
    w = _local(_world_mm(refl), lamp)
    assert _paraboloid_distance(w, lamp, g).max() < VERTEX_TOL_MM
    d = _outline_distance(w[:, 0], w[:, 2], lens_doc)
    assert d.max() < VERTEX_TOL_MM
    assert _paraboloid_distance(_local(_triangle_samples(refl), lamp), lamp, g).max() <= TOL_MM
    edge = w[d > -1e-3]
    gaps = np.linalg.norm(edge[:, None, :] - top[None, :, :], axis=2).min(axis=1)
    assert gaps.max() < VERTEX_TOL_MM  # every vertex of the reflector's edge is a vertex of the wall's top
    assert g["rim"] - 1e-3 <= w[:, 1].min() <= g["rim"] + 0.1  # near the rim plane only at the corners
    assert w[:, 1].max() == pytest.approx(g["vertex"], abs=1e-3)
    centers = np.array([p.center[:] for p in refl.data.polygons])
    normals = np.array([p.normal[:] for p in refl.data.polygons])
    focus = np.array([0.0, g["focus"], 0.0]) / 1000.0
    assert (np.einsum("ij,ij->i", normals, focus - centers) > 0).all()


def test_square_lamp_body_opening_is_the_outline(square):
    scene, objs = square
    lens = scene["lamps"][0]["lens"]
    body = objs["Lamp Body"]
    front = [p for p in body.data.polygons if abs(p.center.y) < 1e-9]
    w, h = scene["body"]["size"]
    r = lens["corner_radius"]
    hole = lens["width"] * lens["height"] - (4 - math.pi) * r * r
    area = sum(p.area for p in front) * 1e6
    # the opening is the rim polygon, inscribed in the outline: each corner chord cuts off a sliver of at
    # most 2/3 of its length times the tolerance, 2/3 * 2 pi r * tol in all
    assert 0 <= area - (w * h - hole) <= 2 / 3 * 2 * math.pi * r * TOL_MM
    xz = np.array([[v.co.x, v.co.z] for v in body.data.vertices]) * 1000
    assert _outline_distance(xz[:, 0], xz[:, 1], lens).min() > -TOL_MM  # no body vertex inside the lens
    assert not any(abs(p.center.y * 1000 - 4.2) < 1e-3 for p in body.data.polygons)  # no bore


def test_square_lamp_materials_follow_the_mapping(square):
    scene, objs = square
    assert_lens_materials(scene, objs["Lamp 1 Lens"], 0)


@pytest.mark.slow
def test_bulb_through_a_flat_rectangular_lens_agrees_with_cycles(lamp_addon, bl_scene):
    # The bulb seen on the axis through the flat clear middle of a square lamp's lens (cut height 0):
    # both renderers give the slab transmittance, whatever the outline around it (test_addon_compare).
    doc = json.loads((PRESETS / "square-tail-lamp.json").read_text())
    lamp = doc["lamps"][0]
    lamp["cuts"]["height"] = 0.0
    lamp["lens"].update(diffuse_color=[0.0, 0.0, 0.0], specular=0.0)  # no eq. 1 on the lens surface
    doc["camera"]["fov_deg"] = 2.0  # 30 mm across at 850 mm: the bulb (8 mm radius) fills the centre
    doc["image"] = {"width": 32, "height": 32}
    scene = core_tracer.parse_scene(doc)
    assert_bulb_through_a_flat_lens(lamp_addon, bl_scene, scene, "flat rectangular lens", 0.02)


def test_a_lamp_added_beside_a_square_lamp_fits(lamp_addon, addon_core):
    layout = lamp_addon.convert.layout
    scene = addon_core.scene.load_scene(PRESETS / "square-tail-lamp.json")
    doc = layout.design_with_new_lamp(scene, 0)  # validated: inside the body, not overlapping
    (x0, z0), (x1, z1) = doc["lamps"][0]["center"], doc["lamps"][1]["center"]
    assert (x1 - x0, z1 - z0) == (150 + layout.MARGIN_MM, 0)
    assert doc["body"]["size"][1] == scene["body"]["size"][1]  # 80 mm high lenses need no taller body


@pytest.mark.slow
@pytest.mark.parametrize("edits", [
    {"lens": {"corner_radius": 0.0}},
    {"cuts": {"height": 0.0}},
    {"cuts": {"pitch": 6.0, "height": 4.0}},
    {"lens": {"width": 150.0, "height": 30.0, "corner_radius": 15.0}},
], ids=["sharp-corners", "flat-cuts", "deep-cuts", "slot"])
def test_square_meshes_are_closed_and_within_tolerance(lamp_addon, addon_core, edits):
    from collections import Counter

    meshes = lamp_addon.convert.meshes
    doc = json.loads((PRESETS / "square-tail-lamp.json").read_text())
    for section, values in edits.items():
        doc["lamps"][0][section].update(values)
    lamp = core_tracer.parse_scene(doc)["lamps"][0]
    rim = meshes.builder.outline_rim(lamp)
    refl = meshes.parts.trimmed_reflector_mesh(lamp, rim)
    lens = meshes.lens.lens_mesh(lamp, len(rim), rim=rim)
    assert refl.max_deviation <= TOL_MM and lens.max_deviation <= TOL_MM
    # The glass is closed: every edge is shared by two faces, except along the cut surface's rim, where
    # the open collar of the side wall stands on it (three), and the collar's top edge (one).
    uses = Counter()
    for face in lens.faces:
        for k in range(len(face)):
            a, b = face[k], face[(k + 1) % len(face)]
            uses[min(a, b), max(a, b)] += 1
    counts = Counter(uses.values())
    assert set(counts) <= {1, 2, 3} and counts[1] == counts[3]
    # The reflector's edge is the collar's top, vertex for vertex: no gap between wall and reflector.
    g = addon_core.scene.lamp_geometry(lamp)
    f = lamp["reflector"]["focal_length"]
    edge = refl.verts[np.abs(_outline_distance(refl.verts[:, 0], refl.verts[:, 2], lamp["lens"])) < 1e-6]
    assert len(edge) == len(rim)
    wall = lens.verts[np.unique([i for face, m in zip(lens.faces, lens.material, strict=True) if m == 1
                                 for i in face])]
    top = wall[np.abs(wall[:, 1] - (g["vertex"] - (wall[:, 0] ** 2 + wall[:, 2] ** 2) / (4 * f))) < 1e-9]
    assert np.linalg.norm(edge[:, None, :] - top[None, :, :], axis=2).min(axis=1).max() < 1e-9

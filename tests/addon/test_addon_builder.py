"""The lamp built as Blender objects: names, geometry against the analytic surfaces, rebuilds, materials.

The analytic surfaces are written out here again from docs/model.md §3 (not taken from the add-on's mesh
code), with the derived positions from ``core_tracer.scene.lamp_geometry``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import PRESETS

pytestmark = pytest.mark.blender

TOL_MM = 0.05  # the chord tolerance the builder promises
VERTEX_TOL_MM = 1e-3  # vertices sit on the surface up to float32 rounding of metres


@pytest.fixture
def scene_mod(addon_core):
    return addon_core.scene


def _load(scene_mod, name: str) -> dict:
    return scene_mod.load_scene(PRESETS / f"{name}.json")


def _built(lamp_addon, bl_scene, scene_mod, name: str) -> dict:
    """The preset ``name``, built in ``bl_scene``; its scene."""
    scene = _load(scene_mod, name)
    _build(lamp_addon, bl_scene, scene)
    return scene


def _build(lamp_addon, bl_scene, scene: dict) -> None:
    import bpy

    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    assert bpy.ops.lamp.build() == {"FINISHED"}


def _objects(bl_scene) -> dict:
    coll = next(c for c in bl_scene.collection.children if c.name.startswith("Lamp Design"))
    return {obj.name: obj for obj in coll.objects}


def _world_mm(obj) -> np.ndarray:
    """Vertex positions in world millimetres."""
    n = len(obj.data.vertices)
    co = np.empty(n * 3, dtype=np.float32)
    obj.data.vertices.foreach_get("co", co)
    m = np.array(obj.matrix_world)
    co = co.reshape(-1, 3).astype(np.float64)
    return (co @ m[:3, :3].T + m[:3, 3]) * 1000.0


def _triangle_samples(obj, tri_filter=None, samples: int = 6) -> np.ndarray:
    """Points (world mm) on Blender's own triangulation of the mesh, a barycentric grid per triangle."""
    mesh = obj.data
    mesh.calc_loop_triangles()
    verts = _world_mm(obj)
    tris = np.array([t.vertices[:] for t in mesh.loop_triangles])
    polys = np.array([t.polygon_index for t in mesh.loop_triangles])
    if tri_filter is not None:
        tris = tris[tri_filter(polys)]
    w = np.array([(1 - i / samples - j / samples, i / samples, j / samples)
                  for i in range(samples + 1) for j in range(samples + 1 - i)])
    return np.matmul(w, verts[tris]).reshape(-1, 3)


def _poly_array(mesh, attr: str, dtype) -> np.ndarray:
    out = np.empty(len(mesh.polygons), dtype=dtype)
    mesh.polygons.foreach_get(attr, out)
    return out


def _cut_distance(points_local: np.ndarray, lamp: dict, scene_mod) -> np.ndarray:
    """Distance to the cap sphere of the cell holding each point (docs/model.md §3.1)."""
    t, p, h = lamp["lens"]["thickness"], lamp["cuts"]["pitch"], lamp["cuts"]["height"]
    x, y, z = points_local.T
    if h == 0:
        return np.abs(y - t)
    rho = scene_mod.cut_sphere_radius(p, h)
    cx, cz = np.round(x / p) * p, np.round(z / p) * p
    return np.abs(np.sqrt((x - cx) ** 2 + (y - (t + h - rho)) ** 2 + (z - cz) ** 2) - rho)


def _paraboloid_distance(points_local: np.ndarray, lamp: dict, g: dict) -> np.ndarray:
    f = lamp["reflector"]["focal_length"]
    r = np.hypot(points_local[:, 0], points_local[:, 2])
    dy = points_local[:, 1] - (g["vertex"] - r * r / (4 * f))
    return np.abs(dy) / np.sqrt(1 + (r / (2 * f)) ** 2)


def _local(points_mm: np.ndarray, lamp: dict) -> np.ndarray:
    cx, cz = lamp["center"]
    return points_mm - np.array([cx, 0.0, cz])


# ---------------------------------------------------------------------------------------------


@pytest.mark.slow
def test_objects_and_names(lamp_addon, bl_scene, scene_mod):
    _build(lamp_addon, bl_scene, _load(scene_mod, "four-lamp-rear-combination"))
    objs = _objects(bl_scene)
    expected = {"Lamp Design", "Lamp Body", "Lamp Sun"} | {f"Lamp {i} {part}" for i in range(1, 5)
                                                           for part in ("Lens", "Reflector", "Bulb", "Socket")}
    assert set(objs) == expected
    root = objs["Lamp Design"]
    assert root.type == "EMPTY" and root.get("lamp_part") == "root" and root.parent is None
    assert all(obj.parent == root for name, obj in objs.items() if name != "Lamp Design")
    assert objs["Lamp Sun"].type == "LIGHT" and objs["Lamp Sun"].data.type == "SUN"
    assert all(obj.type == "MESH" for name, obj in objs.items() if name not in ("Lamp Sun", "Lamp Design"))
    assert [m.name for m in objs["Lamp 2 Lens"].data.materials] == ["Lamp 2 Lens", "Lamp 2 Side Wall"]
    assert bl_scene.world.name == "Lamp Design World"


def test_body_has_an_opening_per_lens(lamp_addon, bl_scene, scene_mod):
    scene = _built(lamp_addon, bl_scene, scene_mod, "four-lamp-rear-combination")
    body = _objects(bl_scene)["Lamp Body"]
    front = [p for p in body.data.polygons if abs(p.center.y) < 1e-9]
    assert all(tuple(p.normal) == pytest.approx((0, -1, 0), abs=1e-6) for p in front)
    w, h = scene["body"]["size"]
    holes = sum(r * r * math.pi for r in (lamp["lens"]["radius"] for lamp in scene["lamps"]))
    area = sum(p.area for p in front) * 1e6  # mm^2
    assert area == pytest.approx(w * h - holes, rel=2e-3)  # the rim polygons are inscribed in the circles
    # No front face covers a lens: the centre of each lens is in no front polygon.
    xs = np.array([[v.co.x, v.co.z] for v in body.data.vertices]) * 1000
    for lamp in scene["lamps"]:
        d = np.hypot(xs[:, 0] - lamp["center"][0], xs[:, 1] - lamp["center"][1])
        assert d.min() >= lamp["lens"]["radius"] * math.cos(math.pi / 16) - 1e-3
    box_min = np.array([v.co[:] for v in body.data.vertices]).min(axis=0) * 1000
    assert box_min[1] == pytest.approx(0.0, abs=1e-6)
    assert np.array([v.co[:] for v in body.data.vertices]).max(axis=0)[1] * 1000 == pytest.approx(
        scene["body"]["depth"], abs=1e-3)


@pytest.mark.slow
@pytest.mark.parametrize("preset", ["paper-baseline", "four-lamp-rear-combination", "paper-cut-size",
                                    "paper-bulb-position"])
def test_geometry_on_the_analytic_surfaces(lamp_addon, bl_scene, scene_mod, preset):
    scene = _built(lamp_addon, bl_scene, scene_mod, preset)
    objs = _objects(bl_scene)
    worst = {}
    for i, lamp in enumerate(scene["lamps"]):
        label = f"Lamp {i + 1}"
        g = scene_mod.lamp_geometry(lamp)
        R, t, h = lamp["lens"]["radius"], lamp["lens"]["thickness"], lamp["cuts"]["height"]

        # Lens: outer face in y = 0, cut surface on the cap spheres, side wall on the cylinder of radius R.
        lens = objs[f"{label} Lens"]
        v = _local(_world_mm(lens), lamp)
        mat = _poly_array(lens.data, "material_index", np.int32)
        center = np.array([p.center[:] for p in lens.data.polygons]) * 1000.0
        normal = np.array([p.normal[:] for p in lens.data.polygons])
        outer = (mat == 0) & (np.abs(center[:, 1]) < 1e-6)
        cut = (mat == 0) & ~outer
        assert outer.sum() == 1 and normal[outer][0] == pytest.approx([0, -1, 0], abs=1e-6)
        cut_vi = np.unique(np.concatenate([lens.data.polygons[k].vertices[:] for k in np.flatnonzero(cut)]))
        assert _cut_distance(v[cut_vi], lamp, scene_mod).max() < VERTEX_TOL_MM
        assert np.hypot(v[cut_vi, 0], v[cut_vi, 2]).max() <= R + 1e-3
        worst[f"{label} cuts"] = _cut_distance(
            _local(_triangle_samples(lens, lambda p, cut=cut: cut[p]), lamp), lamp, scene_mod).max()
        wall_vi = np.unique(np.concatenate([lens.data.polygons[k].vertices[:] for k in np.flatnonzero(mat == 1)]))
        r_wall = np.hypot(v[wall_vi, 0], v[wall_vi, 2])
        assert r_wall.max() <= R + 1e-3 and r_wall.min() >= R * math.cos(math.pi / 16) - 1e-3
        assert v[wall_vi, 1].min() == pytest.approx(0.0, abs=1e-6)
        assert v[wall_vi, 1].max() == pytest.approx(t + h, abs=1e-3)  # up to the cut apex plane
        # Out of the glass: cut faces point away from their cap sphere's centre (upward in y).
        assert (normal[cut][:, 1] > 0).all()

        # Reflector: on the paraboloid, rim radius R in the rim plane, normals toward the focus side.
        refl = objs[f"{label} Reflector"]
        v = _local(_world_mm(refl), lamp)
        assert _paraboloid_distance(v, lamp, g).max() < VERTEX_TOL_MM
        r = np.hypot(v[:, 0], v[:, 2])
        assert r.max() == pytest.approx(R, abs=1e-3)
        assert v[r > R - 1e-3, 1] == pytest.approx(g["rim"], abs=1e-3)
        assert v[:, 1].max() == pytest.approx(g["vertex"], abs=1e-3)
        worst[f"{label} reflector"] = _paraboloid_distance(_local(_triangle_samples(refl), lamp), lamp, g).max()
        centers = np.array([p.center[:] for p in refl.data.polygons])  # local metres, origin on the axis
        normals = np.array([p.normal[:] for p in refl.data.polygons])
        focus = np.array([0.0, g["focus"], 0.0]) / 1000.0
        assert (np.einsum("ij,ij->i", normals, focus - centers) > 0).all()

        # Bulb: a sphere of the bulb radius about the focus plus the offset.
        bulb = objs[f"{label} Bulb"]
        bc = np.array(g["bulb_center"]) + np.array([lamp["center"][0], 0.0, lamp["center"][1]])
        assert np.array(bulb.location) * 1000.0 == pytest.approx(bc, abs=1e-3)
        assert np.array(bulb.location[:]) * 1000.0 == pytest.approx(
            [lamp["center"][0] + lamp["bulb"]["offset"][0], g["focus"] + lamp["bulb"]["offset"][1],
             lamp["center"][1] + lamp["bulb"]["offset"][2]], abs=1e-3)
        rb = lamp["bulb"]["radius"]
        assert np.abs(np.linalg.norm(_world_mm(bulb) - bc, axis=1) - rb).max() < VERTEX_TOL_MM
        worst[f"{label} bulb"] = np.abs(np.linalg.norm(_triangle_samples(bulb) - bc, axis=1) - rb).max()

        # Socket: radius r_s on the axis, from the reflector vertex to the bulb centre.
        sock = objs[f"{label} Socket"]
        v = _local(_world_mm(sock), lamp)
        rs = lamp["socket"]["radius"]
        assert np.hypot(v[:, 0], v[:, 2]).max() == pytest.approx(rs, abs=1e-3)
        assert sorted([v[:, 1].min(), v[:, 1].max()]) == pytest.approx(sorted([g["vertex"], bc[1]]), abs=1e-3)

    for part, dev in worst.items():
        assert dev <= TOL_MM, f"{preset} {part}: {dev:.4f} mm from the analytic surface"


@pytest.mark.slow
def test_smooth_caps_with_sharp_creases(lamp_addon, bl_scene, scene_mod):
    scene = _built(lamp_addon, bl_scene, scene_mod, "paper-baseline")
    mesh = _objects(bl_scene)["Lamp 1 Lens"].data
    p = scene["lamps"][0]["cuts"]["pitch"]
    smooth = _poly_array(mesh, "use_smooth", bool)
    mat = _poly_array(mesh, "material_index", np.int32)
    center = np.array([q.center[:] for q in mesh.polygons]) * 1000.0
    outer = (mat == 0) & (np.abs(center[:, 1]) < 1e-6)
    assert not smooth[outer].any()
    assert smooth[(mat == 0) & ~outer].all()
    assert smooth[mat == 1].all()
    co = np.array([v.co[:] for v in mesh.vertices]) * 1000.0
    crease = inner = 0
    for e in mesh.edges:
        a, b = co[e.vertices[0]], co[e.vertices[1]]
        if min(a[1], b[1]) < 1e-6 or max(np.hypot(a[0], a[2]), np.hypot(b[0], b[2])) > 30:
            continue  # only edges of the cut surface well inside the rim
        on_cell_line = any(abs(c - round(c / p - 0.5) * p - p / 2) < 1e-4 and abs(d - round(d / p - 0.5) * p - p / 2)
                           < 1e-4 for c, d in ((a[0], b[0]), (a[2], b[2])))
        if on_cell_line:
            assert e.use_edge_sharp, (a, b)
            crease += 1
        else:
            assert not e.use_edge_sharp, (a, b)
            inner += 1
    assert crease > 50 and inner > 500


@pytest.mark.slow
def test_rebuild_replaces_in_place(lamp_addon, bl_scene, scene_mod):
    import bpy
    from mathutils import Matrix

    cam_data = bpy.data.cameras.new("My Camera")
    cam = bpy.data.objects.new("My Camera", cam_data)
    bl_scene.collection.objects.link(cam)
    bl_scene.camera = cam

    _build(lamp_addon, bl_scene, _load(scene_mod, "four-lamp-rear-combination"))
    first = {name: obj.as_pointer() for name, obj in _objects(bl_scene).items()}
    n_meshes, n_materials = len(bpy.data.meshes), len(bpy.data.materials)
    assert bpy.ops.lamp.build() == {"FINISHED"}  # unchanged design: the very same objects
    assert {name: obj.as_pointer() for name, obj in _objects(bl_scene).items()} == first
    assert (len(bpy.data.meshes), len(bpy.data.materials)) == (n_meshes, n_materials)

    _build(lamp_addon, bl_scene, _load(scene_mod, "paper-baseline"))  # four lamps -> one
    objs = _objects(bl_scene)
    assert set(objs) == {"Lamp Design", "Lamp Body", "Lamp Sun", "Lamp 1 Lens", "Lamp 1 Reflector", "Lamp 1 Bulb",
                         "Lamp 1 Socket"}
    assert objs["Lamp 1 Lens"].as_pointer() == first["Lamp 1 Lens"]
    assert len([c for c in bl_scene.collection.children if c.name.startswith("Lamp Design")]) == 1
    mesh_users = {obj.data.name for obj in bpy.data.objects if obj.type == "MESH"}
    assert {m.name for m in bpy.data.meshes} == mesh_users  # no orphan meshes
    assert all(m.users > 0 for m in bpy.data.materials)  # no orphan materials
    assert len(bpy.data.materials) == 6  # body; lens, side wall, reflector, bulb, socket of one lamp
    assert len(bpy.data.lights) == 1 and len(bpy.data.worlds) == 1
    # The user's camera object is kept as it was; the first build made the Lamp Camera the scene camera
    # (test_addon_first_build.py: a camera the user picks afterwards stays the scene camera).
    assert cam.name in bl_scene.objects and cam.matrix_world == Matrix.Identity(4) and cam.data == cam_data
    assert lamp_addon.design.camera.is_lamp_camera(bl_scene.camera)


@pytest.mark.slow
def test_two_scenes_keep_their_own_lamps(lamp_addon, bl_scene, scene_mod):
    import bpy

    props, builder = lamp_addon.design.properties, lamp_addon.design.builder
    other = bpy.data.scenes.new("Other")
    other_design = _load(scene_mod, "paper-baseline")
    other_design["lamps"][0]["lens"]["ior"] = 1.7
    props.scene_to_design(other, other_design)
    builder.build_lamp(other, props.design_to_scene(other))
    _build(lamp_addon, bl_scene, _load(scene_mod, "four-lamp-rear-combination"))
    builder.build_lamp(other, props.design_to_scene(other))  # rebuild one, then the other again
    _build(lamp_addon, bl_scene, _load(scene_mod, "four-lamp-rear-combination"))

    mine, theirs = _objects(bl_scene), _objects(other)
    assert len(mine) == 19 and len(theirs) == 7  # the root and its parts
    assert not {o.as_pointer() for o in mine.values()} & {o.as_pointer() for o in theirs.values()}
    lens_a = next(o for o in mine.values() if o.get("lamp_part") == "lamps[0].lens")
    lens_b = next(o for o in theirs.values() if o.get("lamp_part") == "lamps[0].lens")
    assert lens_a.data != lens_b.data and lens_a.data.materials[0] != lens_b.data.materials[0]
    assert _input(lens_b.data.materials[0], "Lens BSDF", "IOR") == pytest.approx(1.7)
    assert bl_scene.world != other.world
    assert all(m.users > 0 for m in bpy.data.meshes) and all(m.users > 0 for m in bpy.data.materials)


def test_rebuild_after_the_collection_was_deleted(lamp_addon, bl_scene, scene_mod):
    import bpy

    _build(lamp_addon, bl_scene, _load(scene_mod, "paper-baseline"))
    coll = next(c for c in bl_scene.collection.children if c.name.startswith("Lamp Design"))
    bpy.data.collections.remove(coll)
    assert bpy.ops.lamp.build() == {"FINISHED"}
    assert len(_objects(bl_scene)) == 7
    assert len([o for o in bpy.data.objects if o.get("lamp_part")]) == 7
    assert {m.name for m in bpy.data.meshes} == {o.data.name for o in bpy.data.objects if o.type == "MESH"}
    assert all(m.users > 0 for m in bpy.data.materials)


def test_user_world_is_kept(lamp_addon, bl_scene, scene_mod):
    import bpy

    mine = bpy.data.worlds.new("My World")
    bl_scene.world = mine
    _build(lamp_addon, bl_scene, _load(scene_mod, "paper-baseline"))
    assert bl_scene.world.name == "Lamp Design World"
    assert mine.use_fake_user  # not lost when the file is saved


def test_build_operator(lamp_addon, bl_scene, scene_mod):
    import bpy

    op = bpy.types.LAMP_OT_build
    assert op.bl_options == {"REGISTER", "UNDO"}  # one undo step (headless Blender has no undo stack)
    assert not bpy.ops.lamp.build.poll()  # no lamp yet
    design = bl_scene.lamp_design
    assert bpy.ops.lamp.lamp_add() == {"FINISHED"}
    assert bpy.ops.lamp.lamp_add() == {"FINISHED"}
    design.lamps[1].center = design.lamps[0].center  # overlapping lenses
    with pytest.raises(RuntimeError, match=r"Lamp 2 › Center: lens overlaps"):
        bpy.ops.lamp.build()
    assert not any(c.name.startswith("Lamp Design") for c in bl_scene.collection.children)


def test_lamp_list_operators(lamp_addon, bl_scene):
    import bpy

    design = bl_scene.lamp_design
    design.body.size = (600.0, 200.0)
    for _ in range(4):
        assert bpy.ops.lamp.lamp_add() == {"FINISHED"}
    assert design.active_lamps_index == 3
    assert lamp_addon.design.properties.design_to_scene(bl_scene)  # new lamps were placed without overlaps
    with pytest.raises(RuntimeError, match="at most 4 lamps"):
        bpy.ops.lamp.lamp_add()
    for _ in range(3):
        assert bpy.ops.lamp.lamp_remove() == {"FINISHED"}
    assert len(design.lamps) == 1 and design.active_lamps_index == 0
    with pytest.raises(RuntimeError, match="at least one lamp"):
        bpy.ops.lamp.lamp_remove()


@pytest.mark.slow
def test_adding_lamps_to_the_baseline_gives_valid_designs(lamp_addon, bl_scene, scene_mod):
    import bpy

    props, margin = lamp_addon.design.properties, lamp_addon.convert.layout.MARGIN_MM
    baseline = _load(scene_mod, "paper-baseline")
    props.scene_to_design(bl_scene, baseline)
    design = bl_scene.lamp_design
    design.lamps[0].lens.radius = 50.0  # a new lamp is a copy of the active one: its radius
    design.lamps[0].lens.ior = 1.6
    border = 110.0 - 50.0  # free body left of the first lens, kept right of the last one
    for count in (2, 3, 4):
        assert bpy.ops.lamp.lamp_add() == {"FINISHED"}
        scene = props.design_to_scene(bl_scene)  # valid: no overlap, every lens inside the body
        assert len(scene["lamps"]) == count and design.active_lamps_index == count - 1
        new, previous = scene["lamps"][-1], scene["lamps"][-2]
        assert {**new, "center": None} == {**previous, "center": None}  # a copy of the active lamp ...
        assert new["center"][1] == previous["center"][1]  # ... in its row, right of it
        assert new["center"][0] - previous["center"][0] == pytest.approx(2 * 50.0 + margin)
        (bx, bz), (width, height) = scene["body"]["center"], scene["body"]["size"]
        assert (bx - width / 2, bz, height) == pytest.approx((-110.0, 0.0, 120.0))  # grown to the right only
        assert bx + width / 2 - (new["center"][0] + 50.0) == pytest.approx(border)
        assert scene["lamps"][0]["center"] == baseline["lamps"][0]["center"]  # the first lamp stays
    assert bpy.ops.lamp.build() == {"FINISHED"}
    assert not bpy.ops.lamp.lamp_add.poll()  # four is the most
    for count in (3, 2, 1):
        assert bpy.ops.lamp.lamp_remove() == {"FINISHED"}
        assert len(props.design_to_scene(bl_scene)["lamps"]) == count


def test_adding_a_lamp_that_does_not_fit_the_spec_is_refused(lamp_addon, addon_core, bl_scene, scene_mod):
    import bpy

    props = lamp_addon.design.properties
    props.scene_to_design(bl_scene, _load(scene_mod, "paper-baseline"))
    bl_scene.lamp_design.body.size = (9990.0, 120.0)  # the lens in the middle: no room within 10 m
    before = props.design_to_scene(bl_scene)
    assert not bpy.ops.lamp.lamp_add.poll()
    with pytest.raises(RuntimeError, match=r"Cannot add a lamp: body\.size\[0\]: 10085(\.0)? is out of range; allowed"):
        bpy.ops.lamp.lamp_add()
    assert props.design_to_scene(bl_scene) == before  # nothing added, nothing moved
    doc = props.design_document(bl_scene)  # the check execute makes, past poll
    with pytest.raises(addon_core.SceneError, match=r"body\.size"):
        lamp_addon.convert.layout.design_with_new_lamp(doc, 0)
    bl_scene.lamp_design.body.size = (9900.0, 120.0)  # a little more room: poll sees the change
    assert bpy.ops.lamp.lamp_add.poll()


# ---------------------------------------------------------------------------------------------
# Materials


def _node(mat, name):
    return mat.node_tree.nodes[name]


def _input(mat, node, socket):
    value = _node(mat, node).inputs[socket].default_value
    return list(value) if hasattr(value, "__len__") else value


@pytest.mark.slow
@pytest.mark.parametrize("preset", ["paper-baseline", "paper-lens-color", "paper-lamp-off",
                                    "four-lamp-rear-combination"])
def test_material_values_follow_the_mapping(lamp_addon, bl_scene, scene_mod, preset):
    import bpy

    scene = _built(lamp_addon, bl_scene, scene_mod, preset)
    for i, lamp in enumerate(scene["lamps"]):
        label = f"Lamp {i + 1}"
        lens = bpy.data.materials[f"{label} Lens"]
        assert _input(lens, "Lens BSDF", "IOR") == pytest.approx(lamp["lens"]["ior"], rel=1e-6)
        assert _input(lens, "Lens BSDF", "Transmission Weight") == 1.0
        assert _input(lens, "Lens BSDF", "Roughness") == 0.0
        assert _input(lens, "Lens BSDF", "Base Color")[:3] == [1.0, 1.0, 1.0]
        a = scene_mod.lens_absorption(lamp["lens"])
        density = _input(lens, "Lens Absorption", "Density")
        color = _input(lens, "Lens Absorption", "Color")[:3]
        assert density == pytest.approx(1000 * max(a), rel=1e-6)
        # Cycles absorbs Density * (1 - Color) per Blender unit = A per mm
        assert [density * (1 - c) / 1000 for c in color] == pytest.approx(a, rel=1e-5, abs=1e-7)
        out = lens.node_tree.nodes["Output"]
        assert out.inputs["Volume"].links[0].from_node.name == "Lens Absorption"
        # the glass, then the lens's own eq. 1 term for camera rays (design.lens_surface) added to it
        surface = out.inputs["Surface"].links[0].from_node
        assert surface.name == "+ Lens Eq. 1" and surface.inputs[0].links[0].from_node.name == "Lens BSDF"

        bulb = bpy.data.materials[f"{label} Bulb"]
        shown = [_input(bulb, "Bulb Emission", "Strength") * c for c in _input(bulb, "Bulb Emission", "Color")[:3]]
        expected = lamp["bulb"]["intensity"] if lamp["bulb"]["on"] else [0.0, 0.0, 0.0]
        assert shown == pytest.approx(expected, rel=1e-6)

        refl = bpy.data.materials[f"{label} Reflector"]
        n = lamp["reflector"]["shininess"]
        assert _input(refl, "Reflector Scatter", "Roughness") == pytest.approx((2 / (n + 2)) ** 0.25, rel=1e-6)
        assert _node(refl, "Reflector Scatter").distribution == "BECKMANN"
        # the paper's mode builds eq. 3 as an emission (design.reflector_glow): the lobe is dark
        assert _input(refl, "Reflector Scatter", "Color")[:3] == pytest.approx([0.0] * 3)
        peak = max(lamp["bulb"]["intensity"]) if lamp["bulb"]["on"] else 0.0
        assert refl.node_tree.nodes["Eq. 3 Weight"].inputs[1].default_value == \
            pytest.approx(lamp["reflector"]["scatter"] * peak, rel=1e-6)
        assert _input(refl, "Reflector Mirror", "Roughness") == 0.0
        assert _input(refl, "Reflector Mirror", "Color")[:3] == pytest.approx([lamp["reflector"]["reflectance"]] * 3)
        assert _input(refl, "Reflector Constant", "Color")[:3] == pytest.approx(lamp["reflector"]["color"])

        for part, key, node in (("Socket", ("socket", "color"), "Socket BSDF"),
                                ("Side Wall", ("lens", "side_wall_color"), "Side Wall BSDF")):
            mat = bpy.data.materials[f"{label} {part}"]
            assert _input(mat, node, "Color")[:3] == pytest.approx(lamp[key[0]][key[1]])
    body = bpy.data.materials["Lamp Body"]
    assert _input(body, "Body BSDF", "Color")[:3] == pytest.approx(scene["body"]["color"])

    sun = bpy.data.objects["Lamp Sun"]
    d = scene["light"]["ambient"]
    assert sun.data.energy == pytest.approx(math.pi * (1 - d), rel=1e-6)
    shine = -(sun.matrix_world.to_3x3() @ __import__("mathutils").Vector((0, 0, 1)))  # the sun shines along -Z
    direction = np.array(scene["light"]["direction"]) / np.linalg.norm(scene["light"]["direction"])
    assert list(shine) == pytest.approx(list(-direction), abs=1e-6)
    world = bl_scene.world
    assert _input(world, "Ambient", "Color")[:3] == pytest.approx([d, d, d])
    assert _input(world, "Background", "Color")[:3] == pytest.approx(scene["background"])
    mix = world.node_tree.nodes["Ambient For Diffuse Rays"]
    assert mix.inputs[0].links[0].from_socket.name == "Is Diffuse Ray"


def test_materials_are_updated_not_duplicated(lamp_addon, bl_scene, scene_mod):
    import bpy

    _built(lamp_addon, bl_scene, scene_mod, "paper-baseline")
    lens = bpy.data.materials["Lamp 1 Lens"]
    pointer = lens.as_pointer()
    bl_scene.lamp_design.lamps[0].lens.ior = 1.6
    assert bpy.ops.lamp.build() == {"FINISHED"}
    assert bpy.data.materials["Lamp 1 Lens"].as_pointer() == pointer
    assert _input(bpy.data.materials["Lamp 1 Lens"], "Lens BSDF", "IOR") == pytest.approx(1.6)
    assert len(bpy.data.materials) == 6

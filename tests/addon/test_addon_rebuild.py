"""Rebuilding keeps the designer's work: the root object, edits that survive, build status, Auto Build.

Starts from Blender's factory startup file (Cube, Camera, Light) where a test says so: the lamp is
built next to objects that are not the add-on's, and must never touch them.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import PRESETS

pytestmark = pytest.mark.blender


@pytest.fixture
def builder(lamp_addon):
    return lamp_addon.design.builder


@pytest.fixture
def autobuild(lamp_addon):
    auto = lamp_addon.design.autobuild
    auto._edits.clear()  # edits other tests made (their timers never ran: no event loop)
    auto._jobs.clear()
    yield auto
    auto._edits.clear()
    auto._jobs.clear()


def _design(lamp_addon, addon_core, bl_scene, name: str = "paper-baseline") -> dict:
    scene = addon_core.scene.load_scene(PRESETS / f"{name}.json")
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    return scene


def _part(bl_scene, part: str):
    return next(o for o in bl_scene.objects if o.get("lamp_part") == part)


def _state(obj) -> tuple:
    """What a build must leave alone on an object that is not the add-on's."""
    return (obj.name, obj.as_pointer(), obj.data.as_pointer() if obj.data else None, obj.parent,
            tuple(tuple(r) for r in obj.matrix_world), tuple(m.as_pointer() for m in obj.data.materials)
            if hasattr(obj.data, "materials") else (), obj.hide_viewport, obj.hide_render, dict(obj.items()))


def _local_radius_mm(obj) -> float:
    co = np.empty(len(obj.data.vertices) * 3, dtype=np.float32)
    obj.data.vertices.foreach_get("co", co)
    co = co.reshape(-1, 3) * 1000.0
    return float(np.hypot(co[:, 0], co[:, 2]).max())


def test_build_in_the_startup_file_touches_none_of_its_objects(lamp_addon, addon_core, startup_scene):
    import bpy

    before = {name: _state(bpy.data.objects[name]) for name in ("Cube", "Camera", "Light")}
    camera, world = startup_scene.camera, startup_scene.world
    _design(lamp_addon, addon_core, startup_scene)
    assert bpy.ops.lamp.build() == {"FINISHED"}

    # What matters: the user's objects (the startup Camera among them) are exactly as they were. The
    # scene's camera pointer is a scene setting, not the Camera object: the first build makes the Lamp
    # Camera the scene camera (test_addon_first_build.py), so the lamp is what F12 shows.
    assert {name: _state(bpy.data.objects[name]) for name in before} == before
    assert camera.name == "Camera" and lamp_addon.design.camera.is_lamp_camera(startup_scene.camera)
    assert world.use_fake_user  # the startup world is replaced by the design's, not lost
    root = lamp_addon.design.root.find_root(startup_scene)
    assert root.name == "Lamp Design" and root.type == "EMPTY" and root.parent is None
    assert root.users_collection[0].name == "Lamp Design"
    parts = [o for o in startup_scene.objects if o.get("lamp_part") not in (None, "root")]
    assert len(parts) == 6 and all(o.parent == root for o in parts)
    assert all(o.users_collection[0] == root.users_collection[0] for o in parts)


@pytest.mark.slow
def test_rebuild_keeps_the_designers_edits(lamp_addon, addon_core, builder, startup_scene):
    """Survive a rebuild: the root parented to another object and moved; a part renamed, nudged,
    hidden, re-parented under another part; a modifier; a material edit on an input the design does not
    drive; an added node. A design-driven value (IOR, lens radius, lamp position) does change."""
    import bpy
    from mathutils import Matrix

    _design(lamp_addon, addon_core, startup_scene)
    assert bpy.ops.lamp.build() == {"FINISHED"}
    others = {name: _state(bpy.data.objects[name]) for name in ("Camera", "Light")}
    car = bpy.data.objects["Cube"]
    root = lamp_addon.design.root.find_root(startup_scene)
    lens, reflector = _part(startup_scene, "lamps[0].lens"), _part(startup_scene, "lamps[0].reflector")
    bulb, socket, body = (_part(startup_scene, p) for p in ("lamps[0].bulb", "lamps[0].socket", "body"))
    pointers = {o.get("lamp_part"): o.as_pointer() for o in startup_scene.objects if o.get("lamp_part")}

    root.parent = car  # the lamp on a car body ...
    root.location = (0.3, -1.0, 0.2)  # ... at its rear, turned and scaled
    root.rotation_euler = (0.0, 0.0, math.radians(30))
    root.scale = (1.5, 1.5, 1.5)
    root_basis = root.matrix_basis.copy()
    lens.name = "Stop Lens"
    reflector.location.z += 0.002  # 2 mm up, in the root's space
    socket.hide_set(True)
    socket.hide_render = True
    body.modifiers.new("Bevel", "BEVEL")
    bulb_world = bulb.matrix_world.copy()
    bulb.parent = lens  # under the lens, where it was in the world
    bulb.matrix_world = bulb_world
    glass = lens.data.materials[0]
    glass.node_tree.nodes["Lens BSDF"].inputs["Roughness"].default_value = 0.2  # not driven
    bump = glass.node_tree.nodes.new("ShaderNodeBump")
    bump.name = "My Bump"
    glass.node_tree.links.new(bump.outputs["Normal"], glass.node_tree.nodes["Lens BSDF"].inputs["Normal"])
    for view_layer in startup_scene.view_layers:
        view_layer.update()

    design = startup_scene.lamp_design
    design.lamps[0].lens.ior = 1.6
    design.lamps[0].lens.radius = 48.0
    design.lamps[0].center = (20.0, 5.0)  # the lamp moves 20 mm right, 5 mm up
    report = builder.build_lamp(startup_scene, lamp_addon.design.properties.design_to_scene(startup_scene))
    assert not report.not_driven

    # Kept
    assert {name: _state(bpy.data.objects[name]) for name in others} == others
    assert "lamp_part" not in car and not car.modifiers
    assert {o.get("lamp_part"): o.as_pointer() for o in startup_scene.objects if o.get("lamp_part")} == pointers
    assert root.parent == car and root.matrix_basis == root_basis
    assert lens.name == "Stop Lens"
    assert socket.hide_get() and socket.hide_render
    assert [m.type for m in body.modifiers] == ["BEVEL"]
    assert bulb.parent == lens
    assert glass.node_tree.nodes["Lens BSDF"].inputs["Roughness"].default_value == pytest.approx(0.2)
    assert glass.node_tree.nodes["Lens BSDF"].inputs["Normal"].links[0].from_node.name == "My Bump"
    assert all(o.parent == root for o in (lens, reflector, socket, body))
    # Changed: what the design drives
    assert glass.node_tree.nodes["Lens BSDF"].inputs["IOR"].default_value == pytest.approx(1.6)
    assert _local_radius_mm(lens) == pytest.approx(48.0, abs=1e-3)
    assert tuple(lens.location) == pytest.approx((0.020, 0.0, 0.005), abs=1e-7)  # moved with the lamp
    assert tuple(reflector.location) == pytest.approx((0.020, 0.0, 0.007), abs=1e-7)  # ... keeping the nudge
    g = addon_core.scene.lamp_geometry(lamp_addon.design.properties.design_to_scene(startup_scene)["lamps"][0])
    in_root = root.matrix_world.inverted() @ bulb.matrix_world  # the bulb, under the lens, at its design place
    expected = Matrix.Translation(((20 + g["bulb_center"][0]) / 1000, g["bulb_center"][1] / 1000,
                                   (5 + g["bulb_center"][2]) / 1000))
    assert np.allclose(np.array(in_root), np.array(expected), atol=1e-6)


@pytest.mark.slow
def test_unchanged_meshes_are_not_remade(lamp_addon, addon_core, builder, bl_scene):
    _design(lamp_addon, addon_core, bl_scene, "four-lamp-rear-combination")
    props = lamp_addon.design.properties
    first = builder.build_lamp(bl_scene, props.design_to_scene(bl_scene))
    assert len(first.remeshed) == 17  # the body and four parts of four lamps
    design = bl_scene.lamp_design
    design.lamps[1].lens.ior = 1.55
    assert builder.build_lamp(bl_scene, props.design_to_scene(bl_scene)).remeshed == []
    design.lamps[2].bulb.radius = 7.0
    assert builder.build_lamp(bl_scene, props.design_to_scene(bl_scene)).remeshed == ["lamps[2].bulb"]
    mesh = _part(bl_scene, "lamps[2].bulb").data
    co = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", co)
    assert np.linalg.norm(co.reshape(-1, 3), axis=1).max() * 1000 == pytest.approx(7.0, abs=1e-3)


def test_a_deleted_driven_node_is_reported_not_brought_back(lamp_addon, addon_core, builder, bl_scene):
    import bpy

    _design(lamp_addon, addon_core, bl_scene)
    assert bpy.ops.lamp.build() == {"FINISHED"}
    glass = _part(bl_scene, "lamps[0].lens").data.materials[0]
    glass.node_tree.nodes.remove(glass.node_tree.nodes["Lens Absorption"])
    bl_scene.lamp_design.lamps[0].lens.ior = 1.55
    report = builder.build_lamp(bl_scene, lamp_addon.design.properties.design_to_scene(bl_scene))
    assert report.not_driven == ["Lamp 1 Lens: Lens Absorption"]
    assert "Lens Absorption" not in glass.node_tree.nodes
    assert glass.node_tree.nodes["Lens BSDF"].inputs["IOR"].default_value == pytest.approx(1.55)


def test_a_material_of_the_designers_own_is_kept(lamp_addon, addon_core, builder, bl_scene):
    import bpy

    _design(lamp_addon, addon_core, bl_scene)
    assert bpy.ops.lamp.build() == {"FINISHED"}
    body = _part(bl_scene, "body")
    paint = bpy.data.materials.new("Car Paint")
    body.data.materials[0] = paint
    bl_scene.lamp_design.body.color = (0.1, 0.2, 0.3)
    report = builder.build_lamp(bl_scene, lamp_addon.design.properties.design_to_scene(bl_scene))
    assert body.data.materials[0] == paint and "lamp_part" not in paint
    assert report.not_driven == ["Lamp Body: the designer's material 'Car Paint'"]


@pytest.mark.slow
def test_removing_a_lamp_removes_its_parts_and_keeps_the_designers_objects(lamp_addon, addon_core, bl_scene):
    import bpy

    _design(lamp_addon, addon_core, bl_scene, "four-lamp-rear-combination")
    assert bpy.ops.lamp.build() == {"FINISHED"}
    lens4 = _part(bl_scene, "lamps[3].lens")
    bezel = bpy.data.objects.new("Bezel", bpy.data.meshes.new("Bezel"))  # the designer's, on lamp 4
    bl_scene.collection.objects.link(bezel)
    bezel.parent = lens4
    bezel.location = (0.0, -0.001, 0.0)
    for view_layer in bl_scene.view_layers:
        view_layer.update()
    where = bezel.matrix_world.copy()
    mesh_names = {p.data.name for p in bl_scene.objects if p.get("lamp_part", "").startswith("lamps[3]")}

    bl_scene.lamp_design.active_lamps_index = 3
    assert bpy.ops.lamp.lamp_remove() == {"FINISHED"}
    assert bpy.ops.lamp.build() == {"FINISHED"}
    assert not [o for o in bl_scene.objects if o.get("lamp_part", "").startswith("lamps[3]")]
    assert not mesh_names & set(bpy.data.meshes.keys())  # their data went with them
    assert bezel.name in bl_scene.objects and bezel.parent == lamp_addon.design.root.find_root(bl_scene)
    assert np.allclose(np.array(bezel.matrix_world), np.array(where), atol=1e-7)


# ---------------------------------------------------------------------------------------------
# Build status


def test_build_status_follows_the_design(lamp_addon, addon_core, builder, bl_scene):
    import bpy

    status = builder.build_status
    _design(lamp_addon, addon_core, bl_scene)
    assert status(bl_scene) == builder.NOT_BUILT and not builder.is_up_to_date(bl_scene)
    assert bpy.ops.lamp.build() == {"FINISHED"}
    assert status(bl_scene) == builder.UP_TO_DATE and builder.is_up_to_date(bl_scene)
    design = bl_scene.lamp_design
    design.camera.fov_deg = 30.0  # the camera and image are not built
    design.image.width = 300
    design.name = "Renamed"
    assert builder.is_up_to_date(bl_scene)
    design.lamps[0].lens.ior = 1.6
    assert status(bl_scene) == builder.OUT_OF_DATE
    assert bpy.ops.lamp.build() == {"FINISHED"}
    assert builder.is_up_to_date(bl_scene)
    bpy.data.objects.remove(_part(bl_scene, "lamps[0].socket"))
    assert status(bl_scene) == builder.OUT_OF_DATE
    assert bpy.ops.lamp.build() == {"FINISHED"}
    design.lamps[0].cuts.height = 9.0  # deeper than the cut size allows
    assert status(bl_scene) == builder.INVALID


def _deep_cut(bl_scene) -> float:
    """Make lamp 1's cuts deep: 90 % of their limit pitch/sqrt 2 (87,000 faces; 98 % gives 186,000 and
    takes twice as long); returns the height."""
    pitch = bl_scene.lamp_design.lamps[0].cuts.pitch
    height = round(0.9 * pitch / math.sqrt(2.0), 3)
    bl_scene.lamp_design.lamps[0].cuts.height = height
    return height


@pytest.mark.slow
def test_a_preview_build_is_lighter_and_says_so(lamp_addon, addon_core, builder, bl_scene):
    _design(lamp_addon, addon_core, bl_scene)
    _deep_cut(bl_scene)
    scene = lamp_addon.design.properties.design_to_scene(bl_scene)
    report = builder.build_lamp(bl_scene, scene, preview=True)
    preview_faces = len(_part(bl_scene, "lamps[0].lens").data.polygons)
    assert report.preview and builder.build_status(bl_scene) == builder.PREVIEW
    assert report.remeshed  # (the preview's own deviation is what it is: only the full build promises 0.05 mm)
    report = builder.build_lamp(bl_scene, scene)
    full_faces = len(_part(bl_scene, "lamps[0].lens").data.polygons)
    assert not report.preview and builder.is_up_to_date(bl_scene)
    assert report.max_deviation["lamps[0].lens"] <= builder.CHORD_TOLERANCE_MM
    assert preview_faces * 10 < full_faces
    # A shallow cut is light already: its preview is the full lens.
    bl_scene.lamp_design.lamps[0].cuts.height = 1.5
    scene = lamp_addon.design.properties.design_to_scene(bl_scene)
    assert not builder.build_lamp(bl_scene, scene, preview=True).preview
    assert builder.is_up_to_date(bl_scene)


# ---------------------------------------------------------------------------------------------
# Auto Build


def test_auto_build_coalesces_edits_into_one_build(lamp_addon, addon_core, builder, autobuild, bl_scene,
                                                   monkeypatch):
    import bpy

    builds = []
    build_lamp = builder.build_lamp
    monkeypatch.setattr(builder, "build_lamp", lambda *a, **k: builds.append(k) or build_lamp(*a, **k))

    design = bl_scene.lamp_design
    assert design.auto_build  # on by default
    _design(lamp_addon, addon_core, bl_scene)  # applying a design is an edit
    assert autobuild.pending() == [bl_scene.name]
    assert bpy.app.timers.is_registered(autobuild.tick)
    edited = autobuild._edits[bl_scene.name]
    assert autobuild.tick(now=edited + autobuild.SETTLE_SECONDS) is None  # one build, done
    assert len(builds) == 1 and builder.is_up_to_date(bl_scene)  # a light lens: the quick build is the full one

    builds.clear()
    for ior in (1.50, 1.52, 1.55):  # three steps of a drag
        design.lamps[0].lens.ior = ior
    edited = autobuild._edits[bl_scene.name]
    assert len(builds) == 0  # the edits themselves build nothing
    assert autobuild.tick(now=edited + autobuild.SETTLE_SECONDS) is None
    assert len(builds) == 1 and builder.is_up_to_date(bl_scene)
    glass = _part(bl_scene, "lamps[0].lens").data.materials[0]
    assert glass.node_tree.nodes["Lens BSDF"].inputs["IOR"].default_value == pytest.approx(1.55)
    assert autobuild.tick(now=edited + 10.0) is None and len(builds) == 1  # nothing left to do


@pytest.mark.slow
def test_auto_build_previews_while_editing_then_builds_in_full(lamp_addon, addon_core, builder, autobuild,
                                                                bl_scene):
    _design(lamp_addon, addon_core, bl_scene)
    autobuild._edits.clear()
    _deep_cut(bl_scene)
    edited = autobuild._edits[bl_scene.name]
    assert autobuild.tick(now=edited + 0.01) == autobuild.TICK_SECONDS  # still editing: a preview
    assert builder.build_status(bl_scene) == builder.PREVIEW
    preview_faces = len(_part(bl_scene, "lamps[0].lens").data.polygons)
    assert autobuild.tick(now=edited + 0.02) == autobuild.TICK_SECONDS  # the preview shows this design
    assert len(_part(bl_scene, "lamps[0].lens").data.polygons) == preview_faces
    # Edits stopped: the full lens is made in the worker thread; the objects keep the preview meanwhile.
    assert autobuild.tick(now=edited + autobuild.SETTLE_SECONDS) == autobuild.TICK_SECONDS
    digest, job = autobuild._jobs[bl_scene.name]
    assert digest == builder.design_digest(lamp_addon.design.properties.design_to_scene(bl_scene))
    job.result(timeout=120)  # waits for the worker (no sleeping)
    assert builder.build_status(bl_scene) == builder.PREVIEW
    assert autobuild.tick(now=edited + autobuild.SETTLE_SECONDS + 0.1) is None  # copied into Blender
    assert builder.is_up_to_date(bl_scene) and not autobuild._jobs
    assert len(_part(bl_scene, "lamps[0].lens").data.polygons) > 10 * preview_faces


@pytest.mark.slow
def test_an_edit_while_the_full_lens_is_made_starts_again(lamp_addon, addon_core, builder, autobuild, bl_scene):
    _design(lamp_addon, addon_core, bl_scene)
    autobuild._edits.clear()
    height = _deep_cut(bl_scene)
    edited = autobuild._edits[bl_scene.name]
    autobuild.tick(now=edited + 0.01)  # preview
    autobuild.tick(now=edited + autobuild.SETTLE_SECONDS)  # full lens for this height, in the worker
    _, first = autobuild._jobs[bl_scene.name]
    bl_scene.lamp_design.lamps[0].cuts.height = height - 0.01  # the designer edits again meanwhile
    first.result(timeout=120)
    edited = autobuild._edits[bl_scene.name]
    assert autobuild.tick(now=edited + 0.01) == autobuild.TICK_SECONDS  # a preview of the new height
    assert builder.build_status(bl_scene) == builder.PREVIEW
    assert autobuild.tick(now=edited + autobuild.SETTLE_SECONDS) == autobuild.TICK_SECONDS
    digest, second = autobuild._jobs[bl_scene.name]
    assert second is not first  # the lens made for the old height is not used
    second.result(timeout=120)
    assert autobuild.tick(now=edited + autobuild.SETTLE_SECONDS + 0.1) is None
    assert builder.is_up_to_date(bl_scene)
    assert lamp_addon.design.root.find_root(bl_scene)[builder.DIGEST_KEY] == digest


def test_auto_build_off_and_invalid_designs_build_nothing(lamp_addon, addon_core, builder, autobuild, bl_scene):
    import bpy

    design = bl_scene.lamp_design
    design.auto_build = False
    _design(lamp_addon, addon_core, bl_scene)
    assert autobuild.pending() == []
    design.auto_build = True  # switching it on brings the objects up to date
    assert autobuild.tick(now=autobuild._edits[bl_scene.name] + autobuild.SETTLE_SECONDS) is None
    assert builder.is_up_to_date(bl_scene)
    design.lamps[0].cuts.height = 9.0  # invalid: nothing is built, nothing is removed
    assert autobuild.tick(now=autobuild._edits[bl_scene.name] + autobuild.SETTLE_SECONDS) is None
    assert builder.build_status(bl_scene) == builder.INVALID
    assert len([o for o in bpy.data.objects if o.get("lamp_part")]) == 7


def test_auto_build_makes_nothing_without_a_lamp(lamp_addon, builder, autobuild, bl_scene):
    import bpy

    assert len(bl_scene.lamp_design.lamps) == 0  # a new scene's design
    bl_scene.lamp_design.body.color = (0.2, 0.2, 0.2)
    assert autobuild.tick(now=autobuild._edits[bl_scene.name] + autobuild.SETTLE_SECONDS) is None
    assert builder.build_status(bl_scene) == builder.NOT_BUILT
    assert not [o for o in bpy.data.objects if o.get("lamp_part")]


def test_auto_build_waits_while_a_part_is_in_edit_mode(lamp_addon, addon_core, builder, autobuild, bl_scene):
    import bpy

    _design(lamp_addon, addon_core, bl_scene)
    assert bpy.ops.lamp.build() == {"FINISHED"}
    lens = _part(bl_scene, "lamps[0].lens")
    bpy.context.view_layer.objects.active = lens
    bpy.ops.object.mode_set(mode="EDIT")
    bl_scene.lamp_design.lamps[0].lens.radius = 48.0
    edited = autobuild._edits[bl_scene.name]
    assert autobuild.tick(now=edited + 5.0) == autobuild.TICK_SECONDS
    assert builder.build_status(bl_scene) == builder.OUT_OF_DATE
    bpy.ops.object.mode_set(mode="OBJECT")
    assert autobuild.tick(now=edited + 5.0) is None
    assert builder.is_up_to_date(bl_scene)


def test_remove_lamp_schedules_a_build(lamp_addon, addon_core, autobuild, bl_scene):
    import bpy

    _design(lamp_addon, addon_core, bl_scene, "four-lamp-rear-combination")
    autobuild._edits.clear()
    assert bpy.ops.lamp.lamp_remove() == {"FINISHED"}
    assert autobuild.pending() == [bl_scene.name]


def test_a_deleted_root_is_made_again_and_takes_the_parts(lamp_addon, addon_core, builder, bl_scene):
    import bpy

    _design(lamp_addon, addon_core, bl_scene)
    assert bpy.ops.lamp.build() == {"FINISHED"}
    lens = _part(bl_scene, "lamps[0].lens")
    bpy.data.objects.remove(lamp_addon.design.root.find_root(bl_scene))
    assert lens.parent is None and builder.build_status(bl_scene) == builder.NOT_BUILT
    assert bpy.ops.lamp.build() == {"FINISHED"}
    root = lamp_addon.design.root.find_root(bl_scene)
    assert _part(bl_scene, "lamps[0].lens") == lens and lens.parent == root
    assert all(o.parent == root for o in bl_scene.objects if o.get("lamp_part") not in (None, "root"))
    assert builder.is_up_to_date(bl_scene)


def test_after_undo_the_objects_follow_the_restored_design(lamp_addon, addon_core, builder, autobuild, bl_scene):
    """Undo restores a design whose objects may lag one build behind (the timer's build is saved with the
    next step); the undo handler has them rebuilt at once, in full."""
    import bpy

    _design(lamp_addon, addon_core, bl_scene)
    assert bpy.ops.lamp.build() == {"FINISHED"}
    bl_scene.lamp_design.lamps[0].lens.ior = 1.6  # as if undo had brought back a design not yet built
    autobuild._edits.clear()
    autobuild._after_undo(bl_scene)
    assert autobuild.pending() == [bl_scene.name]
    assert autobuild.tick(now=0.0) is None  # settled at once: a full build, not a preview
    assert builder.is_up_to_date(bl_scene)


def test_a_copy_of_the_lamp_is_left_alone(lamp_addon, addon_core, builder, bl_scene):
    """A designer copies the built lamp for the other side of the car (Shift+D copies the part tags too):
    rebuilding updates the lamp under the root, not the copy."""
    import bpy

    _design(lamp_addon, addon_core, bl_scene)
    assert bpy.ops.lamp.build() == {"FINISHED"}
    root = lamp_addon.design.root.find_root(bl_scene)
    lens = _part(bl_scene, "lamps[0].lens")
    copy = lens.copy()  # as Shift+D: tags and all, in the same collection, parented elsewhere
    copy.data = lens.data.copy()
    lens.users_collection[0].objects.link(copy)
    copy.parent = None
    copy.name = "Right Lens"
    coll = lens.users_collection[0]
    coll.objects.unlink(lens)  # the copy now comes first in the collection
    coll.objects.link(lens)
    copy_vertices = len(copy.data.vertices)
    bl_scene.lamp_design.lamps[0].lens.radius = 48.0
    builder.build_lamp(bl_scene, lamp_addon.design.properties.design_to_scene(bl_scene))
    assert lens.parent == root and _local_radius_mm(lens) == pytest.approx(48.0, abs=1e-3)
    assert copy.name in bl_scene.objects and len(copy.data.vertices) == copy_vertices  # untouched
    assert _local_radius_mm(copy) == pytest.approx(45.0, abs=1e-3)


def test_a_lamp_built_before_the_root_existed_is_adopted(lamp_addon, addon_core, builder, bl_scene):
    """A file saved by an earlier version: parts at the world origin without root, driven transform or
    shape tags. A build puts them under a new root, where the design says, and keeps their materials."""
    import bpy

    _design(lamp_addon, addon_core, bl_scene)
    assert bpy.ops.lamp.build() == {"FINISHED"}
    bpy.data.objects.remove(lamp_addon.design.root.find_root(bl_scene))
    parts = {o.get("lamp_part"): o for o in bl_scene.objects if o.get("lamp_part")}
    for obj in parts.values():
        del obj[builder.DRIVEN_KEY]
        if obj.type == "MESH":
            del obj.data[builder.GEOMETRY_KEY]
    glass = parts["lamps[0].lens"].data.materials[0]
    assert bpy.ops.lamp.build() == {"FINISHED"}
    root = lamp_addon.design.root.find_root(bl_scene)
    assert {o.get("lamp_part"): o for o in bl_scene.objects if o.get("lamp_part") not in (None, "root")} == parts
    assert all(o.parent == root for o in parts.values())
    g = addon_core.scene.lamp_geometry(lamp_addon.design.properties.design_to_scene(bl_scene)["lamps"][0])
    assert tuple(parts["lamps[0].bulb"].location) == pytest.approx(
        tuple(x / 1000 for x in g["bulb_center"]), abs=1e-7)
    assert parts["lamps[0].lens"].data.materials[0] == glass and builder.is_up_to_date(bl_scene)


def test_a_full_lens_that_cannot_be_made_leaves_the_preview(lamp_addon, addon_core, builder, autobuild, bl_scene,
                                                             monkeypatch, capsys):
    def fail(scene):
        raise MemoryError("no room for the lens")

    monkeypatch.setattr(lamp_addon.design.parts, "make_lenses", fail)
    _design(lamp_addon, addon_core, bl_scene)
    autobuild._edits.clear()
    _deep_cut(bl_scene)
    edited = autobuild._edits[bl_scene.name]
    autobuild.tick(now=edited + 0.01)
    assert autobuild.tick(now=edited + autobuild.SETTLE_SECONDS) == autobuild.TICK_SECONDS
    autobuild._jobs[bl_scene.name][1].exception(timeout=120)
    assert autobuild.tick(now=edited + autobuild.SETTLE_SECONDS + 0.1) is None  # no traceback, no retry loop
    assert builder.build_status(bl_scene) == builder.PREVIEW
    assert "could not make the full lens (MemoryError('no room for the lens'))" in capsys.readouterr().out

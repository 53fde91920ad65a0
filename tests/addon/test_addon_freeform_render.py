"""Designs with free-form parts in Blender: F12 through the free-form tracer, the geometry read and
built once per geometry change, and the exported JSON + .glb rendering the same from the command line."""

from __future__ import annotations

import json

import numpy as np
import pytest
from helpers import BASELINE, PRESETS, run_cli

pytestmark = pytest.mark.blender

SIZE = (48, 40)


def _converted(lamp_addon, addon_core, bl_scene, path=BASELINE, size=SIZE) -> dict:
    scene = addon_core.scene.load_scene(path)
    scene["image"] = {"width": size[0], "height": size[1], "samples": 1}
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    lamp_addon.design.lamp_camera.ensure_lamp_camera(bl_scene, frame=False)
    lamp_addon.freeform.conversion.convert_to_freeform(bl_scene)
    bl_scene.render.engine = "LAMP_TRACER"
    return scene


def _f12(bl_scene, path) -> np.ndarray:
    import bpy
    import OpenImageIO as oiio

    settings = bl_scene.render.image_settings
    settings.file_format = "OPEN_EXR"
    settings.color_depth = "32"
    assert bpy.ops.render.render() == {"FINISHED"}
    bpy.data.images["Render Result"].save_render(str(path), scene=bl_scene)
    buf = oiio.ImageBuf(str(path))
    return np.asarray(buf.get_pixels(oiio.FLOAT)).reshape(buf.spec().height, buf.spec().width, -1)


def _expected(lamp_addon, bl_scene) -> np.ndarray:
    import bpy

    seen = lamp_addon.design.camera.scene_for_render(bl_scene)
    prepared = lamp_addon.freeform.render.prepare(bl_scene, bpy.context.evaluated_depsgraph_get(), seen)
    return lamp_addon.freeform.render.render_passes(prepared, seen["image"]["width"], seen["image"]["height"]).image


@pytest.mark.slow
def test_f12_renders_the_parts_with_the_freeform_tracer(lamp_addon, addon_core, bl_scene, tmp_path):
    _converted(lamp_addon, addon_core, bl_scene)
    rgba = _f12(bl_scene, tmp_path / "f12.exr")
    expected = _expected(lamp_addon, bl_scene)
    assert rgba.shape == (SIZE[1], SIZE[0], 4)
    np.testing.assert_array_equal(rgba[:, :, :3], expected)
    # A real lamp: the red lens glows in the middle, the grey body around it.
    centre, corner = rgba[SIZE[1] // 2, SIZE[0] // 2], rgba[SIZE[1] // 2, 3]
    assert centre[0] > 3 * centre[1] and corner[0] == pytest.approx(corner[1], rel=0.1) and corner[0] > 0.05
    # Taking the roles away renders the parametric lamp again (its objects' visibility does not matter).
    for obj in lamp_addon.freeform.properties.role_objects(bl_scene):
        lamp_addon.freeform.properties.set_role(obj, "NONE")
    parametric = _f12(bl_scene, tmp_path / "parametric.exr")
    np.testing.assert_array_equal(parametric[:, :, :3],
                                  addon_core.render(lamp_addon.design.camera.scene_for_render(bl_scene)))


@pytest.mark.slow
def test_geometry_is_built_once_per_geometry_change(lamp_addon, addon_core, bl_scene, tmp_path):
    import bpy

    _converted(lamp_addon, addon_core, bl_scene)
    geometry = lamp_addon.freeform.geometry
    first = _f12(bl_scene, tmp_path / "1.exr")
    reads = geometry.reads()
    cache = geometry._entries[bl_scene.name].cache
    assert cache.builds == 1
    _f12(bl_scene, tmp_path / "2.exr")  # nothing changed: the meshes and the structure are reused
    assert geometry.reads() == reads and cache.builds == 1
    lens = next(o for o in lamp_addon.freeform.properties.role_objects(bl_scene) if o.lamp_role.role == "lens")
    lens.lamp_role.lens.specular = 0.0  # a role value is not geometry
    bpy.context.view_layer.update()
    no_highlight = _f12(bl_scene, tmp_path / "3.exr")
    # Blender tags the object's geometry on any edit of its properties, so the meshes are read again,
    # but they are the same: the structure is not built again.
    assert cache.builds == 1
    assert not np.array_equal(first, no_highlight)
    lens.location.x += 0.005  # 5 mm to the right: new geometry
    bpy.context.view_layer.update()
    moved = _f12(bl_scene, tmp_path / "4.exr")
    assert cache.builds == 2
    assert not np.array_equal(moved, no_highlight)
    np.testing.assert_array_equal(moved[:, :, :3], _expected(lamp_addon, bl_scene))


@pytest.mark.slow
def test_exported_pair_renders_the_same_from_the_command_line(lamp_addon, addon_core, bl_scene, tmp_path):
    import bpy
    import OpenImageIO as oiio

    _converted(lamp_addon, addon_core, bl_scene, size=(64, 48))
    root = lamp_addon.design.root.find_root(bl_scene)
    root.location = (0.3, -0.2, 0.1)  # the lamp stands anywhere: the file holds it in the root's frame
    root.rotation_euler = (0.1, 0.2, 0.3)
    lens = next(o for o in lamp_addon.freeform.properties.role_objects(bl_scene) if o.lamp_role.role == "lens")
    lens.modifiers.new("Bend", "SIMPLE_DEFORM").deform_axis = "Z"  # reshaped: modifiers are applied
    lens.modifiers["Bend"].angle = 0.2
    lamp_addon.design.lamp_camera.ensure_lamp_camera(bl_scene, frame=False)
    bpy.context.view_layer.update()
    in_blender = _f12(bl_scene, tmp_path / "blender.exr")
    json_path = tmp_path / "my lamp.json"
    assert bpy.ops.lamp.freeform_export(filepath=str(json_path)) == {"FINISHED"}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["blender.exr", "my lamp.glb", "my lamp.json"]
    doc = json.loads(json_path.read_text())
    assert doc["schema"] == "lamp-scene/2" and doc["freeform"]["mesh_file"] == "my lamp.glb"
    assert len(doc["freeform"]["parts"]) == 6
    proc = run_cli("render", json_path, "-o", tmp_path / "cli.exr")
    assert proc.returncode == 0, proc.stderr
    buf = oiio.ImageBuf(str(tmp_path / "cli.exr"))
    cli = np.asarray(buf.get_pixels(oiio.FLOAT)).reshape(buf.spec().height, buf.spec().width, -1)
    np.testing.assert_array_equal(cli[:, :, :3], in_blender[:, :, :3])  # pixel for pixel
    assert in_blender[:, :, :3].max() > 1.0  # the bulb seen through the lens


@pytest.mark.slow
def test_export_never_replaces_without_being_asked(lamp_addon, addon_core, bl_scene, tmp_path):
    import bpy

    _converted(lamp_addon, addon_core, bl_scene)
    json_path = tmp_path / "lamp.json"
    (tmp_path / "lamp.glb").write_bytes(b"someone else's file")
    with pytest.raises(RuntimeError, match="exists already; tick Replace Existing"):
        bpy.ops.lamp.freeform_export(filepath=str(json_path))
    assert (tmp_path / "lamp.glb").read_bytes() == b"someone else's file" and not json_path.exists()
    assert bpy.ops.lamp.freeform_export(filepath=str(json_path), replace=True) == {"FINISHED"}
    assert (tmp_path / "lamp.glb").read_bytes()[:4] == b"glTF"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["lamp.glb", "lamp.json"]  # no temporary left
    names = {o.name for o in bpy.data.objects}
    assert all(o.name in names for o in lamp_addon.freeform.properties.role_objects(bl_scene))
    assert not any(".lamp-export-aside" in n for n in names) and len(bpy.data.scenes) == 1


def _viewport_session(lamp_addon, bl_scene):
    """A viewport session updated from the scene, and the scene camera's matrices as a viewport's
    (window, view) at ``SIZE``."""
    import bpy

    camera = bl_scene.camera
    depsgraph = bpy.context.evaluated_depsgraph_get()
    window = [list(r) for r in camera.calc_matrix_camera(depsgraph, x=SIZE[0], y=SIZE[1])]
    view = [list(r) for r in camera.matrix_world.inverted()]
    session = lamp_addon.render.viewport.ViewportSession(None, in_background=False)
    session.update(bl_scene, depsgraph)
    return session, window, view


@pytest.mark.slow
def test_the_viewport_renders_the_parts_and_restarts_on_geometry_changes(lamp_addon, addon_core, bl_scene):
    import bpy

    _converted(lamp_addon, addon_core, bl_scene)
    session, window, view = _viewport_session(lamp_addon, bl_scene)
    assert session.freeform is not None and session.freeform.geometry is not None
    session.sync(bl_scene, SIZE[0], SIZE[1], window, view)
    while session.preview.step() and session.preview.frame().divisor != 1:
        pass
    assert session.status() == "Lamp Tracer: full resolution, refining"  # 16 samples per pixel next
    shown = session.preview.frame().image
    while session.preview.step():  # the refined stage, more samples per pixel
        pass
    assert session.status() == "Lamp Tracer: full resolution, 16 samples per pixel"
    cache = session.freeform.geometry.cache
    assert cache.builds == 1  # every stage on one structure
    # The viewport's view is the scene camera's: its image is the F12 image up to the camera's
    # float32 round trip through the view matrices.
    expected = _expected(lamp_addon, bl_scene)
    close = np.abs(shown - expected).max(axis=2) <= 1e-3 * max(1.0, float(expected.max()))
    assert close.mean() > 0.97
    session.sync(bl_scene, SIZE[0], SIZE[1], window, view)  # a redraw: the same job
    generation = session.preview.generation
    lens = next(o for o in lamp_addon.freeform.properties.role_objects(bl_scene) if o.lamp_role.role == "lens")
    lens.location.z += 0.01
    depsgraph = bpy.context.evaluated_depsgraph_get()
    depsgraph.update()
    session.update(bl_scene, depsgraph)
    session.sync(bl_scene, SIZE[0], SIZE[1], window, view)
    assert session.preview.generation == generation + 1
    while session.preview.step():
        pass
    assert cache.builds == 2 and not np.array_equal(session.preview.frame().image, shown)


@pytest.mark.slow
def test_an_exported_pair_imports_back_as_parts_with_roles(lamp_addon, addon_core, bl_scene, tmp_path):
    import bpy

    _converted(lamp_addon, addon_core, bl_scene)
    exported = _f12(bl_scene, tmp_path / "exported.exr")
    json_path = tmp_path / "shared.json"
    assert bpy.ops.lamp.freeform_export(filepath=str(json_path)) == {"FINISHED"}
    parts_before = {o.name: lamp_addon.freeform.properties.part_document(o)
                    for o in lamp_addon.freeform.properties.role_objects(bl_scene)}
    bpy.ops.wm.read_homefile(use_empty=True)  # a colleague's empty file
    bl_scene = bpy.context.scene
    with pytest.raises(RuntimeError, match="not added to a library"):
        bpy.ops.lamp.preset_import(filepath=str(json_path))
    assert bpy.ops.lamp.preset_import(filepath=str(json_path), add_to_library=False) == {"FINISHED"}
    parts = lamp_addon.freeform.properties.role_objects(bl_scene)
    assert {o.name: lamp_addon.freeform.properties.part_document(o) for o in parts} == parts_before
    assert all(lamp_addon.freeform.materials.role_material(o) is not None for o in parts)
    bl_scene.render.engine = "LAMP_TRACER"
    imported = _f12(bl_scene, tmp_path / "imported.exr")
    # The parts made from the .glb carry the file's positions and, as free custom normals, normals the
    # exporter writes back as the file's (freeform.meshes.normals_exporting_as): the same picture.
    equal = (imported[:, :, :3] == exported[:, :, :3]).all(axis=2)
    print(f"\nimported pair vs Blender's own render: {equal.mean():.1%} of the pixels equal")
    assert equal.all()


@pytest.mark.slow
def test_a_freeform_preset_with_a_missing_mesh_file_changes_nothing(lamp_addon, addon_core, bl_scene, tmp_path):
    import bpy

    _converted(lamp_addon, addon_core, bl_scene)
    json_path = tmp_path / "shared.json"
    assert bpy.ops.lamp.freeform_export(filepath=str(json_path)) == {"FINISHED"}
    (tmp_path / "shared.glb").unlink()
    bpy.ops.wm.read_homefile(use_empty=True)
    with pytest.raises(RuntimeError, match=r'freeform\.mesh_file: "shared\.glb" is missing'):
        bpy.ops.lamp.preset_import(filepath=str(json_path), add_to_library=False)
    assert list(bpy.context.scene.objects) == [] and len(bpy.context.scene.lamp_design.lamps) == 0


def _add_my_lamp(lamp_addon, bl_scene) -> list:
    """The designer's own small lamp beside the parametric one: a flat 25 × 4 × 25 mm slab of glass
    with the lens role in front of the body, 75 mm right of the lamp axis, and a bulb-role sphere
    (r = 3 mm) between it and the body. Placed in the world through the design root's matrix."""
    import bmesh
    import bpy
    from mathutils import Matrix

    to_world = lamp_addon.design.root.world_from_design(bl_scene)
    made = []
    for name, make, where, scale, role, values in (
            ("My Slab", lambda bm: bmesh.ops.create_cube(bm, size=1.0), (0.075, -0.010, 0.0),
             (0.025, 0.004, 0.025), "lens", {"ior": 1.5, "absorption": (0.5, 0.5, 0.02)}),
            ("My Bulb", lambda bm: bmesh.ops.create_uvsphere(bm, u_segments=24, v_segments=12, radius=0.003),
             (0.075, -0.004, 0.0), (1.0, 1.0, 1.0), "bulb", {"intensity": (8.0, 7.0, 6.0), "on": True})):
        mesh = bpy.data.meshes.new(name)
        bm = bmesh.new()
        make(bm)
        bm.to_mesh(mesh)
        bm.free()
        obj = bpy.data.objects.new(name, mesh)
        bl_scene.collection.objects.link(obj)
        obj.matrix_world = to_world @ Matrix.LocRotScale(where, None, scale)
        lamp_addon.freeform.properties.set_role(obj, role, values)
        made.append(obj)
    bpy.context.view_layer.update()
    return made


def _mixed(lamp_addon, addon_core, bl_scene, size=SIZE, path=BASELINE) -> tuple[dict, list]:
    """The paper's lamp (or ``path``'s) built, not converted, and the designer's own slab and bulb
    beside it."""
    scene = addon_core.scene.load_scene(path)
    scene["image"] = {"width": size[0], "height": size[1], "samples": 1}
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    lamp_addon.design.builder.build_lamp(bl_scene, lamp_addon.design.properties.design_to_scene(bl_scene))
    lamp_addon.design.lamp_camera.ensure_lamp_camera(bl_scene, frame=False)
    bl_scene.render.engine = "LAMP_TRACER"
    return scene, _add_my_lamp(lamp_addon, bl_scene)


def _state(objects) -> list:
    return [(o.name, o.data.name, tuple(map(tuple, o.matrix_world)), tuple(v.co[:] for v in o.data.vertices),
             o.lamp_role.role, o.hide_render, o.hide_get()) for o in objects]


@pytest.mark.slow
def test_f12_renders_the_parametric_lamp_with_the_designers_parts(lamp_addon, addon_core, bl_scene, tmp_path):
    import bpy

    _, mine = _mixed(lamp_addon, addon_core, bl_scene)
    built = [o for o in bl_scene.objects if o.get("lamp_part") not in (None, "root", "sun")]
    before = _state(mine) + _state(built)
    names = sorted(o.name for o in bpy.data.objects)
    meshes = len(bpy.data.meshes)
    status = lamp_addon.freeform.status
    assert status.rendered_text(bl_scene) == status.MIXED_TEXT
    panel = " ".join(line.text for line in status.panel_lines(bl_scene))
    assert status.MIXED_TEXT in panel and "only" not in panel
    rgba = _f12(bl_scene, tmp_path / "mixed.exr")
    np.testing.assert_array_equal(rgba[:, :, :3], _expected(lamp_addon, bl_scene))
    prepared = lamp_addon.freeform.render.prepare(bl_scene, bpy.context.evaluated_depsgraph_get(),
                                                  lamp_addon.design.camera.scene_for_render(bl_scene))
    roles = sorted(p["role"] for p in prepared.scene["freeform"]["parts"])
    assert roles == ["body", "bulb", "bulb", "lens", "lens", "reflector", "side_wall", "socket"]
    # Both lamps are in the picture: the red lens in the middle, the designer's bulb through their slab.
    h, w = SIZE[1], SIZE[0]
    centre = rgba[h // 2, w // 2]
    assert centre[0] > 3 * centre[1]
    right = rgba[:, w // 2 + 1:, :3]
    assert right.max() > 1.0  # only a bulb is brighter than 1 here; the parametric bulb is behind the lens
    # Nothing of Blender's was made or changed.
    assert _state(mine) + _state(built) == before
    assert sorted(o.name for o in bpy.data.objects) == names and len(bpy.data.meshes) == meshes
    # The parametric lamp out of date: the parts alone, and the panel says so.
    bl_scene.lamp_design.lamps[0].lens.thickness = 4.0
    assert status.rendered_text(bl_scene) == status.NOT_BUILT_TEXT
    assert "Build Lamp" in " ".join(line.text for line in status.panel_lines(bl_scene))
    parts_only = lamp_addon.freeform.render.prepare(bl_scene, bpy.context.evaluated_depsgraph_get(),
                                                    lamp_addon.design.camera.scene_for_render(bl_scene))
    assert sorted(p["role"] for p in parts_only.scene["freeform"]["parts"]) == ["bulb", "lens"]


@pytest.mark.slow
@pytest.mark.parametrize("path", [BASELINE, PRESETS / "prism-plate-stop-lamp.json"], ids=lambda p: p.stem)
def test_exported_mixed_pair_renders_the_same_from_the_command_line(lamp_addon, addon_core, bl_scene, tmp_path,
                                                                    path):
    import bpy
    import OpenImageIO as oiio

    _mixed(lamp_addon, addon_core, bl_scene, size=(64, 48), path=path)
    root = lamp_addon.design.root.find_root(bl_scene)
    root.location = (0.3, -0.2, 0.1)  # the lamp stands anywhere: the file holds it in the root's frame
    root.rotation_euler = (0.1, 0.2, 0.3)
    for obj in (bpy.data.objects["My Slab"], bpy.data.objects["My Bulb"]):
        obj.parent = root  # the designer's parts move with the lamp
    lamp_addon.design.lamp_camera.ensure_lamp_camera(bl_scene, frame=False)
    bpy.context.view_layer.update()
    in_blender = _f12(bl_scene, tmp_path / "blender.exr")
    json_path = tmp_path / "mixed.json"
    assert bpy.ops.lamp.freeform_export(filepath=str(json_path)) == {"FINISHED"}
    doc = json.loads(json_path.read_text())
    built = lamp_addon.freeform.parametric.built_parts(bl_scene, bpy.context.evaluated_depsgraph_get())
    parametric = lamp_addon.freeform.parametric.part_documents(built, lamp_addon.design.camera.scene_for_render(
        bl_scene))
    assert len(doc["freeform"]["parts"]) == 2 + len(parametric) >= 8  # the designer's 2 and the lamp's
    proc = run_cli("render", json_path, "-o", tmp_path / "cli.exr")
    assert proc.returncode == 0, proc.stderr
    buf = oiio.ImageBuf(str(tmp_path / "cli.exr"))
    cli = np.asarray(buf.get_pixels(oiio.FLOAT)).reshape(buf.spec().height, buf.spec().width, -1)
    np.testing.assert_array_equal(cli[:, :, :3], in_blender[:, :, :3])  # pixel for pixel
    assert not any(".lamp-export-aside" in o.name or "(Parametric)" in o.name for o in bpy.data.objects)


@pytest.mark.slow
def test_rebuilding_the_parametric_lamp_of_a_mixed_design_is_rendered(lamp_addon, addon_core, bl_scene, tmp_path):
    import bpy

    _mixed(lamp_addon, addon_core, bl_scene)
    first = _f12(bl_scene, tmp_path / "1.exr")
    cache = lamp_addon.freeform.geometry._entries[bl_scene.name].cache
    assert cache.builds == 1
    bl_scene.lamp_design.lamps[0].center = (-20.0, 0.0)  # the lamp 20 mm to the left, built again
    lamp_addon.design.builder.build_lamp(bl_scene, lamp_addon.design.properties.design_to_scene(bl_scene))
    bpy.context.view_layer.update()
    moved = _f12(bl_scene, tmp_path / "2.exr")
    assert cache.builds == 2
    np.testing.assert_array_equal(moved[:, :, :3], _expected(lamp_addon, bl_scene))
    columns = lambda image: np.nonzero(image[:, :, 0] > 2 * image[:, :, 1])[1]  # noqa: E731 - the red lens
    # 20 mm is about 4 pixels here (48 pixels across about 225 mm)
    shift = columns(first).mean() - columns(moved).mean()
    print(f"\nthe lens moved {shift:.2f} pixels left")
    assert 3 <= shift <= 6


@pytest.mark.slow
def test_the_viewport_renders_a_mixed_design(lamp_addon, addon_core, bl_scene):

    _mixed(lamp_addon, addon_core, bl_scene)
    session, window, view = _viewport_session(lamp_addon, bl_scene)
    geometry = session.freeform.geometry
    parametric = sorted(name for name in geometry.meshes if name.endswith(" (Parametric)"))
    assert len(parametric) == 6 and "Lamp 1 Side Wall (Parametric)" in parametric
    assert sorted(set(geometry.meshes) - set(parametric)) == ["My Bulb", "My Slab"]
    session.sync(bl_scene, SIZE[0], SIZE[1], window, view)
    while session.preview.step() and session.preview.frame().divisor != 1:
        pass
    shown = session.preview.frame().image  # full resolution, one sample per pixel as F12
    expected = _expected(lamp_addon, bl_scene)
    close = np.abs(shown - expected).max(axis=2) <= 1e-3 * max(1.0, float(expected.max()))
    print(f"\nviewport vs F12 on a mixed design: {close.mean():.1%} of the pixels within 0.1 %")
    assert close.mean() > 0.97 and geometry.cache.builds == 1


def test_compare_keeps_the_traced_parametric_lamp_in_the_cycles_half(lamp_addon, addon_core, bl_scene):
    # Cycles renders what the tracer traces: the designer's parts and the parametric lamp still in
    # use; once the design is edited without rebuilding, the tracer leaves the lamp out, so does Cycles.
    compare = lamp_addon.compare.comparison
    _, mine = _mixed(lamp_addon, addon_core, bl_scene)
    built = [o for o in bl_scene.objects if o.get("lamp_part") not in (None, "root", "sun") and o.type == "MESH"]
    assert built
    with compare.CompareRun(bl_scene, samples=1, resolution=(24, 24), build=False) as run:
        run.prepare()
        assert not any(o.hide_render for o in built + mine)
    assert not any(o.hide_render for o in built)
    bl_scene.lamp_design.lamps[0].lens.ior = 1.6  # the built lamp is now out of date
    with compare.CompareRun(bl_scene, samples=1, resolution=(24, 24), build=False) as run:
        run.prepare()
        assert all(o.hide_render for o in built) and not any(o.hide_render for o in mine)
    assert not any(o.hide_render for o in built)  # put back

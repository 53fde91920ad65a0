"""Bad free-form input in Blender: the core's one-line message, naming the object and what to fix, in
Blender's report (F12, export) and in the Free-form Parts panel; never a traceback."""

from __future__ import annotations

import re

import pytest
from helpers import BASELINE, whole_report

pytestmark = pytest.mark.blender


def _scene(lamp_addon, addon_core, bl_scene) -> None:
    scene = addon_core.scene.load_scene(BASELINE)
    scene["image"] = {"width": 24, "height": 16, "samples": 1}
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    lamp_addon.design.lamp_camera.ensure_lamp_camera(bl_scene, frame=False)
    bl_scene.render.engine = "LAMP_TRACER"


def _part(lamp_addon, kind: str, name: str, role: str = "lens"):
    import bpy

    if kind == "plane":
        bpy.ops.mesh.primitive_plane_add(size=0.05)
    elif kind == "open box":  # a cube without its top face
        import bmesh

        bpy.ops.mesh.primitive_cube_add(size=0.02, location=(0.0, 0.01, 0.0))
        bm = bmesh.new()
        bm.from_mesh(bpy.context.active_object.data)
        top = max(bm.faces, key=lambda f: f.calc_center_median().z)
        bmesh.ops.delete(bm, geom=[top], context="FACES_ONLY")
        bm.to_mesh(bpy.context.active_object.data)
        bm.free()
    elif kind == "grid":
        bpy.ops.mesh.primitive_grid_add(x_subdivisions=40, y_subdivisions=40, size=0.05)
    else:
        bpy.ops.mesh.primitive_cube_add(size=0.02, location=(0.0, 0.01, 0.0))
    obj = bpy.context.active_object
    obj.name = name
    lamp_addon.freeform.properties.set_role(obj, role)
    return obj


def _flip(obj) -> None:
    import bpy

    bpy.context.view_layer.objects.active = obj
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.select_all(action="SELECT")
    bpy.ops.mesh.flip_normals()
    bpy.ops.object.mode_set(mode="OBJECT")


def _f12_message(bl_scene, capfd=None) -> str:
    """F12's error: the one-line report, or with ``capfd`` its whole text (a long one is cut to one line
    and written whole to the Info editor first)."""
    import bpy

    if capfd is not None:
        capfd.readouterr()
    with pytest.raises(RuntimeError) as raised:
        bpy.ops.render.render()
    return str(raised.value) if capfd is None else whole_report(str(raised.value), capfd.readouterr().out)


CASES = {
    "open lens": ("open box", None, r'mesh "Open Lens": is not closed \(\d+ open or non-manifold edges\)'),
    "flat lens": ("plane", None, r'mesh "Flat Lens": encloses no volume.*Solidify'),
    "flipped normals": ("cube", _flip, r'mesh "Flipped Lens": has its normals pointing inward.*Recalculate Outside'),
}


@pytest.mark.parametrize("case", list(CASES))
def test_a_bad_lens_mesh_is_named_in_f12_the_panel_and_export(lamp_addon, addon_core, bl_scene, tmp_path, case,
                                                               capfd):
    import bpy

    kind, edit, message = CASES[case]
    _scene(lamp_addon, addon_core, bl_scene)
    name = {"open lens": "Open Lens", "flat lens": "Flat Lens", "flipped normals": "Flipped Lens"}[case]
    obj = _part(lamp_addon, kind, name)
    if edit is not None:
        edit(obj)
    text = _f12_message(bl_scene, capfd)
    assert "Lamp Tracer: " in text and "Traceback" not in text
    assert re.search(message, text), text
    assert "Traceback" not in capfd.readouterr().err
    assert re.search(message, lamp_addon.freeform.status.part_problem(bl_scene))
    capfd.readouterr()
    with pytest.raises(RuntimeError) as raised:
        bpy.ops.lamp.freeform_export(filepath=str(tmp_path / "lamp.json"))
    assert re.search(message, whole_report(str(raised.value), capfd.readouterr().out))
    assert list(tmp_path.iterdir()) == []  # nothing written
    # Fixed, the problem goes away at the next render.
    bpy.data.objects.remove(obj)
    _part(lamp_addon, "cube", "Good Lens")
    assert bpy.ops.render.render() == {"FINISHED"}
    assert lamp_addon.freeform.status.part_problem(bl_scene) is None


def test_a_role_value_out_of_range_is_named_in_f12(lamp_addon, addon_core, bl_scene):
    _scene(lamp_addon, addon_core, bl_scene)
    obj = _part(lamp_addon, "cube", "Glass")
    obj.lamp_role.lens["shininess"] = -5.0  # what an old file or a script may have stored
    text = _f12_message(bl_scene)
    assert 'Lamp Tracer: free-form part: "Glass" Lens › Shininess: -5.0 is out of range; allowed [0, 10000]' in text


def test_a_huge_mesh_is_refused_with_the_limit(lamp_addon, addon_core, bl_scene, monkeypatch):
    # The core's limit is 2 million triangles a mesh; the test lowers it rather than build such a mesh.
    _scene(lamp_addon, addon_core, bl_scene)
    monkeypatch.setattr(addon_core.freeform.meshes, "MAX_TRIANGLES_PER_MESH", 1000)
    _part(lamp_addon, "grid", "Dense Body", role="body")
    text = _f12_message(bl_scene)
    assert 'mesh "Dense Body": has 3200 triangles; allowed at most 1000' in text, text


def test_without_embree_the_feature_says_so_once_and_the_lamp_renders(lamp_addon, addon_core, bl_scene,
                                                                      monkeypatch, capfd):
    import sys

    import bpy

    monkeypatch.setitem(sys.modules, "embreex", None)
    monkeypatch.setattr(lamp_addon.freeform.status, "_available", [])
    monkeypatch.setattr(lamp_addon.freeform.render, "_said", set())
    _scene(lamp_addon, addon_core, bl_scene)
    _part(lamp_addon, "cube", "Glass")
    ok, reason = lamp_addon.freeform.status.available()
    assert not ok and "embreex" in reason
    lines = [line.text for line in lamp_addon.freeform.status.panel_lines(bl_scene)]
    assert " ".join(lines).startswith("free-form rendering needs the embreex package")
    capfd.readouterr()
    for _ in range(2):
        assert bpy.ops.render.render() == {"FINISHED"}  # the parametric lamp, with a warning the first time
    printed = capfd.readouterr()
    said = [line for line in (printed.out + printed.err).splitlines() if line.startswith("Warning: ")]
    assert sum("free-form parts are not rendered" in line for line in said) == 1  # once, in one line
    assert "Traceback" not in printed.err
    # Everything else works: building, exporting the preset.
    assert bpy.ops.lamp.build() == {"FINISHED"}


def test_the_viewport_says_which_part_is_wrong(lamp_addon, addon_core, bl_scene):
    import bpy

    _scene(lamp_addon, addon_core, bl_scene)
    obj = _part(lamp_addon, "cube", "Flipped Lens")
    _flip(obj)
    camera = bl_scene.camera
    depsgraph = bpy.context.evaluated_depsgraph_get()
    window = [list(r) for r in camera.calc_matrix_camera(depsgraph, x=24, y=16)]
    view = [list(r) for r in camera.matrix_world.inverted()]
    session = lamp_addon.render.viewport.ViewportSession(None, in_background=False)
    session.update(bl_scene, depsgraph)
    session.sync(bl_scene, 24, 16, window, view)
    session.preview._run(session.preview.job)  # the worker's loop, in this thread
    assert re.match(r'Lamp Tracer: mesh "Flipped Lens": has its normals pointing inward', session.status())

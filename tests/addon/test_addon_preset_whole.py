"""Applying a preset in Blender is all or nothing (issue 21): whatever fails part-way, after the
design was written and the Lamp Camera made, the design and the scene are put back exactly as they
were and the operator reports one line."""

from __future__ import annotations

import pytest
from helpers import PRESETS

pytestmark = pytest.mark.blender


def _state(lamp_addon, bl_scene) -> dict:
    import bpy

    return {"design": lamp_addon.design.properties.design_document(bl_scene),
            "objects": sorted(ob.name for ob in bpy.data.objects),
            "cameras": sorted(c.name for c in bpy.data.cameras),
            "camera": bl_scene.camera.name if bl_scene.camera else None,
            "custom": sorted(k for k in bl_scene.keys() if k not in bl_scene.bl_rna.properties),
            "render": (bl_scene.render.engine, bl_scene.render.resolution_x, bl_scene.render.resolution_y),
            "exposure": bl_scene.view_settings.exposure}


@pytest.fixture
def failing_after_changes(lamp_addon, monkeypatch):
    """``show_view`` (or, in a file not yet set up, ``set_up``) makes the Lamp Camera (as it does), then
    fails as a broken file or a Blender failure would, after the design has been written."""
    ops = lamp_addon.presets.apply
    real_view, real_set_up = ops.show_view, ops.render_setup.set_up

    def show_view_then_fail(bl_scene, scene):
        real_view(bl_scene, scene)
        raise ValueError("negative image size in the header")

    def set_up_then_fail(bl_scene):
        real_set_up(bl_scene)
        raise ValueError("negative image size in the header")

    monkeypatch.setattr(ops, "show_view", show_view_then_fail)
    monkeypatch.setattr(ops.render_setup, "set_up", set_up_then_fail)
    return ops


def test_a_failure_part_way_leaves_design_and_scene_as_they_were(lamp_addon, bl_scene, failing_after_changes):
    import bpy

    core = lamp_addon.presets.ops.P
    before = _state(lamp_addon, bl_scene)
    with pytest.raises(ValueError, match="negative image size"):
        failing_after_changes.apply_preset_whole(bl_scene, core.load_preset(str(PRESETS / "paper-baseline.json")))
    assert _state(lamp_addon, bl_scene) == before
    assert not [ob for ob in bpy.data.objects if "Camera" in ob.name]


def test_the_import_operator_reports_one_line_and_changes_nothing(lamp_addon, bl_scene, failing_after_changes):
    import bpy

    before = _state(lamp_addon, bl_scene)
    with pytest.raises(RuntimeError) as err:
        bpy.ops.lamp.preset_import(filepath=str(PRESETS / "four-lamp-rear-combination.json"), apply=True,
                                   add_to_library=False)
    text = str(err.value).strip()
    assert "Not imported, the design is unchanged: ValueError: negative image size in the header" in text
    assert "\n" not in text.removeprefix("Error: ")
    assert _state(lamp_addon, bl_scene) == before


def test_a_good_preset_still_applies(lamp_addon, bl_scene):
    import bpy

    assert bpy.ops.lamp.preset_import(filepath=str(PRESETS / "four-lamp-rear-combination.json"), apply=True,
                                      add_to_library=False) == {"FINISHED"}
    assert len(lamp_addon.design.properties.design_document(bl_scene)["lamps"]) == 4


def _meshes(bpy) -> dict:
    """Each of our parts' mesh: the numbers it was made from and its size."""
    return {ob.get("lamp_part"): (ob.data.get("lamp_geometry"), len(ob.data.vertices), len(ob.data.polygons))
            for ob in bpy.data.objects if ob.type == "MESH" and ob.get("lamp_part")}


@pytest.mark.slow
def test_a_rebuild_that_fails_while_meshing_leaves_the_built_lamp_as_it_was(lamp_addon, bl_scene, monkeypatch):
    """The lamp is built; applying another preset rebuilds it, and making its third new shape fails (as
    a deep-cut lens that runs out of memory, or an interrupt, would): the objects, their meshes and the
    design are what they were. Before the shapes were made ahead of any change, the first parts were
    refilled with the new preset's geometry and stayed so."""
    import bpy

    core = lamp_addon.presets.ops.P
    apply = lamp_addon.presets.apply
    apply.apply_preset_whole(bl_scene, core.load_preset(str(PRESETS / "four-lamp-rear-combination.json")))
    assert bpy.ops.lamp.build() == {"FINISHED"}
    before, meshes = _state(lamp_addon, bl_scene), _meshes(bpy)
    shapes = lamp_addon.design.parts.shapes
    real, made = shapes.get, []

    def get_then_fail(key, make):
        made.append(key)
        if len(made) == 3:
            raise MemoryError("meshing the third shape")
        return real(key, make)

    monkeypatch.setattr(shapes, "get", get_then_fail)
    with pytest.raises(MemoryError):
        apply.apply_preset_whole(bl_scene, core.load_preset(str(PRESETS / "paper-cut-height.json")))
    assert len(made) == 3
    assert _state(lamp_addon, bl_scene) == before
    assert _meshes(bpy) == meshes

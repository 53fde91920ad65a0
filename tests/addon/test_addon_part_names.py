"""A function change renames the parts it named, unless the designer renamed a part
(``design.builder.follow_name``); numbering by function is stable."""

from __future__ import annotations

import pytest
from helpers import BASELINE

import core_tracer

pytestmark = pytest.mark.blender


def _names(bl_scene) -> dict[str, str]:
    """part -> object name, for the lamps' parts."""
    return {ob["lamp_part"]: ob.name for ob in bl_scene.objects
            if str(ob.get("lamp_part", "")).startswith("lamps[")}


def _build(bl_scene) -> dict[str, str]:
    import bpy

    assert bpy.ops.lamp.build() == {"FINISHED"}
    return _names(bl_scene)


@pytest.fixture
def design(lamp_addon, bl_scene):
    scene = core_tracer.load_scene(str(BASELINE))
    scene["image"] = {"width": 32, "height": 24}
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    bl_scene.lamp_design.auto_build = False
    return bl_scene.lamp_design


def test_a_function_change_renames_the_parts_it_named_and_keeps_the_designers_names(design, bl_scene):
    import bpy

    design.lamps[0].function = "stop"
    names = _build(bl_scene)
    assert names["lamps[0].lens"] == "Stop Lens" and names["lamps[0].bulb"] == "Stop Bulb"
    lens_mesh = next(ob for ob in bl_scene.objects if ob.get("lamp_part") == "lamps[0].lens").data
    assert lens_mesh.name == "Stop Lens"

    design.lamps[0].function = "turn"
    names = _build(bl_scene)
    assert {part: name for part, name in names.items()} == {
        part: name.replace("Stop", "Turn") for part, name in names.items()}
    assert names["lamps[0].lens"] == "Turn Lens" and lens_mesh.name == "Turn Lens"
    assert not any("Stop" in ob.name for ob in bpy.data.objects)

    bulb = next(ob for ob in bl_scene.objects if ob.get("lamp_part") == "lamps[0].bulb")
    bulb.name = "My Bulb"  # the designer's own name
    design.lamps[0].function = "tail"
    names = _build(bl_scene)
    assert names["lamps[0].bulb"] == "My Bulb" and names["lamps[0].lens"] == "Tail Lens"

    socket = next(ob for ob in bl_scene.objects if ob.get("lamp_part") == "lamps[0].socket")
    bpy.data.objects.remove(socket)  # deleted: comes back under the current name
    assert _build(bl_scene)["lamps[0].socket"] == "Tail Socket"


@pytest.mark.slow
def test_numbering_by_function_is_stable(design, bl_scene):
    import bpy

    design.lamps[0].function = "tail"
    assert bpy.ops.lamp.lamp_add() == {"FINISHED"}  # a copy: a second tail lamp
    names = _build(bl_scene)
    assert (names["lamps[0].lens"], names["lamps[1].lens"]) == ("Tail 1 Lens", "Tail 2 Lens")
    assert bpy.ops.lamp.lamp_add() == {"FINISHED"}
    design.lamps[2].function = "stop"
    names = _build(bl_scene)
    assert [names[f"lamps[{i}].lens"] for i in range(3)] == ["Tail 1 Lens", "Tail 2 Lens", "Stop Lens"]
    design.lamps[2].function = "turn"  # another lamp's change leaves the tail lamps' numbers alone
    names = _build(bl_scene)
    assert [names[f"lamps[{i}].lens"] for i in range(3)] == ["Tail 1 Lens", "Tail 2 Lens", "Turn Lens"]
    design.lamps[1].function = "stop"  # one tail lamp left: it is "Tail" again, the stop lamp "Stop"
    names = _build(bl_scene)
    assert [names[f"lamps[{i}].lens"] for i in range(3)] == ["Tail Lens", "Stop Lens", "Turn Lens"]

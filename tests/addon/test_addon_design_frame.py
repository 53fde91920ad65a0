"""A new design's image follows its body (``design.ops.follow_body_aspect``) and study cells frame the
lamp (``study.settings.study_from_settings``), so the lamp fills the frame instead of a band of it."""

from __future__ import annotations

import pytest
from helpers import FOUR_LAMPS

import core_tracer

pytestmark = pytest.mark.blender


def body_share(lamp_addon, scene: dict) -> tuple[float, float]:
    """(width, height) of the body's projected box as fractions of the image."""
    cm = lamp_addon.convert.camera
    size = (scene["image"]["width"], scene["image"]["height"])
    points = cm.project(scene["camera"], size, cm.box_corners(*cm.body_box(scene)))
    xs, ys = [p[0] for p in points], [p[1] for p in points]
    return (max(xs) - min(xs)) / size[0], (max(ys) - min(ys)) / size[1]


def test_image_size_for_a_body(lamp_addon):
    size = lamp_addon.convert.layout.image_size_for_body
    assert size((480.0, 120.0)) == (512, 192)  # (480 + 96) / (120 + 96) = 2.67
    assert size((220.0, 120.0)) == (512, 318)
    assert size((120.0, 220.0)) == (318, 512)
    assert size((100.0, 100.0)) == (512, 512)


def test_the_image_of_a_new_design_follows_its_body_as_lamps_are_added(lamp_addon, bl_scene):
    import bpy

    design = bl_scene.lamp_design
    for count in range(1, 5):
        assert bpy.ops.lamp.lamp_add() == {"FINISHED"}
        image = (design.image.width, design.image.height)
        assert image == lamp_addon.convert.layout.image_size_for_body(design.body.size), count
        seen = lamp_addon.design.camera.scene_for_render(bl_scene)
        assert (bl_scene.render.resolution_x, bl_scene.render.resolution_y) == image
        width, height = body_share(lamp_addon, seen)
        assert max(width, height) > 0.75 and min(width, height) > 0.4, (count, width, height)
    design.image.width, design.image.height = 640, 480  # the designer's own size: kept from now on
    assert bpy.ops.lamp.lamp_remove() == {"FINISHED"}
    assert (design.image.width, design.image.height) == (640, 480)


def test_a_presets_image_is_kept(lamp_addon, bl_scene):
    import bpy

    scene = core_tracer.load_scene(str(FOUR_LAMPS))
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    bl_scene.lamp_design.active_lamps_index = 0
    image = (scene["image"]["width"], scene["image"]["height"])
    assert bpy.ops.lamp.lamp_remove() == {"FINISHED"}
    assert (bl_scene.lamp_design.image.width, bl_scene.lamp_design.image.height) == image


def test_study_cells_frame_the_lamp(lamp_addon, bl_scene):
    import bpy

    scene = core_tracer.load_scene(str(FOUR_LAMPS))
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    lamp_addon.design.lamp_camera.ensure_lamp_camera(bl_scene)
    settings = bl_scene.lamp_study
    settings.width, settings.height = 128, 128
    settings.axis_1.parameter, settings.axis_1.mode, settings.axis_1.values = "lens.ior", "LIST", "1.45, 1.6"
    settings.use_axis_2 = False
    study = lamp_addon.study.settings.study_from_settings(bl_scene)
    for variant in study.variants:
        width, _height = body_share(lamp_addon, variant.scene)
        assert width > 0.8, width  # the 480 mm body across the cell, with a margin
    # A camera of the designer's own is their view: kept as it is.
    mine = bpy.data.objects.new("My Camera", bpy.data.cameras.new("My Camera"))
    bl_scene.collection.objects.link(mine)
    mine.location, mine.rotation_euler = (0.0, -3.0, 0.0), (1.5708, 0.0, 0.0)
    bl_scene.camera = mine
    seen = lamp_addon.design.camera.scene_for_render(bl_scene, size=(128, 128))
    study = lamp_addon.study.settings.study_from_settings(bl_scene)
    for key in ("position", "target"):
        assert study.variants[0].scene["camera"][key] == pytest.approx(seen["camera"][key])

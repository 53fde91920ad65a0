"""Images the add-on shows go through Blender's own colour management, at the design's exposure,
and look exactly like the PNGs core_tracer writes outside Blender."""

from __future__ import annotations

import json

import numpy as np
import OpenImageIO as oiio
import pytest
from helpers import BASELINE, FOUR_LAMPS

import core_tracer
from core_tracer.images import display

pytestmark = pytest.mark.blender


def _load(lamp_addon, bl_scene, path, size) -> dict:
    with open(path, encoding="utf-8") as f:
        doc = json.load(f)
    doc["image"] = {"width": size[0], "height": size[1]}
    scene = core_tracer.parse_scene(doc)
    lamp_addon.design_properties.scene_to_design(bl_scene, scene)
    lamp_addon.render_camera.ensure_scene_camera(bl_scene, scene)
    return lamp_addon.render_camera.scene_for_render(bl_scene)


@pytest.mark.parametrize("view", ["AgX", "Standard", "False Color"])
def test_lamp_tracer_image_in_blender_equals_the_cli_png(lamp_addon, bl_scene, tmp_path, view):
    import bpy

    scene = _load(lamp_addon, bl_scene, FOUR_LAMPS, (96, 64))
    assert bpy.ops.lamp.render_tracer() == {"FINISHED"}
    image = bpy.data.images["Lamp Tracer"]
    # What Blender shows: the image through the scene's view transform (use_view_as_render), written
    # by save_render as an 8-bit PNG, which applies the same colour management.
    bl_scene.view_settings.view_transform = view
    settings = bl_scene.render.image_settings
    settings.file_format, settings.color_mode, settings.color_depth = "PNG", "RGB", "8"
    path = tmp_path / "shown.png"
    image.save_render(str(path), scene=bl_scene)
    shown = np.asarray(oiio.ImageBuf(str(path)).get_pixels(oiio.UINT8))[..., :3].astype(int)
    # What core_tracer writes for the same design outside Blender.
    linear = core_tracer.render(scene)
    ours = display.view_transform(view).to_display8(linear, display.auto_exposure(linear)).astype(int)
    assert np.abs(shown - ours).max() <= 1


def test_design_exposure_from_a_preview_equals_the_full_renders(lamp_addon):
    for path in (BASELINE, FOUR_LAMPS):
        scene = core_tracer.load_scene(path)
        assert lamp_addon.image_view.design_exposure(scene) == display.auto_exposure(core_tracer.render(scene))


def test_thumbnails_use_the_default_view_of_the_running_blenders_config(lamp_addon):
    import os

    import bpy

    view = lamp_addon.image_view.thumbnail_view()
    own = bpy.utils.system_resource("DATAFILES", path="colormanagement")
    assert view.view == "AgX" and view.note == ""
    assert os.path.samefile(view.config, os.path.join(own, "config.ocio"))

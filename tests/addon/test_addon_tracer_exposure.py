"""Render with Lamp Tracer follows the one exposure policy (issue 24): the exposure belongs to the view.
Its image holds what F12 renders and is shown at the scene's exposure, as F12 is; rendering neither
changes the exposure nor exposes the image by itself, so a stop lamp rendered after a tail lamp shows
brighter, in the paper's model and in the photometric one. Exposure from Design is the explicit way."""

from __future__ import annotations

import numpy as np
import pytest

pytestmark = [pytest.mark.blender, pytest.mark.slow]


def _apply(bpy, file_name: str) -> None:
    wm = bpy.context.window_manager
    wm.lamp_presets_index = next(i for i, item in enumerate(wm.lamp_presets) if item.file.endswith(file_name))
    assert bpy.ops.lamp.preset_apply() == {"FINISHED"}


def _f12(bpy, bl_scene, path) -> np.ndarray:
    import OpenImageIO as oiio

    settings = bl_scene.render.image_settings
    settings.file_format, settings.color_depth = "OPEN_EXR", "32"
    assert bpy.ops.render.render() == {"FINISHED"}
    bpy.data.images["Render Result"].save_render(str(path), scene=bl_scene)
    buf = oiio.ImageBuf(str(path))
    return np.asarray(buf.get_pixels(oiio.FLOAT)).reshape(buf.spec().height, buf.spec().width, -1)[:, :, :3]


def _lamp_tracer(bpy, lamp_addon) -> np.ndarray:
    assert bpy.ops.lamp.render_tracer() == {"FINISHED"}
    image = bpy.data.images["Lamp Tracer"]
    assert image.use_view_as_render and image[lamp_addon.image_view.EXPOSURE_PROPERTY] == 0.0
    return lamp_addon.image_view.image_to_array(image)


@pytest.mark.parametrize(("tail", "stop"), [("square-tail-lamp.json", "sawtooth-stop-lamp.json"),
                                            ("photometric-tail-lamp.json", "photometric-stop-lamp.json")])
def test_a_stop_lamp_rendered_after_a_tail_lamp_shows_brighter(lamp_addon, addon, tmp_path, tail, stop):
    import bpy

    bpy.ops.wm.read_homefile(use_factory_startup=True)
    bpy.ops.lamp.preset_refresh()
    shown = {}
    for name in (tail, stop):
        _apply(bpy, name)
        bl_scene = bpy.context.scene
        bl_scene.render.resolution_x, bl_scene.render.resolution_y = 96, 96
        bl_scene.lamp_design.image.samples = 1
        if name == tail:  # the first lamp of the file set the exposure; the user takes it a stop up
            bl_scene.view_settings.exposure += 1.0
            exposure = bl_scene.view_settings.exposure
        image = _lamp_tracer(bpy, lamp_addon)
        # The view's exposure is kept, and the image holds F12's very pixels.
        assert bl_scene.view_settings.exposure == exposure
        f12 = _f12(bpy, bl_scene, tmp_path / f"{name}.exr")
        assert image.shape == f12.shape == (96, 96, 3)
        np.testing.assert_array_equal(image, f12)
        shown[name] = image
    # Under one exposure the stop lamp's lit lens is brighter than the tail lamp's (a bulb 2.5 times as
    # bright in the paper's presets; a stop filament in the photometric ones).
    brightest = {name: np.percentile(image.max(axis=2), 99) for name, image in shown.items()}
    assert brightest[stop] > 1.5 * brightest[tail], brightest


def test_exposure_from_design_is_what_exposes_it(lamp_addon, addon):
    import bpy

    bpy.ops.wm.read_homefile(use_factory_startup=True)
    bpy.ops.lamp.preset_refresh()
    _apply(bpy, "square-tail-lamp.json")
    bl_scene = bpy.context.scene
    bl_scene.render.resolution_x, bl_scene.render.resolution_y = 64, 64
    bl_scene.view_settings.exposure = 0.0  # the user's own choice
    before = _lamp_tracer(bpy, lamp_addon)
    assert bl_scene.view_settings.exposure == 0.0
    assert bpy.ops.lamp.exposure_from_design() == {"FINISHED"}
    assert bl_scene.view_settings.exposure < -2
    # The pixels are the render's either way; the view's exposure is what changed how they show.
    np.testing.assert_array_equal(_lamp_tracer(bpy, lamp_addon), before)

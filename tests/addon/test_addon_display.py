"""Images the add-on shows go through Blender's own colour management, at the design's exposure,
and look exactly like the PNGs core_tracer writes outside Blender."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import OpenImageIO as oiio
import pytest
from helpers import BASELINE, FOUR_LAMPS, ROOT

import core_tracer
from core_tracer.images import display, imageio

pytestmark = pytest.mark.blender


def _load(lamp_addon, bl_scene, path, size) -> dict:
    with open(path, encoding="utf-8") as f:
        doc = json.load(f)
    doc["image"] = {"width": size[0], "height": size[1]}
    scene = core_tracer.parse_scene(doc)
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    lamp_addon.design.lamp_camera.ensure_lamp_camera(bl_scene, frame=False)
    return lamp_addon.design.camera.scene_for_render(bl_scene)


@pytest.mark.slow
@pytest.mark.parametrize("view", ["AgX", "Standard", "False Color"])
def test_lamp_tracer_image_in_blender_equals_the_cli_png(lamp_addon, bl_scene, tmp_path, view):
    import bpy

    scene = _load(lamp_addon, bl_scene, FOUR_LAMPS, (96, 64))
    # The image is shown at the view's exposure, as F12 is: exposed for the design, the explicit way.
    assert bpy.ops.lamp.exposure_from_design() == {"FINISHED"}
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


@pytest.mark.slow
def test_design_exposure_from_a_preview_equals_the_full_renders(lamp_addon):
    for path in (BASELINE, FOUR_LAMPS):
        scene = core_tracer.load_scene(path)
        assert lamp_addon.image_view.design_exposure(scene) == display.auto_exposure(core_tracer.render(scene))


def test_thumbnails_use_the_default_view_of_the_running_blenders_config(lamp_addon):
    import bpy

    view = lamp_addon.image_view.thumbnail_view()
    own = bpy.utils.system_resource("DATAFILES", path="colormanagement")
    assert view.view == "AgX" and view.note == ""
    assert os.path.samefile(view.config, os.path.join(own, "config.ocio"))


@pytest.mark.slow
def test_compare_tool_png_shows_both_halves_through_one_transform(tmp_path):
    tool = str(ROOT / "tools" / "compare_preset.py")
    env = {k: v for k, v in os.environ.items() if k != "BLENDER_USER_RESOURCES"}
    args = [str(BASELINE), "--samples", "2", "--size", "40x32"]
    outputs = {}
    for name, extra in (("linear.exr", []), ("shown.png", ["--view", "Filmic"])):
        done = subprocess.run([sys.executable, tool, *args, "-o", str(tmp_path / name), *extra], capture_output=True,
                              text=True, env=env, cwd=tmp_path, timeout=300)
        assert done.returncode == 0, done.stderr
        outputs[name] = done.stdout
    assert "shown: Filmic at " in outputs["shown.png"] and "shown:" not in outputs["linear.exr"]
    linear, _ = imageio.read_image(tmp_path / "linear.exr")
    png = tmp_path / "shown.png"
    ev = float(imageio.read_attribute(png, imageio.EXPOSURE_ATTRIBUTE))
    assert imageio.read_attribute(png, imageio.VIEW_ATTRIBUTE) == "Filmic"
    strip = linear.shape[0] - 32
    tracer, cycles, difference = linear[strip:, :40], linear[strip:, 42:82], linear[strip:, 84:]
    # the third panel: the signed relative difference of luminance (red: tracer brighter, blue: Cycles), held
    # linear so that the Standard view shows its colours
    shown_difference = display.view_transform("Standard").to_display(difference)
    luminance = np.array([0.2126, 0.7152, 0.0722])
    bright = np.minimum(tracer @ luminance, cycles @ luminance) > 0.05 * (tracer @ luminance).max()
    relative = np.where(bright, (tracer @ luminance) / np.maximum(cycles @ luminance, 1e-12) - 1.0, 0.0)
    assert (bright & (np.abs(relative) > 0.05)).any()  # 40x32 px at 2 samples: edges differ
    for sign, (warm, cool) in ((1, (0, 2)), (-1, (2, 0))):
        clear = bright & (sign * relative > 0.05)
        if clear.any():
            assert np.mean(shown_difference[clear][:, warm] > shown_difference[clear][:, cool]) > 0.9
    assert not np.allclose(difference, np.abs(tracer - cycles), atol=1e-3)  # no longer |tracer - Cycles|
    assert ev == display.auto_exposure([tracer, cycles]) < -2  # measured over both halves together
    codes = np.asarray(oiio.ImageBuf(str(png)).get_pixels(oiio.UINT8))[..., :3].astype(int)
    view = display.view_transform("Filmic")
    for half, cols in ((tracer, slice(0, 40)), (cycles, slice(42, 82))):
        expected = view.to_display8(half, ev).astype(int)
        assert np.abs(codes[strip:, cols] - expected).max() <= 1


@pytest.mark.slow
def test_compare_tool_refuses_an_unknown_view_in_one_line(tmp_path):
    env = {k: v for k, v in os.environ.items() if k != "BLENDER_USER_RESOURCES"}
    done = subprocess.run([sys.executable, str(ROOT / "tools" / "compare_preset.py"), str(BASELINE), "-o",
                           str(tmp_path / "c.png"), "--view", "Bogus"], capture_output=True, text=True, env=env,
                          cwd=tmp_path, timeout=300)
    assert done.returncode == 2 and "Traceback" not in done.stderr + done.stdout
    assert done.stderr.strip().splitlines() == [done.stderr.strip()]
    assert done.stderr.startswith("compare_preset: --view: 'Bogus' is not a view") and "AgX" in done.stderr
    assert list(tmp_path.iterdir()) == []


def test_exposure_from_design_makes_f12_show_what_the_cli_shows(lamp_addon, bl_scene, tmp_path):
    import bpy

    scene = _load(lamp_addon, bl_scene, FOUR_LAMPS, (96, 64))
    assert bl_scene.view_settings.exposure == 0.0 and bl_scene.view_settings.view_transform == "AgX"
    assert bpy.ops.lamp.exposure_from_design() == {"FINISHED"}
    linear = core_tracer.render(scene)
    exposure = display.auto_exposure(linear)
    assert bl_scene.view_settings.exposure == pytest.approx(exposure, abs=1e-6) and exposure < -2
    # F12 with the Lamp Tracer engine, as Blender shows it (Render Result through the scene's settings).
    bl_scene.render.engine = "LAMP_TRACER"
    assert bpy.ops.render.render() == {"FINISHED"}
    settings = bl_scene.render.image_settings
    settings.file_format, settings.color_mode, settings.color_depth = "PNG", "RGB", "8"
    path = tmp_path / "f12.png"
    bpy.data.images["Render Result"].save_render(str(path), scene=bl_scene)
    shown = np.asarray(oiio.ImageBuf(str(path)).get_pixels(oiio.UINT8))[..., :3].astype(int)
    assert np.abs(shown - display.view_transform("AgX").to_display8(linear, exposure).astype(int)).max() <= 1
    # The add-on's own images are not exposed twice: with the scene at the design's exposure, they
    # hold the plain render.
    assert bpy.ops.lamp.render_tracer() == {"FINISHED"}
    image = bpy.data.images["Lamp Tracer"]
    assert image["lamp_exposure"] == pytest.approx(0.0, abs=1e-6)
    np.testing.assert_allclose(lamp_addon.image_view.image_to_array(image), linear, rtol=1e-6)


def test_exposure_from_design_needs_a_camera(lamp_addon, bl_scene):
    import bpy

    assert bl_scene.camera is None
    assert not bpy.ops.lamp.exposure_from_design.poll()

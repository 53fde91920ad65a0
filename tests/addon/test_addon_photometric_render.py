"""F12 (the Lamp Tracer engine) and the viewport's Rendered shading in the photometric mode: the
tracer's XYZ (cd/m²) goes to Blender as the working space's scene-linear RGB at the design's EV100,
out-of-gamut colours unclipped, for Blender's view transform to show."""

from __future__ import annotations

import colorsys
import math

import numpy as np
import pytest
from helpers import PRESETS, render_engine_exr
from test_addon_viewport import _blender_camera, _window_matrix

pytestmark = pytest.mark.blender

SIZE = 120


def _stop_lamp(lamp_addon, addon_core, bl_scene, size: int = SIZE) -> dict:
    scene = addon_core.scene.load_scene(PRESETS / "photometric-stop-lamp.json")
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    lamp_addon.design.lamp_camera.ensure_lamp_camera(bl_scene, frame=False)
    bl_scene.render.engine = "LAMP_TRACER"
    bl_scene.render.resolution_x = bl_scene.render.resolution_y = size
    bl_scene.lamp_design.image.samples = 1
    return scene


def _xyz(lamp_addon, addon_core, bl_scene) -> np.ndarray:
    """The tracer's own photometric image of what F12 renders (CIE XYZ, cd/m²)."""
    import bpy

    scene = lamp_addon.design.camera.scene_for_render(bl_scene, camera_object=bpy.context.scene.camera)
    assert scene["light_model"] == "photometric" and scene["camera"]["ev100"] == 15.0
    return addon_core.render(scene, SIZE, SIZE)


def test_f12_gives_blender_the_xyz_at_the_designs_ev100(lamp_addon, addon_core, bl_scene, tmp_path):
    _stop_lamp(lamp_addon, addon_core, bl_scene)
    pixels = render_engine_exr(bl_scene, tmp_path / "f12.exr")
    XYZ = _xyz(lamp_addon, addon_core, bl_scene)
    output = addon_core.photometry.output
    expected = output.xyz_to_linear_rec709(XYZ) / (1.2 * 2.0 ** 15.0)  # L / (1.2 · 2^EV100), Rec.709
    np.testing.assert_allclose(pixels[..., :3], expected, rtol=1e-5, atol=1e-7)
    lens = XYZ[..., 1] > 0.5 * XYZ[..., 1].max()
    assert lens.sum() > 50
    assert (pixels[..., 1][lens] < 0).mean() > 0.5  # legal red is outside Rec.709: left negative, not clipped


def test_the_stop_lamps_lens_reads_red_under_the_view_transform(lamp_addon, addon_core, bl_scene, tmp_path):
    """Saved through Blender's AgX (the default view), the lit lens is red: hue within 20 degrees of
    red, where amber and orange lie at 30 to 45 degrees."""
    import bpy
    from OpenImageIO import UINT8, ImageBuf

    _stop_lamp(lamp_addon, addon_core, bl_scene, size=200)
    bl_scene.lamp_design.image.samples = 1
    render_engine_exr(bl_scene, tmp_path / "f12.exr")
    settings = bl_scene.render.image_settings
    settings.file_format, settings.color_mode, settings.color_depth = "PNG", "RGB", "8"
    assert bl_scene.view_settings.view_transform == "AgX"
    bpy.data.images["Render Result"].save_render(str(tmp_path / "stop.png"), scene=bl_scene)
    shown = np.asarray(ImageBuf(str(tmp_path / "stop.png")).get_pixels(format=UINT8), np.float64)[..., :3] / 255
    lit = shown.sum(axis=2) > 0.6 * shown.sum(axis=2).max()
    r, g, b = shown[lit].mean(axis=0)
    hue = colorsys.rgb_to_hsv(r, g, b)[0] * 360.0
    assert hue < 20.0 or hue > 340.0, (hue, (r, g, b))
    assert r > 2.0 * g


def test_another_working_space_gets_its_own_rgb(lamp_addon, addon_core, bl_scene, tmp_path):
    import bpy

    display = lamp_addon.render.photometric_display
    _stop_lamp(lamp_addon, addon_core, bl_scene)
    bpy.ops.wm.set_working_color_space(working_space="Linear Rec.2020")
    pixels = render_engine_exr(bl_scene, tmp_path / "f12.exr")
    XYZ = _xyz(lamp_addon, addon_core, bl_scene)
    rec709 = addon_core.photometry.output.xyz_to_linear_rec709(XYZ) / (1.2 * 2.0 ** 15.0)
    # BT.2020's red primary (x 0.708, y 0.292) lies beyond R48's red, so the lens is inside its gamut
    to_2020 = display.from_rec709("Linear Rec.2020")
    np.testing.assert_allclose(to_2020 @ [1.0, 1.0, 1.0], [1.0, 1.0, 1.0], atol=1e-4)  # both D65
    np.testing.assert_allclose(pixels[..., :3], rec709 @ to_2020.T, rtol=1e-4, atol=1e-6)
    bpy.ops.wm.set_working_color_space(working_space="ACEScg")
    with pytest.raises(addon_core.SceneError, match="Working Space Linear Rec.709 or Linear Rec.2020"):
        display.from_rec709()


@pytest.mark.slow
def test_the_viewport_shows_the_xyz_at_the_designs_ev100(lamp_addon, addon_core, bl_scene):
    _stop_lamp(lamp_addon, addon_core, bl_scene)
    session = lamp_addon.render.viewport.ViewportSession(None, in_background=False)
    session.update(bl_scene)
    assert session.design["camera"]["exposure"] == "ev100" and session.design["camera"]["ev100"] == 15.0
    ob = _blender_camera("PERSP", location=(0.16, -0.78, 0.12), rotation=(1.43, 0.0, 0.2))
    session.sync(bl_scene, 64, 48, _window_matrix(ob, 64, 48), ob.matrix_world.inverted())
    while session.preview.step():
        pass
    frame = session.preview.frame()
    shown = session._shown(frame)
    expected = addon_core.photometry.output.xyz_to_linear_rec709(frame.image) / (1.2 * 2.0 ** 15.0)
    np.testing.assert_allclose(shown, expected, rtol=1e-5, atol=1e-7)
    # "auto": one EV100 per preview, measured on its first stage and kept while it refines
    bl_scene.lamp_design.camera.exposure = "auto"
    session.update(bl_scene)
    session.sync(bl_scene, 80, 60, _window_matrix(ob, 80, 60), ob.matrix_world.inverted())  # a new preview
    assert session.preview.step()
    first = session.preview.frame()
    assert first.divisor > 1  # the coarse stage
    session._shown(first)
    generation, ev100 = session._auto_ev100
    assert generation == first.generation and 5.0 < ev100 < 20.0 and ev100 != 15.0
    while session.preview.step():
        pass
    last = session.preview.frame()
    assert last.divisor == 1 and last.generation == generation
    shown = session._shown(last)
    assert session._auto_ev100 == (generation, ev100)
    expected = addon_core.photometry.output.xyz_to_linear_rec709(last.image) / (1.2 * 2.0 ** ev100)
    np.testing.assert_allclose(shown, expected, rtol=1e-5, atol=1e-7)


def _named_curve_design(lamp_addon, addon_core, bl_scene) -> None:
    _stop_lamp(lamp_addon, addon_core, bl_scene, size=48)
    bulb = bl_scene.lamp_design.lamps[0].bulb
    bulb.type, bulb.spectrum, bulb.spectrum_file, bulb.flux_lm = "custom", "file", "my-led.csv", 300.0


def _write_led_curve(folder) -> None:
    rows = "\n".join(f"{nm},{math.exp(-0.5 * ((nm - 625) / 12) ** 2):.6f}" for nm in range(560, 700))
    (folder / "my-led.csv").write_text("nm,value\n" + rows + "\n")


def test_a_measured_spectrum_is_read_beside_the_saved_blend_file(lamp_addon, addon_core, bl_scene, tmp_path):
    import bpy

    _named_curve_design(lamp_addon, addon_core, bl_scene)
    with pytest.raises(addon_core.SceneError, match="save the .blend file"):
        lamp_addon.design.camera.scene_for_render(bl_scene)
    bpy.ops.wm.save_as_mainfile(filepath=str(tmp_path / "lamp.blend"))
    bl_scene = bpy.context.scene
    with pytest.raises(addon_core.SceneError, match="beside the saved .blend file") as missing:
        lamp_addon.design.camera.scene_for_render(bl_scene)
    assert missing.value.path == "lamps[0].bulb.spectrum_file" and str(tmp_path) in missing.value.message
    _write_led_curve(tmp_path)
    scene = lamp_addon.design.camera.scene_for_render(bl_scene)
    assert scene["lamps"][0]["bulb"]["spectrum_file"] == str(tmp_path / "my-led.csv")
    pixels = render_engine_exr(bl_scene, tmp_path / "f12.exr")
    XYZ = addon_core.render(scene, 48, 48)
    np.testing.assert_allclose(pixels[..., :3], addon_core.photometry.output.xyz_to_linear_rec709(XYZ)
                               / (1.2 * 2.0 ** 15.0), rtol=1e-5, atol=1e-7)
    assert addon_core.photometry.cie.xy(XYZ.reshape(-1, 3).sum(axis=0))[0] > 0.65  # a deep red LED, as measured


def test_a_preset_finds_its_curves_beside_it(lamp_addon, addon_core, bl_scene, tmp_path):
    _named_curve_design(lamp_addon, addon_core, bl_scene)
    _write_led_curve(tmp_path)
    doc = lamp_addon.design.properties.design_document(bl_scene)
    (tmp_path / "led-lamp.json").write_text(addon_core.scene_to_json(addon_core.parse_scene(doc)))
    scene = addon_core.scene.load_scene(tmp_path / "led-lamp.json")
    lamp_addon.presets.apply.apply_preset(bl_scene, scene, str(tmp_path / "led-lamp.json"))
    rendered = lamp_addon.design.camera.scene_for_render(bl_scene)
    assert rendered["lamps"][0]["bulb"]["spectrum_file"] == str(tmp_path / "my-led.csv")


@pytest.mark.slow
def test_auto_exposure_is_measured_once_per_render(lamp_addon, addon_core, bl_scene, tmp_path):
    """With "auto", F12 shows the image at the EV100 measured on a small preview of the same view, one
    factor for every pixel (never re-exposed band by band)."""
    _stop_lamp(lamp_addon, addon_core, bl_scene)
    bl_scene.lamp_design.camera.exposure = "auto"
    pixels = render_engine_exr(bl_scene, tmp_path / "f12.exr")
    import bpy

    scene = lamp_addon.design.camera.scene_for_render(bl_scene, camera_object=bpy.context.scene.camera)
    ev100 = lamp_addon.render.photometric_display.auto_ev100(scene)
    assert 5.0 < ev100 < 20.0 and ev100 != 15.0
    expected = addon_core.photometry.output.xyz_to_linear_rec709(addon_core.render(scene, SIZE, SIZE))
    np.testing.assert_allclose(pixels[..., :3], expected / (1.2 * 2.0 ** ev100), rtol=1e-5, atol=1e-7)


def test_a_photometric_design_never_sets_the_scenes_exposure(lamp_addon, addon_core, bl_scene):
    """Its EV100 is in the pixels: Build and Apply Preset leave the view's exposure at 0 for the stop
    and the tail lamp alike (the paper's automatic exposure would darken the stop lamp to match)."""
    setup = lamp_addon.design.setup
    for name in ("photometric-stop-lamp", "photometric-tail-lamp"):
        scene = addon_core.scene.load_scene(PRESETS / f"{name}.json")
        lamp_addon.presets.apply.apply_preset(bl_scene, scene)
        lamp_addon.design.lamp_camera.ensure_lamp_camera(bl_scene, frame=False)
        bl_scene.view_settings.exposure = -3.0  # a paper-mode exposure left over: Exposure from Design resets it
        setup.set_design_exposure(bl_scene)  # what Exposure from Design does (Build and Apply never expose)
        assert bl_scene.view_settings.exposure == 0.0, name

"""A red photometric stop lamp shows red on every picture Blender shows or saves (issue 31 item 1): F12,
the "Lamp Tracer" image of the Image Editor, the viewport, Run Study and Save Sheet, the Light Panel
and Compare. Every one goes through ``core_tracer.images.display.shown``. Before it, Run Study in
Blender took the variants' XYZ in cd/m² for R, G, B and showed the lamp gold (G/R 0.8 on its lit lens)
while F12 showed it red.

Images Blender holds are scene-linear: they are shown here through the scene's own view transform
(``image_view.scene_view``, what the Image Editor applies). Metric: the medians of G/R and B/R over
the lit lens (``helpers.lit_lens_ratios``) below 0.5."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import STOP_LAMP, lit_lens_ratios, render_engine_exr

pytestmark = pytest.mark.blender

RED = 0.5
SIZE = 48


def _assert_red(shown: np.ndarray, where: str) -> None:
    g, b, pixels = lit_lens_ratios(shown)
    assert pixels > 20, where
    assert g < RED and b < RED, f"{where}: G/R {g:.2f}, B/R {b:.2f} on {pixels} lit pixels"


@pytest.fixture
def stop_lamp(lamp_addon, addon_core, bl_scene):
    scene = addon_core.scene.load_scene(STOP_LAMP)
    scene["image"].update(width=SIZE, height=SIZE, samples=1)
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    bl_scene.lamp_design.auto_build = False
    lamp_addon.design.lamp_camera.ensure_lamp_camera(bl_scene, frame=False)
    bl_scene.render.engine = "LAMP_TRACER"
    bl_scene.render.resolution_x = bl_scene.render.resolution_y = SIZE
    return bl_scene


def _as_shown(lamp_addon, bl_scene, image) -> np.ndarray:
    """An image Blender holds, as the Image Editor shows it: the scene's view transform."""
    return lamp_addon.image_view.scene_view(bl_scene).to_display(lamp_addon.image_view.image_to_array(image))


def test_f12_and_the_image_editors_render_show_red(lamp_addon, stop_lamp, tmp_path):
    import bpy
    from OpenImageIO import FLOAT, ImageBuf

    render_engine_exr(stop_lamp, tmp_path / "f12.exr")
    settings = stop_lamp.render.image_settings
    settings.file_format, settings.color_mode, settings.color_depth = "PNG", "RGB", "8"
    bpy.data.images["Render Result"].save_render(str(tmp_path / "f12.png"), scene=stop_lamp)
    _assert_red(np.asarray(ImageBuf(str(tmp_path / "f12.png")).get_pixels(FLOAT))[..., :3], "F12")
    image, _seconds = lamp_addon.render.ops.render_to_image(stop_lamp)
    _assert_red(_as_shown(lamp_addon, stop_lamp, image), "Lamp Tracer image")


@pytest.mark.slow
def test_the_viewport_shows_red(lamp_addon, stop_lamp):
    from test_addon_viewport import _blender_camera, _window_matrix

    session = lamp_addon.render.viewport.ViewportSession(None, in_background=False)
    session.update(stop_lamp)
    camera = stop_lamp.camera
    ob = _blender_camera("PERSP", location=tuple(camera.location), rotation=tuple(camera.rotation_euler))
    session.sync(stop_lamp, SIZE, SIZE, _window_matrix(ob, SIZE, SIZE), ob.matrix_world.inverted())
    while session.preview.step():
        pass
    linear = session._shown(session.preview.frame())
    _assert_red(lamp_addon.image_view.scene_view(stop_lamp).to_display(linear), "viewport")


@pytest.mark.slow
def test_run_study_and_save_sheet_show_red(lamp_addon, stop_lamp, tmp_path):
    """The fault of issue 31: the sheet run from Blender showed the red lamp gold."""
    import bpy
    from OpenImageIO import FLOAT, ImageBuf

    study = stop_lamp.lamp_study
    study.width, study.height, study.workers = SIZE, SIZE, 1
    study.axis_1.parameter, study.axis_1.mode, study.axis_1.values = "lens.ior", "LIST", "1.45, 1.6"
    study.use_axis_2 = False
    assert bpy.ops.lamp.study_run() == {"FINISHED"}
    # Fit to Lamp (the default): the cells take the body's aspect (220 x 120 mm) at Width x Height pixels
    cell = lamp_addon.study.settings.last_study().size
    assert cell == (58, 40) and abs(cell[0] * cell[1] - SIZE * SIZE) < 0.05 * SIZE * SIZE
    image = bpy.data.images["Lamp Study"]
    assert image["lamp_ev100"] == 15.0  # the design's camera, for every cell
    _assert_red(_as_shown(lamp_addon, stop_lamp, image), "Lamp Study image")
    assert bpy.ops.lamp.study_save_sheet(filepath=str(tmp_path / "sheet.png")) == {"FINISHED"}
    _assert_red(np.asarray(ImageBuf(str(tmp_path / "sheet.png")).get_pixels(FLOAT))[..., :3], "Save Sheet .png")


@pytest.mark.slow
def test_the_light_panel_shows_red(lamp_addon, stop_lamp):
    import bpy

    assert bpy.ops.lamp.light_states_render() == {"FINISHED"}
    image = bpy.data.images[lamp_addon.measures.light_panel.IMAGE_NAME]
    _assert_red(_as_shown(lamp_addon, stop_lamp, image), "Light Panel")


@pytest.mark.slow
def test_compare_shows_both_halves_red(lamp_addon, stop_lamp):
    import bpy

    stop_lamp.lamp_design.auto_build = True
    result = lamp_addon.compare.comparison.compare_design(stop_lamp, samples=16)
    assert result["exposure"] == 0.0  # both at the design's EV100
    view = lamp_addon.image_view.scene_view(stop_lamp)
    _assert_red(view.to_display(result["tracer"]), "Compare, tracer half")
    _assert_red(view.to_display(result["cycles"]), "Compare, Cycles half")
    image = bpy.data.images[lamp_addon.compare.comparison.COMPARE_IMAGE]
    shown = _as_shown(lamp_addon, stop_lamp, image)
    _assert_red(shown[:, : shown.shape[1] // 3], "Lamp Compare image, left panel")

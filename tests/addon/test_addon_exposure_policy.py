"""One exposure policy (``lamp_addon.design.setup``): the exposure belongs to the view, not the design.

A new file's first lamp sets the scene's exposure once (measured with the bulbs on, so a first design
whose bulbs are all off does not wash out the lit one applied next); Build Lamp and Apply Preset never
change it afterwards; *Exposure from Design* re-exposes on request and says when nothing is lit. A
study shows all its cells under one exposure, so a stop lamp is brighter than a tail lamp by the ratio
of their bulbs.
"""

from __future__ import annotations

import numpy as np
import pytest
from helpers import BASELINE
from test_addon_new_user import f12_codes, lens_reading, lit_lens_mask

import core_tracer
from core_tracer.scene import functions

pytestmark = pytest.mark.blender

SMALL = (96, 96)


@pytest.fixture
def startup(startup_scene):
    """The factory startup file with the preset browser filled."""
    import bpy

    bpy.ops.lamp.preset_refresh()
    return startup_scene


def apply_preset(file_name: str, capfd=None) -> str:
    """Apply a built-in preset through the browser, as the user does; the operator's report."""
    import bpy

    wm = bpy.context.window_manager
    wm.lamp_presets_index = next(i for i, item in enumerate(wm.lamp_presets) if item.file.endswith(file_name))
    if capfd is not None:
        capfd.readouterr()
    assert bpy.ops.lamp.preset_apply() == {"FINISHED"}
    return capfd.readouterr().out if capfd is not None else ""


@pytest.mark.slow
def test_lamp_off_then_tail_lamp_then_f12_keeps_the_exposure(lamp_addon, startup, tmp_path):
    """The issue's reproduction: "Paper study: lamp off", then "Round red tail lamp", then F12. The
    first lamp set the exposure for the lamp lit; the tail lamp keeps it and shows its cut pattern."""
    import bpy

    apply_preset("paper-lamp-off.json")
    first = startup.view_settings.exposure
    seen = lamp_addon.design.camera.scene_for_render(startup)
    assert not any(lamp["bulb"]["on"] for lamp in seen["lamps"])
    lit = lamp_addon.design.setup.lit_version(seen)
    assert first == pytest.approx(lamp_addon.image_view.design_exposure(lit), abs=1e-5) and first < -2.0

    apply_preset(BASELINE.name)
    assert startup.view_settings.exposure == first  # Apply Preset leaves the view's exposure alone
    startup.lamp_design.image.width, startup.lamp_design.image.height = SMALL  # a quick F12
    assert bpy.ops.lamp.build() == {"FINISHED"}
    assert startup.view_settings.exposure == first  # and so does Build
    codes = f12_codes(startup, tmp_path / "f12.png")
    assert startup.view_settings.exposure == first
    clipped, spread = lens_reading(codes, lit_lens_mask(lamp_addon.design.camera.scene_for_render(startup)))
    print(f"\nF12 of the tail lamp at {first:+.2f} EV: lit lens clipped {clipped:.1%}, spread {spread:.0f} codes")
    assert clipped < 0.01 and spread >= 30  # not the washed-out pink disk


@pytest.mark.slow
def test_build_and_apply_preset_keep_the_users_exposure(lamp_addon, startup):
    import bpy

    apply_preset(BASELINE.name)
    startup.view_settings.exposure = -2.5  # the user's own
    for preset in ("sawtooth-stop-lamp.json", "paper-bulb-brightness.json", "paper-lamp-off.json"):
        apply_preset(preset)
        startup.lamp_design.image.width, startup.lamp_design.image.height = 48, 48
        assert bpy.ops.lamp.build() == {"FINISHED"}
        assert startup.view_settings.exposure == -2.5, preset


@pytest.mark.slow
def test_a_brighter_bulb_keeps_the_exposure_so_it_looks_brighter(lamp_addon, startup):
    import bpy

    lamp_addon.design.properties.scene_to_design(startup, _small_baseline())
    assert bpy.ops.lamp.build() == {"FINISHED"}
    first = startup.view_settings.exposure
    assert first < -2.0  # the first build set it
    bulb = startup.lamp_design.lamps[0].bulb
    bulb.intensity = [4.0 * c for c in bulb.intensity]
    assert bpy.ops.lamp.build() == {"FINISHED"}
    assert startup.view_settings.exposure == first
    assert bpy.ops.lamp.exposure_from_design() == {"FINISHED"}  # asked for: two stops less
    assert startup.view_settings.exposure == pytest.approx(first - 2.0, abs=0.15)


@pytest.mark.slow
def test_exposure_from_design_says_when_nothing_is_lit(lamp_addon, startup, capfd):
    import bpy

    lamp_addon.design.properties.scene_to_design(startup, _small_baseline())
    assert bpy.ops.lamp.build() == {"FINISHED"}
    lit = startup.view_settings.exposure
    startup.lamp_design.lamps[0].bulb.on = False
    startup.view_settings.exposure = 0.0
    capfd.readouterr()
    assert bpy.ops.lamp.exposure_from_design() == {"FINISHED"}
    said = capfd.readouterr().out
    assert "Nothing is lit (every bulb is off)" in said and "cut pattern" not in said
    assert startup.view_settings.exposure == pytest.approx(lit, abs=1e-5)  # exposed for the bulbs on
    startup.lamp_design.lamps[0].bulb.on = True
    assert bpy.ops.lamp.exposure_from_design() == {"FINISHED"}
    assert "the lit lens shows its cut pattern" in capfd.readouterr().out


def _small_baseline(size=(64, 48)) -> dict:
    scene = core_tracer.load_scene(str(BASELINE))
    scene["image"] = {"width": size[0], "height": size[1]}
    return scene


@pytest.mark.slow
def test_a_stop_lamp_beside_a_tail_lamp_in_one_study_is_brighter_by_their_bulbs(lamp_addon, bl_scene):
    """A study of the lamp's function (tail, stop) by its bulb (on, off): the cells share one exposure,
    so the light the bulb adds to the lens (on minus off) of the stop lamp is that of the tail lamp
    times the ratio of their bulbs, channel by channel."""
    import bpy

    lamp_addon.design.properties.scene_to_design(bl_scene, _small_baseline())
    lamp_addon.design.lamp_camera.ensure_lamp_camera(bl_scene, frame=False)
    settings = bl_scene.lamp_study
    settings.width, settings.height, settings.workers = 48, 48, 1
    settings.axis_1.parameter, settings.axis_1.mode, settings.axis_1.values = "function", "LIST", "tail, stop"
    settings.use_axis_2 = True
    settings.axis_2.parameter, settings.axis_2.mode, settings.axis_2.values = "bulb.on", "LIST", "on, off"
    assert bpy.ops.lamp.study_run() == {"FINISHED"}
    study = lamp_addon.study.settings.last_study()
    from core_tracer.study import definition as st
    from core_tracer.study import sheet as study_sheet

    lay = study_sheet.layout(lamp_addon.study.settings.worded(st.Study.from_json(study.to_json())))
    pixels = lamp_addon.image_view.image_to_array(bpy.data.images["Lamp Study"])
    cells = [pixels[r.y:r.y + r.h, r.x:r.x + r.w] for r in lay.cells]  # row by row: (tail, stop) x (on, off)
    mask = lit_lens_mask(study.variants[0].scene)
    added_tail, added_stop = cells[0] - cells[2], cells[1] - cells[3]
    ratio = np.asarray(functions.DEFAULTS["stop"][1]) / np.asarray(functions.DEFAULTS["tail"][1])
    measured = added_stop[mask].sum(axis=0) / added_tail[mask].sum(axis=0)
    print(f"\nstop / tail, light the bulb adds over the lit lens: {np.round(measured, 4)} (bulbs {ratio})")
    np.testing.assert_allclose(measured, ratio, rtol=1e-3)


@pytest.mark.slow
def test_each_light_model_keeps_its_own_exposure(lamp_addon, startup, tmp_path, capfd):
    """Issue 31: the exposure kept from a paper design (about -4 EV) made the first photometric F12
    nearly black (its EV100 already puts display white at 1). Each light model keeps its own: the
    switch sets the new model's (0 EV the first time for a photometric design) and keeps the old one's."""
    import bpy

    apply_preset(BASELINE.name)
    paper = startup.view_settings.exposure
    assert paper < -2.0  # the first lamp of the file exposed it
    said = apply_preset("photometric-stop-lamp.json", capfd)
    assert startup.view_settings.exposure == 0.0
    assert "+0.0 EV for the photometric model" in said
    startup.lamp_design.image.width, startup.lamp_design.image.height = SMALL
    assert bpy.ops.lamp.build() == {"FINISHED"}
    codes = f12_codes(startup, tmp_path / "f12.png")
    bright = np.percentile(codes[..., 0], 99)
    print(f"\nfirst photometric F12 after a paper design: red p99 {bright:.0f} codes")
    assert bright > 150  # the lit stop lamp, not a nearly black image

    startup.view_settings.exposure = 0.5  # the user's own, for the photometric model
    startup.lamp_design.light_model = "paper"  # in the panel: the paper model's exposure comes back
    assert startup.view_settings.exposure == pytest.approx(paper)
    startup.lamp_design.light_model = "photometric"
    assert startup.view_settings.exposure == 0.5
    labels = _labels(bpy.types.LAMP_PT_light, startup)
    assert f"Exposure +0.5 EV for this model (paper: {paper:+.1f} EV)" in labels


def _labels(panel, scene) -> list[str]:
    from test_addon_panels import draw

    return draw(panel, scene).labels()

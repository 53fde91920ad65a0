"""The Light Panel (``lamp_addon.measures.light_panel``): the design's lighting states rendered once,
then switched and dimmed without rendering; the design untouched unless Apply to Design."""

from __future__ import annotations

import json

import numpy as np
import pytest
from helpers import PRESETS
from test_addon_panels import draw

pytestmark = pytest.mark.blender


@pytest.fixture
def night(lamp_addon, addon_core, bl_scene):
    scene = addon_core.scene.load_scene(PRESETS / "four-lamp-night-lit-photometric.json")
    scene["image"] = {"width": 96, "height": 64}
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    bl_scene.lamp_design.auto_build = False
    lamp_addon.design.lamp_camera.ensure_lamp_camera(bl_scene)
    bl_scene.render.engine = "LAMP_TRACER"
    return bl_scene


def _pixels(name: str) -> np.ndarray:
    import bpy

    image = bpy.data.images[name]
    return np.array(image.pixels[:], np.float32).reshape(image.size[1], image.size[0], 4)[..., :3]


def test_registration_is_symmetric_and_repeatable(lamp_addon, night):
    import bpy

    for _ in range(2):
        lamp_addon.measures.unregister()
        assert not hasattr(bpy.types.Scene, "lamp_light_panel") and not hasattr(bpy.types, "LAMP_PT_light_panel")
        assert lamp_addon.measures.light_panel._forget_on_load not in bpy.app.handlers.load_post
        lamp_addon.measures.register()
        assert hasattr(bpy.types.Scene, "lamp_light_panel") and hasattr(bpy.types, "LAMP_OT_light_states_render")


@pytest.mark.slow
def test_switching_a_lamp_re_weights_without_rendering_and_keeps_the_design(lamp_addon, night):
    import bpy

    light_panel = lamp_addon.measures.light_panel
    before = json.dumps(lamp_addon.design.properties.design_document(night), sort_keys=True)
    assert bpy.ops.lamp.light_states_render() == {"FINISHED"}
    items = {item.key: item for item in night.lamp_light_panel.states}
    assert list(items) == ["surroundings", "tail", "tail.stop_filament", "stop", "stop.tail_filament", "turn",
                           "turn.tail_filament", "reversing", "reversing.tail_filament"]  # by function (issue 31)
    assert items["turn"].label == "Turn (lamp 3, P21/5W)"
    assert items["tail"].on and not items["tail.stop_filament"].on  # the design's own: lamp 1 a tail lamp
    assert items["tail.stop_filament"].level == 440.0 and items["tail"].level == 35.0
    design_view = _pixels(light_panel.IMAGE_NAME).copy()

    # The design's own states show what the tracer's render shows (Render with Lamp Tracer: F12's pixels,
    # tests/addon/test_addon_tracer_exposure.py), the same scene, glare and exposure.
    image, _seconds = lamp_addon.render.ops.render_to_image(night)
    rendered = _pixels(image.name)
    assert np.abs(rendered - design_view).max() <= 1e-4 * max(1.0, float(rendered.max()))

    # Lamps 2-4 off: only the tail lamp and the surroundings; a change re-weights in milliseconds.
    for key in ("stop", "turn", "reversing"):
        items[key].on = False
    only_tail = _pixels(light_panel.IMAGE_NAME)
    assert only_tail.sum() < 0.5 * design_view.sum()
    assert light_panel.held(night)["ms"] < 50.0  # 96×64 here; benchmarks/bench_light_states.py at 512²
    # Its stop filament on too: brighter than the tail alone.
    items["tail.stop_filament"].on = True
    assert _pixels(light_panel.IMAGE_NAME).sum() > only_tail.sum()
    assert json.dumps(lamp_addon.design.properties.design_document(night), sort_keys=True) == before


@pytest.mark.slow
def test_a_design_change_makes_the_states_stale_and_apply_sets_the_bulbs(lamp_addon, night):
    import bpy

    light_panel = lamp_addon.measures.light_panel
    assert bpy.ops.lamp.light_states_render() == {"FINISHED"}
    items = {item.key: item for item in night.lamp_light_panel.states}
    items["tail"].on = False
    items["tail.stop_filament"].on = True
    items["reversing"].on = False
    assert bpy.ops.lamp.light_states_apply() == {"FINISHED"}
    bulbs = [lamp.bulb for lamp in night.lamp_design.lamps]
    assert (bulbs[0].on, bulbs[0].state) == (True, "stop") and not bulbs[3].on
    assert light_panel.stale(night)  # the design changed: render again
    layout = draw(bpy.types.LAMP_PT_light_panel, night)
    assert "The design changed since its light states: render them again" in layout.labels()
    assert not bpy.types.LAMP_OT_light_states_apply.poll(bpy.context)


@pytest.mark.slow
def test_apply_keeps_every_level_or_says_what_it_cannot_keep(lamp_addon, night, capfd):
    """Issue 31: Apply to Design dropped a level without a word. A named bulb's level (or both its
    filaments lit) becomes a Custom bulb of its spectrum and that flux, the same light; the
    surroundings' level cannot be kept, and the report's one line says so."""
    import bpy

    light_panel = lamp_addon.measures.light_panel
    assert bpy.ops.lamp.light_states_render() == {"FINISHED"}
    items = {item.key: item for item in night.lamp_light_panel.states}
    items["turn"].level = 300.0
    items["stop.tail_filament"].on = True  # the stop lamp's both filaments: 440 + 35 lm
    relit = _pixels(light_panel.IMAGE_NAME).copy()  # what the applied design must render
    items["surroundings"].level = 0.5
    dark = relit.max(axis=2) < 1e-3 * relit.max()  # mostly the surroundings (a night street)
    assert np.median(_pixels(light_panel.IMAGE_NAME)[dark] / relit[dark]) == pytest.approx(0.5, abs=1e-3)
    capfd.readouterr()
    assert bpy.ops.lamp.light_states_apply() == {"FINISHED"}
    said = capfd.readouterr().out.splitlines()
    assert said[-1] == ("Info: Applied the Light Panel's bulbs to the design; 2 made Custom to keep their level; "
                        "not kept: the surroundings x0.5")
    assert "Info: Turn (lamp 3, P21/5W): a Custom incandescent bulb of 300 lm (stop 300 lm; a P21/5W's flux is its " \
           "filament's)" in said
    assert any(line.startswith("Info: Stop (lamp 2, P21/5W): a Custom incandescent bulb of 475 lm") for line in said)
    bulbs = [lamp.bulb for lamp in night.lamp_design.lamps]
    assert (bulbs[2].type, bulbs[2].spectrum, bulbs[2].flux_lm) == ("custom", "incandescent", 300.0)
    assert (bulbs[1].type, bulbs[1].flux_lm) == ("custom", 475.0)
    assert (bulbs[0].type, bulbs[0].state) == ("P21/5W", "tail")  # at its own level: as it was
    # The design as applied renders as the panel showed it, but for the surroundings' level.
    image, _seconds = lamp_addon.render.ops.render_to_image(night)
    rendered = _pixels(image.name)
    assert np.abs(rendered - relit).max() <= 1e-4 * float(rendered.max())


@pytest.mark.slow
def test_the_held_passes_are_forgotten_when_a_file_is_opened(lamp_addon, night):
    import bpy

    assert bpy.ops.lamp.light_states_render() == {"FINISHED"}
    assert lamp_addon.measures.light_panel.held(night) is not None
    bpy.ops.wm.read_homefile(use_empty=True)  # a new file: another design, the same scene name
    assert lamp_addon.measures.light_panel.held(bpy.context.scene) is None


@pytest.mark.slow
def test_in_the_startup_file_the_light_panel_shows_what_f12_shows(lamp_addon, addon):
    """A new user's file (Cube, Camera, Light): apply the photometric stop lamp from the preset browser,
    render the light states; the design's own states give the tracer's render of the scene camera, the
    user's objects are untouched, and switching the lamp off leaves the surroundings only."""
    import bpy

    bpy.ops.wm.read_homefile(use_factory_startup=True)
    scene = bpy.context.scene
    bpy.ops.lamp.preset_refresh()
    wm = bpy.context.window_manager
    wm.lamp_presets_index = next(i for i, item in enumerate(wm.lamp_presets)
                                 if item.file.endswith("photometric-stop-lamp.json"))
    assert bpy.ops.lamp.preset_apply() == {"FINISHED"}
    scene.lamp_design.auto_build = False
    scene.lamp_design.image.width, scene.lamp_design.image.height = 64, 48
    users = {name: tuple(bpy.data.objects[name].location) for name in ("Cube", "Camera", "Light")}
    assert bpy.ops.lamp.light_states_render() == {"FINISHED"}
    light_panel = lamp_addon.measures.light_panel
    shown = _pixels(light_panel.IMAGE_NAME).copy()
    image, _seconds = lamp_addon.render.ops.render_to_image(scene)
    rendered = _pixels(image.name)
    assert np.abs(rendered - shown).max() <= 1e-4 * max(1.0, float(rendered.max()))
    assert {name: tuple(bpy.data.objects[name].location) for name in users} == users
    items = {item.key: item for item in scene.lamp_light_panel.states}
    assert list(items) == ["surroundings", "stop", "stop.tail_filament"]
    items["stop"].on = False
    assert _pixels(light_panel.IMAGE_NAME).max() < 0.1 * shown.max()

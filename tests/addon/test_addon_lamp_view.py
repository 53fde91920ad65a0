"""The lamp view (issue 31 item 7): lit red and amber lamps keep their hue on screen.

``display.LAMP_VIEW`` (Filmic) is chosen where the project chooses (sheets, the report, the scene the
first lamp of a new file sets up, when it still has Blender's default AgX: test_addon_first_build) and
offered in Blender by the *Lamp View* button; a view the user chose is never changed otherwise (Build,
Apply Preset and Exposure from Design leave it as it is). Metric: the hue and saturation of the lit lenses of the
four-lamp night preset, under AgX and under the lamp view, one stop above its camera's EV100."""

from __future__ import annotations

import colorsys

import numpy as np
import pytest
from helpers import PRESETS

from core_tracer import render
from core_tracer.images import display
from core_tracer.scene.validate import load_scene

pytestmark = pytest.mark.blender

NIGHT = PRESETS / "four-lamp-night-lit-photometric.json"


def _lens_colours(shown: np.ndarray, XYZ: np.ndarray) -> list[tuple[float, float]]:
    """(hue in degrees, red near 0 either side; saturation) of each lit lens's median colour, left to right
    (the lenses as the docs picture finds them: tools/make_lamp_view_image.py)."""
    from tools.make_lamp_view_image import lens_colours

    hsv = [colorsys.rgb_to_hsv(*rgb) for rgb in lens_colours(shown, XYZ)]
    return [((h * 360.0 + 180.0) % 360.0 - 180.0, s) for h, s, _v in hsv]


@pytest.mark.slow
def test_the_lamp_view_keeps_red_and_amber_where_agx_washes_them():
    scene = load_scene(NIGHT)
    XYZ = render(scene, 240, 150)
    linear = display.shown(XYZ, scene, view=None, stops=1.0).pixels[0]  # a designer brightening by a stop
    agx = _lens_colours(display.view_transform("AgX").to_display(linear), XYZ)
    lamp = _lens_colours(display.view_transform(display.LAMP_VIEW).to_display(linear), XYZ)
    (_, agx_tail), (_, agx_stop), (agx_amber_hue, agx_amber), _white = agx
    (_, tail), (stop_hue, stop), (amber_hue, amber), _white = lamp
    assert stop > 0.9 and tail > 0.9 and abs(stop_hue) < 5.0  # red stays red
    assert agx_tail < 0.8  # AgX: salmon
    assert amber > 0.9 and 30.0 <= amber_hue <= 45.0  # amber stays amber (ECE amber: hue about 30-45 in sRGB)
    assert agx_amber < amber and agx_amber_hue < amber_hue  # AgX: toward a paler orange (peach)


@pytest.mark.slow
def test_the_lamp_view_button_sets_the_view_on_request_only(lamp_addon, addon_core, bl_scene):
    import bpy

    settings = bl_scene.view_settings
    settings.view_transform, settings.look = "AgX", "AgX - Punchy"  # the user's own choice, before any lamp
    scene = addon_core.scene.load_scene(NIGHT)
    lamp_addon.presets.apply.apply_preset(bl_scene, scene)
    lamp_addon.design.lamp_camera.ensure_lamp_camera(bl_scene, frame=False)
    assert bpy.ops.lamp.build() == {"FINISHED"}
    bpy.ops.lamp.exposure_from_design()
    assert (settings.view_transform, settings.look) == ("AgX", "AgX - Punchy")  # kept: it is theirs
    assert bpy.ops.lamp.lamp_view() == {"FINISHED"}
    assert settings.view_transform == display.LAMP_VIEW and settings.look == "None"
    assert not bpy.types.LAMP_OT_lamp_view.poll(bpy.context)  # already there: says so
    assert "lamp.lamp_view" in [idname for idname, *_ in lamp_addon.actions.ACTION_OPERATORS]

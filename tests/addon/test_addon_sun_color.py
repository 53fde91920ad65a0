"""The Lamp Sun in Blender takes the tracer's sun colour, also when it follows the environment, so
Compare's Cycles half is lit by the same sun as the tracer's."""

from __future__ import annotations

import json

import numpy as np
import pytest
from helpers import BASELINE, write_exr

import core_tracer
from core_tracer.raytrace import sunlight

pytestmark = pytest.mark.blender


def _sun_light(bl_scene):
    return next(ob for ob in bl_scene.objects if ob.type == "LIGHT" and ob.data.type == "SUN").data


def _design(tmp_path, follow: bool) -> dict:
    sky = np.full((32, 64, 3), 0.5, np.float32)
    sky[6, 40], sky[6, 41] = (900.0, 500.0, 120.0), (950.0, 520.0, 100.0)  # a low orange sun
    doc = json.loads(BASELINE.read_text(encoding="utf-8"))
    doc["light"] = {"direction": [0.3, -1.0, 0.6], "color": [1, 1, 1], "ambient": 0.2, "strength": 2.5,
                    "sun_color": [0.2, 0.4, 1.0], "follow_environment": True, "follow_environment_color": follow}
    doc["environment"] = {"world": "file", "file": write_exr(tmp_path / "sun.exr", sky), "strength": 2.0,
                          "rotation_deg": 15.0}
    return core_tracer.parse_scene(doc)


@pytest.mark.slow
@pytest.mark.parametrize("follow", [True, False])
def test_the_lamp_sun_has_the_tracers_colour(lamp_addon, bl_scene, tmp_path, follow):
    scene = _design(tmp_path, follow)
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    # The switch goes through the panel's properties and back unchanged.
    assert lamp_addon.design.properties.design_to_scene(bl_scene)["light"]["follow_environment_color"] is follow
    lamp_addon.design.builder.build_lamp(bl_scene, scene)
    light = _sun_light(bl_scene)
    expected = sunlight.sun_color(scene)
    assert tuple(light.color) == pytest.approx(tuple(expected), rel=1e-6)
    if follow:
        assert expected[0] > expected[1] > expected[2]  # the image's orange sun, not the blue sun_color
        assert expected @ np.array([0.2126, 0.7152, 0.0722]) == pytest.approx(1.0)
    else:
        assert tuple(light.color) == pytest.approx((0.2, 0.4, 1.0))
    assert light.energy == pytest.approx(np.pi * 0.8 * 2.5, rel=1e-6)  # the strength stays the user's


@pytest.mark.slow
def test_the_body_under_the_followed_sun_agrees_with_cycles(lamp_addon, bl_scene, tmp_path):
    # The body's front face lit by the sun alone (no ambient, no specular; the environment so dim that
    # only its sun's colour counts): the tracer's (1 - d) s S cos theta C0 against Cycles' Diffuse BSDF
    # under the Lamp Sun of strength pi (1 - d) s and colour S.
    scene = _design(tmp_path, True)
    doc = {**scene, "light": {**scene["light"], "ambient": 0.0, "strength": 1.5, "follow_environment": False},
           "environment": {**scene["environment"], "strength": 1e-6}, "body": {**scene["body"], "specular": 0.0},
           "image": {"width": 64, "height": 64, "samples": 1}}
    scene = core_tracer.parse_scene(doc)
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    result = lamp_addon.compare.comparison.compare_design(bl_scene, samples=16, resolution=(64, 64))
    region = (slice(24, 40), slice(4, 14))  # left of the lens, clear of the body's edges
    t = result["tracer"][region].reshape(-1, 3).astype(np.float64).mean(axis=0)
    c = result["cycles"][region].reshape(-1, 3).astype(np.float64).mean(axis=0)
    cos_theta = 1.0 / np.linalg.norm([0.3, -1.0, 0.6])
    expected = 1.5 * cos_theta * sunlight.sun_color(scene) * np.array(scene["body"]["color"])
    print(f"\nbody under the followed sun: tracer {t}, Cycles {c}, closed form {expected}")
    np.testing.assert_allclose(t, expected, rtol=1e-3)
    np.testing.assert_allclose(c, t, rtol=0.02)  # the 2 % per channel

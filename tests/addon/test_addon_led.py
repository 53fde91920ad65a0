"""LED lamps in Blender (docs/photometric.md, "LED sources"): the LED panel follows the lamp's source,
the builder makes one emitting object of flat dies in place of bulb and socket (front lit, back black),
and a photometric design's dies carry their Cycles radiance Φ_e / (π A)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from helpers import PRESETS, build_parts

import core_tracer

pytestmark = pytest.mark.blender

PRESET = PRESETS / "led-stop-lamp.json"



def test_an_led_lamp_is_built_with_its_dies_instead_of_bulb_and_socket(lamp_addon, bl_scene):
    scene = core_tracer.normalize(json.loads(PRESET.read_text()))
    parts = build_parts(lamp_addon, bl_scene, scene)
    assert "lamps[0].led" in parts and "lamps[0].bulb" not in parts and "lamps[0].socket" not in parts
    obj = parts["lamps[0].led"]
    mesh = obj.data
    assert len(mesh.polygons) == 9
    led = scene["lamps"][0]["led"]
    for poly in mesh.polygons:  # every die faces the lens (-y), 1 mm²
        assert tuple(poly.normal) == pytest.approx((0.0, -1.0, 0.0), abs=1e-6)
    area_mm2 = np.array([p.area for p in mesh.polygons]) * 1e6 * obj.matrix_world.to_scale()[0] ** 2
    np.testing.assert_allclose(area_mm2, led["die_size"][0] * led["die_size"][1], rtol=1e-4)
    centres = np.array([tuple(p.center) for p in mesh.polygons]) @ np.array(obj.matrix_world)[:3, :3].T
    centres = (centres + np.array(obj.matrix_world)[:3, 3]) * 1000.0
    assert sorted({round(float(x), 3) for x in centres[:, 0]}) == [-12.0, 0.0, 12.0]
    assert sorted({round(float(z), 3) for z in centres[:, 2]}) == [-12.0, 0.0, 12.0]
    np.testing.assert_allclose(centres[:, 1], led["position"][1], atol=1e-3)
    tree = obj.active_material.node_tree
    assert tree.nodes["Die Sides"].inputs["Fac"].links[0].from_socket.name == "Backfacing"


def test_a_photometric_die_carries_flux_over_pi_a_in_watts(lamp_addon, bl_scene):
    from core_tracer.photometry import cie
    from core_tracer.raytrace import spectral

    scene = core_tracer.normalize(json.loads(PRESET.read_text()))
    equivalent = lamp_addon.convert.photometric_cycles.equivalent(scene)
    led = scene["lamps"][0]["led"]
    spectrum = spectral.led_spectrum(led, "led")
    radiance_w = led["flux_lm"] / cie.luminous_efficacy(spectrum) / (math.pi * 1e-6)  # 1 mm², Lambertian
    color = lamp_addon.convert.photometric_cycles.light_color(spectrum)
    np.testing.assert_allclose(equivalent["lamps"][0]["bulb"]["intensity"], radiance_w * color, rtol=1e-9)


def test_switching_back_to_the_bulb_removes_the_dies(lamp_addon, bl_scene):
    scene = core_tracer.normalize(json.loads(PRESET.read_text()))
    build_parts(lamp_addon, bl_scene, scene)
    scene["lamps"][0]["source"] = "bulb"
    parts = build_parts(lamp_addon, bl_scene, core_tracer.normalize(scene))
    assert "lamps[0].led" not in parts and "lamps[0].bulb" in parts and "lamps[0].socket" in parts


def test_the_led_panel_shows_for_led_lamps_only(lamp_addon, bl_scene):
    scene = core_tracer.normalize(json.loads(PRESET.read_text()))
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    lamp = bl_scene.lamp_design.lamps[0]
    in_use = lamp_addon.design.panels.section_in_use
    assert in_use(lamp, "led") and not in_use(lamp, "bulb") and not in_use(lamp, "socket")
    lamp.source = "bulb"
    assert not in_use(lamp, "led") and in_use(lamp, "bulb")
    # the design reads back as the preset (the LED fields follow from the spec)
    lamp.source = "led"
    back = lamp_addon.design.properties.design_to_scene(bl_scene)
    assert back["lamps"][0]["led"] == scene["lamps"][0]["led"]

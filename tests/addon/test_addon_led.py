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
    names = {key: lamp.led.bl_rna.properties[key].name for key in ("far_field_file", "flux_lm", "die_size")}
    assert names == {"far_field_file": "Far-Field File (.ies, .ldt)", "flux_lm": "Flux per LED (lm)",
                     "die_size": "Die Size (mm)"}
    lamp.source = "bulb"
    assert not in_use(lamp, "led") and in_use(lamp, "bulb")
    # the design reads back as the preset (the LED fields follow from the spec)
    lamp.source = "led"
    back = lamp_addon.design.properties.design_to_scene(bl_scene)
    assert back["lamps"][0]["led"] == scene["lamps"][0]["led"]


@pytest.mark.slow
def test_a_white_die_through_a_clear_lens_agrees_with_cycles(lamp_addon, bl_scene):
    """Compare on an LED die of white_led (inside Rec.709: Cycles can carry its colour) filling the
    view's centre through a flat clear PMMA lens: Cycles' emission plane of Φ_e / (π A) against the
    tracer's Φ / (π A), luminance within 2 % and xy within 0.005 (as the bulb's in
    tests/addon/test_addon_photometric_compare.py)."""
    from helpers import BASELINE

    from core_tracer.photometry import cie

    doc = json.loads(BASELINE.read_text())
    doc["light_model"] = "photometric"
    doc["image"] = {"width": 32, "height": 32}
    doc["light"]["illuminance_lux"] = 0.0
    doc["camera"].update(fov_deg=2.0, exposure="ev100", ev100=17.0)
    lamp = doc["lamps"][0]
    lamp["cuts"]["height"] = 0.0
    lamp["lens"].update(diffuse_color=[0.0, 0.0, 0.0], specular=0.0, material="pmma", filter="clear")
    lamp["source"] = "led"
    lamp["led"] = {"position": [0.0, 10.0, 0.0], "die_size": [12.0, 12.0], "flux_lm": 100.0, "spectrum": "white_led"}
    scene = core_tracer.parse_scene(doc)
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    result = lamp_addon.compare.comparison.compare_design(bl_scene, samples=64)

    def xyz(half):
        rows = half[12:20, 12:20].reshape(-1, 3).astype(np.float64)
        return (rows @ cie.LINEAR_REC709_TO_XYZ.T * (1.2 * 2.0 ** 17.0)).mean(axis=0)

    tracer, cycles = xyz(result["tracer"]), xyz(result["cycles"])
    print(f"LED die: tracer {tracer[1]:.0f} cd/m2, Cycles {cycles[1] / tracer[1] - 1:+.2%}, "
          f"xy {float(np.hypot(*(cie.xy(cycles) - cie.xy(tracer)))):.4f} apart")
    expected = 100.0 / (math.pi * 144e-6) * 0.92  # Φ/(πA) through two PMMA faces (about 4 % each)
    assert tracer[1] == pytest.approx(expected, rel=0.01)
    assert cycles[1] / tracer[1] - 1.0 == pytest.approx(0.0, abs=0.02)
    assert float(np.hypot(*(cie.xy(cycles) - cie.xy(tracer)))) < 0.005

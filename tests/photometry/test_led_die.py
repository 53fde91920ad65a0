"""LED dies (docs/photometric.md, "LED sources") against closed forms, through the real tracer and
both intensity estimators: a bare Lambertian die of flux Φ and area A shows the luminance Φ / (π A)
on every pixel of it and sends I(θ) = (Φ / π) cos θ; a lamp without LEDs traces as before.

"Bare": a lens of index 1.0001 with a clear filter and no cuts (no Fresnel loss to speak of, no
absorption: tests/measures/conftest.py), a black reflector, no sun, no surroundings.
"""

from __future__ import annotations

import copy
import json
import math

import numpy as np
import pytest
from helpers import PRESETS

from core_tracer import render_passes
from core_tracer.raytrace import spectral
from core_tracer.raytrace.lamp_table import LampTable
from core_tracer.scene.reading import SceneError
from core_tracer.scene.validate import parse_scene

FLUX_LM = 30.0
DIE_MM = 3.0


def die_document(die_mm: float = DIE_MM, depth_mm: float = 1.0, **led) -> dict:
    """The photometric stop lamp reduced to one bare LED die facing the lens (−y), ``depth_mm`` behind a
    0.5 mm window of radius 25 mm: seen unhidden to 80° off its axis (1 mm × tan 80° = 5.7 mm)."""
    doc = json.loads((PRESETS / "photometric-stop-lamp.json").read_text())
    doc["camera"] = {"type": "orthographic", "position": [0, -500, 0], "target": [0, 0, 0], "up": [0, 0, 1],
                     "width": 0.9 * die_mm, "exposure": "ev100", "ev100": 15.0}
    doc["image"] = {"width": 9, "height": 9, "samples": 1}
    doc["light"] = {"direction": [0.3, -1.0, 0.6], "ambient": 0.0, "illuminance_lux": 0.0}
    doc["environment"] = {"world": "none"}
    doc["body"] = {**doc["body"], "size": [60.0, 60.0], "depth": 20.0}
    lamp = doc["lamps"][0]
    lamp["cuts"]["height"] = 0.0
    lamp["lens"] = {**lamp["lens"], "material": "custom", "ior": 1.0001, "abbe": 100.0, "filter": "clear",
                    "radius": 25.0, "thickness": 0.5, "specular": 0.0, "diffuse_color": [0.0, 0.0, 0.0]}
    lamp["source"] = "led"
    lamp["led"] = {"position": [0.0, depth_mm, 0.0], "die_size": [die_mm, die_mm], "flux_lm": FLUX_LM,
                   "spectrum": "red_led", **led}
    return doc


@pytest.fixture
def black_reflector(monkeypatch):
    monkeypatch.setattr(spectral, "finish_reflectance", lambda reflector, bands: np.zeros(bands.k))


def test_a_bare_die_shows_flux_over_pi_a_on_every_pixel():
    expected = FLUX_LM / (math.pi * (DIE_MM * 1e-3) ** 2)  # cd/m², a flat Lambertian emitter
    luminance = render_passes(parse_scene(die_document())).image[..., 1].astype(np.float64)
    np.testing.assert_allclose(luminance, expected, rtol=1e-5)
    doc = die_document()
    doc["lamps"][0]["bulb"]["on"] = False  # the lamp's switch turns its LEDs off
    assert render_passes(parse_scene(doc)).image[..., 1].max() == 0.0


def test_a_die_seen_from_behind_is_dark_and_opaque():
    doc = die_document(normal=[0.0, 1.0, 0.0])  # facing away from the lens
    image = render_passes(parse_scene(doc)).image
    assert image.max() == 0.0


def test_an_array_has_its_dies_where_the_pitch_puts_them():
    doc = die_document(die_mm=1.0, columns=3, rows=2, pitch=[2.0, 4.0])
    scene = parse_scene(doc)
    table = LampTable.from_scene(scene)
    from core_tracer.raytrace.parts import led_die

    # rays straight at the lens from the front, at the dies' centres and between them
    xs = np.array([-2.0, 0.0, 2.0, -1.0, 1.0, 0.0, 0.0, -2.0, 3.0])
    zs = np.array([2.0, -2.0, 2.0, 2.0, 2.0, 0.0, 2.6, -1.6, 2.0])
    o = np.stack([xs, np.full(9, -10.0), zs], axis=1)
    d = np.tile([0.0, 1.0, 0.0], (9, 1))
    t = led_die.hit_dies(o, d, table, np.zeros(9, int))
    hit = np.isfinite(t)
    assert hit.tolist() == [True, True, True, False, False, False, False, True, False]
    np.testing.assert_allclose(t[hit], 11.0)


def test_a_lamp_without_leds_has_no_die_part():
    from core_tracer.raytrace.parts import led_die, parts_for

    scene = parse_scene(json.loads((PRESETS / "photometric-stop-lamp.json").read_text()))
    assert led_die not in parts_for(LampTable.from_scene(scene))
    assert led_die in parts_for(LampTable.from_scene(parse_scene(die_document())))


def test_overlapping_dies_and_dies_in_the_lens_are_refused():
    with pytest.raises(SceneError, match=r"lamps\[0\]\.led\.pitch.*overlap"):
        parse_scene(die_document(die_mm=2.0, columns=2, pitch=[1.5, 5.0]))
    with pytest.raises(SceneError, match=r"lamps\[0\]\.led\.position"):
        parse_scene(die_document(depth_mm=0.4))


def test_old_documents_keep_the_bulb():
    doc = json.loads((PRESETS / "photometric-stop-lamp.json").read_text())
    assert "source" not in doc["lamps"][0]
    scene = parse_scene(copy.deepcopy(doc))
    assert scene["lamps"][0]["source"] == "bulb"
    assert not LampTable.from_scene(scene).any_leds

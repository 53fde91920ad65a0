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


# ---------------------------------------------------------------------------------------------
# Intensity of a bare Lambertian die by both estimators: I(θ) = (Φ / π) cos θ


THETAS = (0.0, 30.0, 60.0, 80.0)
AZIMUTH_DEG = 30.0  # off the die's axes, so that its edges cross the pixel rows (no aligned-edge error)


def _direction(theta_deg: float, azimuth_deg: float = AZIMUTH_DEG) -> np.ndarray:
    """The light's direction θ from the die's normal (−y), at an azimuth from +x toward +z."""
    t, c = math.radians(theta_deg), math.radians(azimuth_deg)
    return np.array([math.sin(t) * math.cos(c), -math.cos(t), math.sin(t) * math.sin(c)])


def _lambertian_cd(theta_deg: float) -> float:
    return FLUX_LM / math.pi * math.cos(math.radians(theta_deg))


@pytest.mark.slow
def test_a_bare_die_rendered_is_flux_over_pi_cos_theta(black_reflector):
    """The rendered views' estimator, pixels of 0.05 mm on a 3 mm die (60 across), 8 shifted lattices:
    within 1 % at θ = 0–80° (the die 0.3 mm behind a 0.1 mm window of radius 12 mm: unhidden to 88°)."""
    from core_tracer.measures import intensity
    from core_tracer.measures.directions import angles_of

    doc = die_document(depth_mm=0.3)
    doc["lamps"][0]["lens"].update(thickness=0.1, radius=12.0)
    doc["body"].update(size=[30.0, 30.0], depth=5.0)
    scene = parse_scene(doc)
    for theta in THETAS:
        h, v = angles_of(_direction(theta))
        got = intensity.rendered_intensity(scene, float(h), float(v), pixel_mm=0.05, replicates=8, seed=1)
        expected = _lambertian_cd(theta)
        assert got.cd == pytest.approx(expected, rel=0.01), (theta, got)
        assert got.stderr < 0.006 * expected, (theta, got)


def _cone_mean_cd(theta_deg: float, cone_deg: float, steps: int = 400) -> float:
    """The mean of (Φ / π) max(0, cos θ) over the cone of half angle ``cone_deg`` about the direction θ
    from the normal, by the midpoint rule in the cone's polar angle ρ (weight sin ρ) and azimuth ψ."""
    a = math.radians(cone_deg)
    rho = (np.arange(steps) + 0.5) * a / steps
    psi = (np.arange(2 * steps) + 0.5) * math.pi / steps
    t = math.radians(theta_deg)
    # cos of the angle to the normal of the direction at (ρ, ψ) about the axis at θ (spherical cosines)
    cos_n = math.cos(t) * np.cos(rho)[:, None] + math.sin(t) * np.sin(rho)[:, None] * np.cos(psi)[None, :]
    weight = np.sin(rho)[:, None] * np.ones_like(psi)[None, :]
    return float(FLUX_LM / math.pi * (np.maximum(cos_n, 0.0) * weight).sum() / weight.sum())


@pytest.mark.slow
def test_a_bare_die_light_traced_is_flux_over_pi_cos_theta(black_reflector):
    """Light traced from the die, counted over cones of 25° (the closed form's mean over the cone,
    the light beyond the die's plane being none): within 1 % at θ = 0–80°, and its flux out is Φ. The
    window's radius (200 mm) lets light out unhidden to 89.9° from the die 0.3 mm behind it."""
    from core_tracer.measures import light_tracing
    from core_tracer.measures.directions import angles_of

    doc = die_document(depth_mm=0.3)
    doc["lamps"][0]["lens"].update(thickness=0.1, radius=200.0)
    doc["lamps"][0]["reflector"]["focal_length"] = 1000.0  # a shallow bowl (10 mm) inside the body
    doc["body"].update(size=[420.0, 420.0], depth=60.0)
    scene = parse_scene(doc)
    angles = [tuple(float(x) for x in angles_of(_direction(theta))) for theta in THETAS]
    cone = 25.0
    got, flux = light_tracing.traced_beam(scene, angles, photons=3_000_000, cone_deg=cone, seed=5)
    for theta, value in zip(THETAS, got[0], strict=True):
        expected = _cone_mean_cd(theta, cone)
        assert value.stderr < 0.0035 * expected, (theta, value)
        assert value.cd == pytest.approx(expected, rel=0.01), (theta, value, expected)
    assert flux[0][0] == pytest.approx(FLUX_LM, rel=0.002)


def test_the_cone_mean_is_the_closed_form_where_the_cone_stays_in_front():
    """The test's cone integral against the exact mean of a linear function over a cap, (1 + cos α)/2."""
    assert _cone_mean_cd(40.0, 25.0) == pytest.approx(_lambertian_cd(40.0) * (1 + math.cos(math.radians(25))) / 2,
                                                      rel=1e-5)

"""Luminous intensity by its two estimators (core_tracer.measures): the rendered views' luminance
integrated over the projected area, and light traced forward from the bulbs; checked against closed
forms and against each other."""

from __future__ import annotations

import math

import pytest

from core_tracer.measures import intensity, light_tracing
from core_tracer.photometry.cie import luminance_weights
from core_tracer.raytrace import spectral
from core_tracer.scene import load_scene

STOP_FLUX_LM = 440.0  # the P21/5W stop filament of the lamps in conftest (UN R37, photometry.sources)
BARE_DIRECTIONS = [(0.0, 0.0), (20.0, 0.0), (0.0, 15.0), (-15.0, -10.0)]


@pytest.mark.slow
def test_bare_bulb_rendered_is_flux_over_four_pi(bare_bulb):
    """A Lambertian sphere of flux Φ is isotropic: I = Φ / (4π) = 35.01 cd in every direction where
    nothing hides it, within 1 %."""
    expected = STOP_FLUX_LM / (4.0 * math.pi)
    for h, v in BARE_DIRECTIONS:
        got = intensity.rendered_intensity(bare_bulb, h, v, pixel_mm=0.5, replicates=3)
        assert got.cd == pytest.approx(expected, rel=0.01), (h, v, got)
        assert got.stderr < 0.005 * expected


@pytest.mark.slow
def test_bare_bulb_light_traced_is_flux_over_four_pi(bare_bulb):
    """The same by light tracing, over cones of 25° (the bulb is isotropic and unhidden to 70° off
    axis, so the cone's size adds no bias), within 1 % and with a standard error below 0.4 %."""
    expected = STOP_FLUX_LM / (4.0 * math.pi)
    got = light_tracing.traced_intensities(bare_bulb, BARE_DIRECTIONS, photons=2_000_000, cone_deg=25.0, seed=3)[0]
    for (h, v), value in zip(BARE_DIRECTIONS, got, strict=True):
        assert value.stderr < 0.004 * expected, (h, v, value)
        assert value.cd == pytest.approx(expected, rel=0.01), (h, v, value)


def paraboloid_on_axis(scene: dict) -> float:
    """The on-axis intensity of a sphere bulb at the focus of a paraboloid mirror, in cd.

    Seen from far along the axis, the mirror at a point P reflects the viewing ray (parallel to
    the axis) toward the focus F, the bulb's centre: every unobstructed point of the mirror shows
    the bulb's luminance L times the mirror's reflectance ρ, whatever the bulb's size (a
    paraboloid's defining property). The on-axis intensity is the luminance integrated over the
    projected area (I = ∫ L dA⊥):

        I = ρ_v L · π (R² − h_b²) + L · π r_b²,

    the second term the bulb seen directly (a disc of radius r_b), the first the mirror's annulus
    from h_b to the rim radius R. Inside h_b the annulus shows no bulb:
    - behind the bulb's disc (h < r_b) the bulb hides the mirror;
    - the socket, a cylinder of radius r_s on the axis from the vertex to the bulb's centre plane,
      stands between P and the bulb where the ray from P toward F crosses radius r_s before
      reaching the bulb's sphere: at distance r_s / sin θ > r_b from F, θ the angle of FP from the
      axis toward the vertex, i.e. sin θ < r_s / r_b. On a paraboloid h = 2f tan(θ/2), so the
      socket hides the mirror inside h_s = 2f tan(asin(r_s / r_b) / 2) (12.6 mm here);
    h_b = max(r_b, h_s). ρ_v = Σ L_k ρ_k w_k / Σ L_k w_k, the finish's reflectance weighted by the
    bulb's luminance spectrum over the bands (the project's finishes are measured metals, ρ ≈ 0.91
    for aluminium; the closed form carries it rather than assuming 1). The lens here has n = 1.0001
    and no filter (no Fresnel loss, no absorption); the glow share is 0 (a pure mirror). All
    lengths in m, L in cd/m².
    """
    lamp = scene["lamps"][0]
    bands = spectral.bands_of(None)
    radiance = spectral.bulb_radiance(lamp["bulb"], bands)
    weights = luminance_weights(bands)
    luminance = float(radiance @ weights)
    rho_v = float((radiance * spectral.finish_reflectance(lamp["reflector"], bands)) @ weights) / luminance
    r_b, r_s = lamp["bulb"]["radius"] * 1e-3, lamp["socket"]["radius"] * 1e-3
    f, rim = lamp["reflector"]["focal_length"] * 1e-3, lamp["lens"]["radius"] * 1e-3
    h_socket = 2.0 * f * math.tan(math.asin(r_s / r_b) / 2.0)
    h_b = max(r_b, h_socket)
    return rho_v * luminance * math.pi * (rim**2 - h_b**2) + luminance * math.pi * r_b**2


def test_paraboloid_closed_form_assumptions(paraboloid_lamp):
    """The closed form's geometry is the lamp's: the bulb at the focus, rim radius = lens radius."""
    lamp = paraboloid_lamp["lamps"][0]
    assert lamp["bulb"]["offset"] == [0.0, 0.0, 0.0]
    assert lamp["reflector"]["gap"] == 0.0
    assert paraboloid_on_axis(paraboloid_lamp) == pytest.approx(967.2, abs=0.1)


@pytest.mark.slow
def test_paraboloid_on_axis_rendered(paraboloid_lamp):
    expected = paraboloid_on_axis(paraboloid_lamp)
    got = intensity.rendered_intensity(paraboloid_lamp, 0.0, 0.0, pixel_mm=0.5, replicates=4)
    assert got.cd == pytest.approx(expected, rel=0.003), got
    assert abs(got.cd - expected) < 3.0 * got.stderr + 0.001 * expected


@pytest.mark.slow
def test_paraboloid_on_axis_light_traced(paraboloid_lamp):
    """Over a 2° cone (I is flat there within 0.3 %: the renders at 1°–3° off axis)."""
    expected = paraboloid_on_axis(paraboloid_lamp)
    got = light_tracing.traced_intensity(paraboloid_lamp, 0.0, 0.0, photons=1_000_000, cone_deg=2.0, seed=5)
    assert got.stderr < 0.015 * expected
    assert abs(got.cd - expected) < 3.0 * got.stderr + 0.003 * expected, got


FOUR_LAMP_DIRECTIONS = [(0.0, 0.0), (10.0, 5.0), (-10.0, 5.0), (-20.0, 0.0), (20.0, -5.0), (5.0, -10.0),
                        (0.0, 10.0), (-45.0, 0.0), (30.0, 10.0), (-5.0, -5.0)]


@pytest.mark.slow
def test_estimators_agree_on_four_lamp_preset(repo_root):
    """The two estimators of the four-lamp photometric preset (night, lit: tail, stop, turn and
    reversing on) agree within 3 standard errors at 10 directions, as the mean over a 3° cone (the
    renders by the 7-point disc rule over it)."""
    scene = load_scene(repo_root / "presets" / "four-lamp-night-lit-photometric.json")
    traced = light_tracing.traced_intensities(scene, FOUR_LAMP_DIRECTIONS, photons=300_000, cone_deg=3.0, seed=11)[0]
    for (h, v), forward in zip(FOUR_LAMP_DIRECTIONS, traced, strict=True):
        rendered = intensity.rendered_cone_means(scene, h, v, 3.0, pixel_mm=1.0, replicates=2)[0]
        sigma = math.hypot(forward.stderr, rendered.stderr)
        assert abs(forward.cd - rendered.cd) < 3.0 * sigma, ((h, v), forward, rendered)

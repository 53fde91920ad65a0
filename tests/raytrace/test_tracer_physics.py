"""Values the physics and the paper fix: Fresnel, the slab series, absorption, Phong, background."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import flat_lens_on_axis, scene_with, slab_series

from core_tracer import render, render_passes
from core_tracer.raytrace import optics
from core_tracer.raytrace.camera import eye_rays, make_camera
from core_tracer.raytrace.engine.rays import CUTOFF

# -- Fresnel --------------------------------------------------------------------------------------

def fresnel_by_angles(theta_i: float, n1: float, n2: float) -> float:
    """The textbook angle form, independent of the implementation's cosine form."""
    s = n1 / n2 * math.sin(theta_i)
    if s >= 1.0:
        return 1.0
    theta_t = math.asin(s)
    if theta_i == 0.0:
        return ((n1 - n2) / (n1 + n2)) ** 2
    rs = -math.sin(theta_i - theta_t) / math.sin(theta_i + theta_t)
    rp = math.tan(theta_i - theta_t) / math.tan(theta_i + theta_t)
    return 0.5 * (rs * rs + rp * rp)


@pytest.mark.parametrize("n", [1.33, 1.49, 1.6, 2.4])
def test_fresnel_normal_incidence(n):
    r = optics.fresnel_reflectance(np.array([1.0]), 1.0, n)[0]
    assert r == pytest.approx(((n - 1) / (n + 1)) ** 2, rel=1e-12)
    r_inside = optics.fresnel_reflectance(np.array([1.0]), n, 1.0)[0]
    assert r_inside == pytest.approx(r, rel=1e-12)


@pytest.mark.parametrize("deg", [10, 30, 45, 60, 75, 85, 89])
@pytest.mark.parametrize("n1,n2", [(1.0, 1.49), (1.49, 1.0), (1.0, 1.6)])
def test_fresnel_oblique_matches_angle_form(deg, n1, n2):
    theta = math.radians(deg)
    r = optics.fresnel_reflectance(np.array([math.cos(theta)]), n1, n2)[0]
    assert r == pytest.approx(fresnel_by_angles(theta, n1, n2), rel=1e-9, abs=1e-12)


def test_fresnel_brewster_angle_has_no_p_reflection():
    n = 1.49
    theta_b = math.atan(n)
    theta_t = math.asin(math.sin(theta_b) / n)
    rs = math.sin(theta_b - theta_t) / math.sin(theta_b + theta_t)
    r = optics.fresnel_reflectance(np.array([math.cos(theta_b)]), 1.0, n)[0]
    assert r == pytest.approx(0.5 * rs * rs, rel=1e-9)


def test_total_internal_reflection_beyond_the_critical_angle():
    n = 1.49
    critical = math.asin(1.0 / n)
    below = optics.fresnel_reflectance(np.array([math.cos(critical - 1e-4)]), n, 1.0)[0]
    beyond = optics.fresnel_reflectance(np.array([math.cos(critical + 1e-4), math.cos(1.4)]), n, 1.0)
    assert below < 1.0
    assert np.all(beyond == 1.0)


@pytest.mark.seed(7)
def test_snell_law_and_reflection_directions(rng):
    d = optics.normalize(rng.normal(size=(500, 3)) + [0, 0, -2])
    n = np.tile([0.0, 0.0, 1.0], (500, 1))
    eta = 1 / 1.49
    t = optics.refract(d, n, eta)
    sin_i = np.linalg.norm(np.cross(d, n), axis=1)
    sin_t = np.linalg.norm(np.cross(t, n), axis=1)
    np.testing.assert_allclose(sin_t, eta * sin_i, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(t, axis=1), 1.0, rtol=1e-12)
    m = optics.reflect(d, n)
    np.testing.assert_allclose(m[:, :2], d[:, :2])
    np.testing.assert_allclose(m[:, 2], -d[:, 2])


# -- The slab: a bulb seen through a flat lens ------------------------------------------------------


@pytest.mark.parametrize("ior", [1.3, 1.49, 1.7])
def test_bulb_through_flat_clear_lens_equals_slab_series(ior):
    intensity = np.array([8.0, 7.0, 6.0])
    scene = flat_lens_on_axis(ior=ior, intensity=tuple(intensity))
    result = render_passes(scene)
    centre = result.image[4, 4]
    r = ((ior - 1) / (ior + 1)) ** 2
    expected = intensity * slab_series(r, np.ones(3), CUTOFF)
    np.testing.assert_allclose(centre, expected, rtol=1e-6)
    assert result.passes["bulb"][4, 4] == pytest.approx(centre, rel=1e-6)
    # the second bounce is traced exactly when its attenuation clears the 0.1 % cut-off
    first = intensity * (1 - r) ** 2
    if (1 - r) * r * r >= CUTOFF:
        assert np.all(expected > first * (1 + 1e-6))
    else:
        np.testing.assert_allclose(centre, first, rtol=1e-6)


def test_bulb_through_flat_absorbing_lens_follows_equation_2():
    a = np.array([0.02, 0.6, 1.1])
    t = 3.0
    scene = flat_lens_on_axis(ior=1.49, absorption=tuple(a), intensity=(5.0, 5.0, 5.0), thickness=t)
    centre = render(scene)[4, 4]
    r = ((1.49 - 1) / 2.49) ** 2
    np.testing.assert_allclose(centre, 5.0 * slab_series(r, np.exp(-a * t), CUTOFF), rtol=1e-6)


def test_channel_ratio_through_absorbing_lens_is_exp_minus_delta_a_t():
    # With n = 1 there is no reflection, so each channel is I exp(-A t) exactly.
    a = np.array([0.05, 0.8, 1.3])
    t = 2.5
    centre = render(flat_lens_on_axis(ior=1.0, absorption=tuple(a), intensity=(4.0, 4.0, 4.0), thickness=t))[4, 4]
    assert centre[1] / centre[0] == pytest.approx(math.exp(-(a[1] - a[0]) * t), rel=1e-6)
    assert centre[2] / centre[1] == pytest.approx(math.exp(-(a[2] - a[1]) * t), rel=1e-6)
    # at the paper's index the primary term dominates: the ratio is within the multiple-bounce share
    c2 = render(flat_lens_on_axis(ior=1.49, absorption=tuple(a), intensity=(4.0, 4.0, 4.0), thickness=t))[4, 4]
    assert c2[1] / c2[0] == pytest.approx(math.exp(-(a[1] - a[0]) * t), rel=2e-3)


# -- Body and background ------------------------------------------------------------------------------

def test_body_pixel_equals_equation_1():
    scene = scene_with(**{"image": {"width": 64, "height": 64},
                          "light": {"direction": [0.4, -1.0, 0.3], "color": [0.9, 0.8, 1.0], "ambient": 0.3},
                          "body.color": [0.5, 0.25, 0.125], "body.specular": 0.4, "body.shininess": 12.0})
    image = render(scene)
    cam = make_camera(scene["camera"], 64, 64)
    row, col = 18, 8  # on the body, left of the lens
    o, d = eye_rays(cam, np.array([row * 64 + col]))
    L = np.array([0.4, -1.0, 0.3]) / np.linalg.norm([0.4, -1.0, 0.3])
    N = np.array([0.0, -1.0, 0.0])
    V = -d[0]
    H = (L + V) / np.linalg.norm(L + V)
    cos_t, cos_b = max(0.0, N @ L), max(0.0, N @ H)
    expected = (0.3 + 0.7 * cos_t) * np.array([0.5, 0.25, 0.125]) + 0.4 * cos_b**12 * np.array([0.9, 0.8, 1.0])
    p = o[0] + d[0] * (-o[0, 1] / d[0, 1])
    assert abs(p[0]) > 45 and abs(p[0]) < 110 and abs(p[2]) < 60  # really on the body, off the lens
    np.testing.assert_allclose(image[row, col], expected, rtol=1e-6)


def test_background_pixels_are_exactly_zero():
    scene = scene_with(**{"image": {"width": 48, "height": 48}})
    image = render(scene)
    # the default 16-degree camera at 800 mm sees 225 mm square: above and below the 120 mm body is background
    assert np.all(image[0] == 0.0) and np.all(image[-1] == 0.0)
    assert np.count_nonzero(image[24]) > 0


def test_lamp_off_shows_no_bulb_and_no_scatter():
    on = render_passes(scene_with(**{"image": {"width": 40, "height": 40}}))
    off = render_passes(scene_with(**{"image": {"width": 40, "height": 40}, "lamps[0].bulb.on": False}))
    assert on.passes["bulb"].max() > 0 and on.passes["reflector_scatter"].max() > 0
    assert off.passes["bulb"].max() == 0 and off.passes["reflector_scatter"].max() == 0
    # the reflector's own colour still shows through the lens with the lamp off (paper §3.3.3)
    assert off.passes["reflector_constant"].max() > 0
    np.testing.assert_array_equal(off.passes["reflector_constant"], on.passes["reflector_constant"])


def test_passes_sum_to_the_image():
    result = render_passes(scene_with(**{"image": {"width": 64, "height": 48}}))
    total = sum(p.astype(np.float64) for p in result.passes.values())
    np.testing.assert_allclose(result.image, total, rtol=1e-5, atol=1e-6)
    for name in ("lens_surface", "bulb", "reflector_constant", "reflector_scatter", "body"):
        assert result.passes[name].max() > 0, name
    assert all(np.all(p >= 0) for p in result.passes.values())


def test_on_band_hands_out_each_band_of_the_image_and_its_passes(monkeypatch):
    from core_tracer.raytrace import engine

    monkeypatch.setattr(engine.sampling, "TILE_RAYS", 400)  # 10 rows a band at 40 px wide
    scene = scene_with(**{"image": {"width": 40, "height": 30}})
    bands = []

    def keep(a, b, rows, passes):
        bands.append((a, b, rows.copy(), {k: v.copy() for k, v in passes.items()}))

    result = render_passes(scene, on_band=keep)
    assert [(a, b) for a, b, *_ in bands] == [(0, 10), (10, 20), (20, 30)]
    np.testing.assert_array_equal(np.concatenate([rows for _, _, rows, _ in bands]), result.image)
    for name, full in result.passes.items():
        np.testing.assert_array_equal(np.concatenate([p[name] for *_, p in bands]), full)


@pytest.mark.parametrize("threads", [1, 2])
def test_should_stop_ends_the_render_after_the_band_it_follows(monkeypatch, threads):
    from core_tracer.raytrace import engine

    monkeypatch.setattr(engine.sampling, "TILE_RAYS", 400)  # 10 rows a band at 40 px wide: 3 bands
    scene = scene_with(**{"image": {"width": 40, "height": 30}})
    bands = []
    with pytest.raises(engine.RenderCancelled):
        render_passes(scene, threads=threads, on_band=lambda a, b, rows, passes: bands.append((a, b)),
                      should_stop=lambda: len(bands) >= 1)
    assert bands == [(0, 10)]


def test_threaded_render_shortens_the_switch_interval_and_restores_it_even_when_cancelled(monkeypatch):
    # Bands on several threads run with the interpreter's switch interval at engine.schedule.SWITCH_INTERVAL
    # (a band tracing its last few rays would otherwise hold the GIL for 5 ms at a time); the
    # caller's interval comes back afterwards, also when the render is cancelled.
    import sys

    from core_tracer.raytrace import engine

    monkeypatch.setattr(engine.sampling, "TILE_RAYS", 400)
    scene = scene_with(**{"image": {"width": 40, "height": 30}})
    before = sys.getswitchinterval()
    seen = []
    render_passes(scene, threads=2, on_rows=lambda a, b, rows: seen.append(sys.getswitchinterval()))
    assert seen == pytest.approx([engine.schedule.SWITCH_INTERVAL] * 3)  # (kept in microseconds)
    assert sys.getswitchinterval() == before
    with pytest.raises(engine.RenderCancelled):
        render_passes(scene, threads=2, should_stop=lambda: True)
    assert sys.getswitchinterval() == before
    render_passes(scene, threads=1, on_rows=lambda a, b, rows: seen.append(sys.getswitchinterval()))
    assert seen[3:] == [before] * 3

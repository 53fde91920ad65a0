"""Daylight: the CIE D series against colour-science, sun and sky scaled exactly, environment
images scaled by luminance and by illuminance against closed forms."""

from __future__ import annotations

import math

import numpy as np
import pytest

from core_tracer.photometry import cie, daylight
from core_tracer.photometry.bands import Bands

pytestmark = pytest.mark.filterwarnings("ignore:Correlated colour temperature")


@pytest.mark.parametrize("cct", [4000.0, 5003.0, 5500.0, 6504.0, 7500.0, 25000.0])
def test_daylight_series_is_colour_sciences(colour, cct):
    xy = colour.temperature.CCT_to_xy_CIE_D(cct)
    np.testing.assert_allclose(daylight.daylight_chromaticity(cct), xy, atol=1e-12)
    theirs = colour.sd_CIE_illuminant_D_series(xy)  # M1, M2 rounded to 3 decimals by default
    ours = daylight.daylight_spectrum(cct)
    np.testing.assert_allclose(ours.at(theirs.wavelengths), theirs.values, rtol=1e-9, atol=1e-9)


def test_d65_from_the_series_is_the_tabulated_d65(colour):
    # CIE D65 is the series at 6500 K × 1.4388/1.4380 (the revised second radiation constant)
    ours = daylight.daylight_spectrum(6500.0 * 1.4388 / 1.4380)
    d65 = colour.SDS_ILLUMINANTS["D65"]
    np.testing.assert_allclose(ours.at(d65.wavelengths), d65.values, atol=0.05)


@pytest.mark.parametrize("cct", [3999.0, 25001.0, float("nan")])
def test_daylight_refuses_out_of_range(cct):
    with pytest.raises(ValueError, match="4000 to 25000 K"):
        daylight.daylight_chromaticity(cct)


@pytest.mark.parametrize("k", [1, 4, 16, 81])
def test_sun_and_sky_are_exact_in_the_bands(k):
    b = Bands.uniform(k)
    e = daylight.sun_spectral_irradiance(daylight.CLEAR_DAY_SUN_LUX, b)
    assert e @ cie.luminance_weights(b) == pytest.approx(100_000.0, rel=1e-12)
    sky = daylight.sky_spectral_radiance(5000.0, b)
    assert sky @ cie.luminance_weights(b) == pytest.approx(5000.0, rel=1e-12)
    xy = cie.xy(daylight.sun_spectral_irradiance(1.0, Bands.uniform(81)) @ cie.xyz_matrix(Bands.uniform(81)))
    np.testing.assert_allclose(xy, daylight.daylight_chromaticity(daylight.SUN_CCT_K), atol=2e-3)


def test_sun_refuses_negative_illuminance():
    with pytest.raises(ValueError, match="sun illuminance"):
        daylight.sun_spectral_irradiance(-1.0, Bands.uniform(4))


def test_uniform_environment_scales():
    # A uniform image of value v: mean luminance v; illuminance on a horizontal plane π v.
    image = np.full((64, 128, 3), 0.5)
    assert daylight.environment_scale_for_luminance(image, 1000.0) == pytest.approx(2000.0, rel=1e-12)
    assert daylight.environment_scale_for_illuminance(image, 1000.0) == pytest.approx(1000.0 / (math.pi * 0.5),
                                                                                     rel=1e-12)


def test_environment_illuminance_counts_the_upper_half_with_cosine(rng):
    # Against a brute-force sum over directions: E = Σ L cos θ dω over the upper hemisphere.
    h, w = 32, 64
    image = rng.random((h, w, 3))
    y = image @ np.asarray(daylight.REC709_LUMINANCE)
    lat = np.linspace(math.pi / 2, -math.pi / 2, 20 * h + 1)
    mid = 0.5 * (lat[:-1] + lat[1:])
    rows = np.minimum((np.arange(mid.size) // 20), h - 1)
    d_omega = (2 * math.pi / w) * (np.sin(lat[:-1]) - np.sin(lat[1:]))
    e = sum(float(y[rows[i]].sum() * d_omega[i] * math.sin(mid[i])) for i in range(mid.size) if mid[i] > 0)
    assert daylight.environment_scale_for_illuminance(image, 1.0) == pytest.approx(1.0 / e, rel=1e-4)


def test_environment_refuses_dark_or_malformed_images():
    with pytest.raises(ValueError, match="no light"):
        daylight.environment_scale_for_luminance(np.zeros((4, 8, 3)), 100.0)
    lower_only = np.zeros((4, 8, 3))
    lower_only[2:] = 1.0
    with pytest.raises(ValueError, match="upper half"):
        daylight.environment_scale_for_illuminance(lower_only, 100.0)
    with pytest.raises(ValueError, match="height, width, 3"):
        daylight.environment_scale_for_luminance(np.ones((4, 8)), 100.0)


def test_night_street_lighting_is_a_few_lux():
    assert 1.0 <= daylight.STREET_LIGHTING_LUX <= 10.0

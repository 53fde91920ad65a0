"""Homogeneity of a lit lens (core_tracer.measures.homogeneity) on synthetic luminance images with
known statistics."""

from __future__ import annotations

import math

import numpy as np
import pytest

from core_tracer.measures import homogeneity as H


def test_eye_resolution_at_10_m_is_about_3_mm():
    assert H.eye_resolution_mm(10.0) == pytest.approx(10_000 * math.tan(math.radians(1 / 60)))
    assert H.eye_resolution_mm(10.0) == pytest.approx(2.909, abs=1e-3)


def test_known_statistics_unblurred():
    """A 20 × 20 lit square, its left half 1000 cd/m² and right half 3000 cd/m², on a dark 0 field
    outside: mean 2000, min 1000, max 3000, CV 0.5, the left half below 0.6 × the mean."""
    image = np.zeros((40, 40))
    mask = np.zeros((40, 40), bool)
    mask[10:30, 10:30] = True
    image[10:30, 10:20] = 1000.0
    image[10:30, 20:30] = 3000.0
    got = H.homogeneity(image, mask, 0.5, resolution_mm=0.0, dark_below=0.6)
    assert (got.l_min, got.l_max, got.l_mean) == (1000.0, 3000.0, 2000.0)
    assert got.uniformity_min_max == pytest.approx(1 / 3)
    assert got.uniformity_min_mean == pytest.approx(0.5)
    assert got.cv == pytest.approx(0.5)
    assert got.dark_fraction == pytest.approx(0.5)
    assert got.dark[10:30, 10:20].all() and not got.dark[10:30, 20:30].any() and not got.dark[~mask].any()
    assert np.isnan(got.blurred[~mask]).all()


def test_blur_inside_the_mask_keeps_an_even_lens_even():
    """A constant lit disc on a black field stays constant to its edge (normalised convolution)."""
    yy, xx = np.mgrid[0:120, 0:120]
    mask = (xx - 60) ** 2 + (yy - 60) ** 2 < 45**2
    got = H.homogeneity(np.where(mask, 5000.0, 0.0), mask, 1.0, distance_m=10.0)
    assert got.cv == pytest.approx(0.0, abs=1e-12)
    assert got.uniformity_min_max == pytest.approx(1.0)


def test_stripes_finer_than_the_eye_resolves_vanish_and_coarse_ones_stay():
    """Stripes of ±50 % in luminance: of 1 mm period seen from 10 m (2.9 mm resolution) they blur to
    a contrast exp(−2π²σ²/p²) ≈ 1e-10; of 40 mm period they keep exp(−2π² · 1.235² / 40²) = 98 %."""
    yy, xx = np.mgrid[0:400, 0:400] * 0.25  # mm, pixels of 0.25 mm
    mask = np.ones(xx.shape, bool)
    interior = np.zeros(xx.shape, bool)
    interior[60:340, 60:340] = True
    for period, kept in ((1.0, 0.0), (40.0, math.exp(-2 * math.pi**2 * (H.eye_resolution_mm(10) / 2.3548) ** 2
                                                         / 40.0**2))):
        image = 1000.0 * (1.0 + 0.5 * np.sin(2 * math.pi * xx / period))
        got = H.homogeneity(image, mask, 0.25, distance_m=10.0)
        contrast = (np.nanmax(got.blurred[interior]) - np.nanmin(got.blurred[interior])) / 2000.0 / 0.5
        assert contrast == pytest.approx(kept, abs=0.01), period


def test_bad_input_names_the_field():
    with pytest.raises(ValueError, match="mask selects no pixel"):
        H.homogeneity(np.ones((4, 4)), np.zeros((4, 4), bool), 1.0)
    with pytest.raises(ValueError, match="dark threshold"):
        H.homogeneity(np.ones((4, 4)), np.ones((4, 4), bool), 1.0, dark_below=1.5)
    with pytest.raises(ValueError, match="viewing distance"):
        H.eye_resolution_mm(0.0)

"""Band means: exact for the polyline through the samples, held at the ends; validation."""

from __future__ import annotations

import numpy as np
import pytest

from core_tracer.photometry.bands import Bands


def test_uniform_bands_edges_centres_widths():
    b = Bands.uniform(4, 380.0, 780.0)
    assert b.k == 4
    np.testing.assert_allclose(b.edges_nm, [380, 480, 580, 680, 780])
    np.testing.assert_allclose(b.centres_nm, [430, 530, 630, 730])
    np.testing.assert_allclose(b.widths_nm, 100.0)
    assert b == Bands.uniform(4) and hash(b) == hash(Bands.uniform(4)) and b != Bands.uniform(5)


@pytest.mark.parametrize("k", [1, 3, 7, 81])
def test_linear_curve_band_mean_is_its_value_at_the_centre(k, rng):
    # The mean of a straight line over an interval is its value at the interval's centre, exactly.
    slope, offset = rng.normal(), rng.normal()
    x = np.sort(rng.uniform(300.0, 850.0, 37))  # irregular samples on a line
    b = Bands.uniform(k)
    np.testing.assert_allclose(b.average(x, slope * x + offset), slope * b.centres_nm + offset, rtol=1e-12, atol=1e-9)


@pytest.mark.seed(3)
def test_polyline_mean_against_fine_quadrature(rng):
    x = np.sort(rng.uniform(390.0, 770.0, 25))
    y = rng.uniform(0.0, 2.0, 25)
    b = Bands(np.sort(rng.uniform(380.0, 780.0, 9)))
    expected = []
    for lo, hi in zip(b.edges_nm[:-1], b.edges_nm[1:], strict=True):
        fine = np.linspace(lo, hi, 200_001)
        expected.append(np.trapz(np.interp(fine, x, y), fine) / (hi - lo))  # np.interp holds the ends too
    np.testing.assert_allclose(b.average(x, y), expected, rtol=1e-6)


def test_columns_are_averaged_independently():
    x = np.array([380.0, 580.0, 780.0])
    y = np.array([[0.0, 1.0], [2.0, 1.0], [0.0, 1.0]])
    means = Bands.uniform(2).average(x, y)
    np.testing.assert_allclose(means, [[1.0, 1.0], [1.0, 1.0]])
    np.testing.assert_allclose(Bands.uniform(2).integrals(x, y), [[200.0, 200.0], [200.0, 200.0]])


def test_curve_is_held_beyond_its_samples():
    b = Bands.uniform(2, 380.0, 780.0)
    # 1 up to 500 nm, a line to 3 at 600 nm, 3 beyond: [380, 580] holds 120·1 + 80·(1 + 2.6)/2,
    # [580, 780] holds 20·(2.6 + 3)/2 + 180·3.
    np.testing.assert_allclose(b.average([500.0, 600.0], [1.0, 3.0]), [264.0 / 200, 596.0 / 200], rtol=1e-12)


@pytest.mark.parametrize("edges, words", [
    ([500.0], "2 to"), ([500.0, 400.0], "increasing"), ([380.0, np.nan], "finite"), (np.zeros((2, 2)), "2 to"),
])
def test_bad_edges_are_refused_in_one_line(edges, words):
    with pytest.raises(ValueError, match=words) as e:
        Bands(np.asarray(edges))
    assert "\n" not in str(e.value)


@pytest.mark.parametrize("k", [0, -1, 2.5, 10_000])
def test_bad_band_count_is_refused(k):
    with pytest.raises(ValueError, match="number of bands"):
        Bands.uniform(k)


def test_average_refuses_mismatched_or_unordered_samples():
    b = Bands.uniform(3)
    with pytest.raises(ValueError, match="do not match"):
        b.average([400.0, 500.0], [1.0])
    with pytest.raises(ValueError, match="increase"):
        b.average([500.0, 400.0], [1.0, 2.0])

"""The row-by-row vector helpers of ``optics`` give numpy's own results to the last bit: the images
may not change by a bit when the tracer's arithmetic is rearranged for speed."""

from __future__ import annotations

import numpy as np
import pytest

from core_tracer.raytrace import optics


def _bits(a: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(a).view(np.uint64)


def _awkward_rows(rng: np.random.Generator, n: int) -> np.ndarray:
    """Rows of three of every magnitude, with signed zeros, infinities and NaNs among them."""
    v = rng.standard_normal((n, 3)) * 10.0 ** rng.integers(-150, 150, (n, 3))
    v[rng.random((n, 3)) < 0.1] = -0.0
    v[rng.random((n, 3)) < 0.1] = 0.0
    v[rng.random((n, 3)) < 0.005] = np.inf
    return v


@pytest.mark.parametrize("layout", ["contiguous", "one_row_broadcast", "every_other_row", "fortran"])
@pytest.mark.seed(7)
def test_dot_is_einsum_bit_for_bit(layout, rng):
    a, b = _awkward_rows(rng, 200_000), _awkward_rows(rng, 200_000)
    b[::7] = -0.0  # rows whose products are all -0: einsum's sum is +0
    a[::7] = np.abs(a[::7])
    if layout == "one_row_broadcast":
        b = b[:1]
    elif layout == "every_other_row":
        a, b = a[::2], b[::2]
    elif layout == "fortran":
        a = np.asfortranarray(a)
    with np.errstate(invalid="ignore", over="ignore"):
        expected = np.einsum("ij,ij->i", a, b)
        got = optics.dot(a, b)
    same = (_bits(got) == _bits(expected)) | (np.isnan(got) & np.isnan(expected))
    assert same.all(), int((~same).sum())
    assert (np.signbit(got[::7]) == np.signbit(expected[::7])).all()


@pytest.mark.seed(8)
def test_dot_of_unit_rows_differs_from_the_plain_sum_where_einsum_does(rng):
    # The order matters: (a0 b0 + a1 b1) + a2 b2 differs from einsum's sum in the last bit for
    # about a third of random rows, so a helper summing in that order would change the images.
    a, b = rng.standard_normal((100_000, 3)), rng.standard_normal((100_000, 3))
    products = a * b
    plain = (products[:, 0] + products[:, 1]) + products[:, 2]
    assert (plain != np.einsum("ij,ij->i", a, b)).mean() > 0.1
    assert (_bits(optics.dot(a, b)) == _bits(np.einsum("ij,ij->i", a, b))).all()


@pytest.mark.seed(9)
def test_scaled_and_normalize_are_the_broadcast_products_bit_for_bit(rng):
    v, s = _awkward_rows(rng, 100_000), rng.standard_normal(100_000) * 10.0 ** rng.integers(-100, 100, 100_000)
    with np.errstate(invalid="ignore", over="ignore", under="ignore"):
        assert (_bits(optics.scaled(v, s)) == _bits(v * s[:, None])).all()
    u = rng.standard_normal((100_000, 3))
    expected = u / np.sqrt(np.einsum("ij,ij->i", u, u))[:, None]
    assert (_bits(optics.normalize(u)) == _bits(expected)).all()


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.sqrt(np.einsum("ij,ij->i", v, v))[:, None]


@pytest.mark.seed(10)
def test_surface_optics_are_their_plain_formulas_bit_for_bit(rng):
    # reflect, refract, fresnel_reflectance and blinn work in place a column at a time: the same
    # operations on every element as the textbook expressions, so the same bits.
    n_rays = 50_000
    d, n = _unit(rng.standard_normal((n_rays, 3))), _unit(rng.standard_normal((n_rays, 3)))
    n = np.where((np.einsum("ij,ij->i", d, n) > 0.0)[:, None], -n, n)  # facing the incident side
    eta = rng.uniform(0.6, 1.6, n_rays)
    cos_i = -np.einsum("ij,ij->i", d, n)
    with np.errstate(invalid="ignore"):
        assert (_bits(optics.reflect(d, n)) == _bits(_unit(d - n * (2.0 * np.einsum("ij,ij->i", d, n))[:, None]))).all()
        for e in (eta, 1.0 / 1.49):
            ee = np.broadcast_to(e, cos_i.shape)
            cos_t = np.sqrt(np.maximum(0.0, 1.0 - ee * ee * (1.0 - cos_i * cos_i)))
            expected = _unit(d * ee[:, None] + n * (ee * cos_i - cos_t)[:, None])
            assert (_bits(optics.refract(d, n, e)) == _bits(expected)).all()
            assert (_bits(optics.refract(d, n, e, cos_i)) == _bits(expected)).all()
        for n1, n2 in ((1.0, eta), (eta, 1.0), (1.49, 1.0)):
            c = np.clip(cos_i, 0.0, 1.0)
            ratio = n1 / n2
            sin2_t = ratio * ratio * (1.0 - c * c)
            cos_t = np.sqrt(np.maximum(0.0, 1.0 - sin2_t))
            rs = (n1 * c - n2 * cos_t) / (n1 * c + n2 * cos_t)
            rp = (n2 * c - n1 * cos_t) / (n2 * c + n1 * cos_t)
            expected = np.where(sin2_t >= 1.0, 1.0, 0.5 * (rs * rs + rp * rp))
            assert (_bits(optics.fresnel_reflectance(cos_i, n1, n2)) == _bits(expected)).all()
        view, light = _unit(rng.standard_normal((n_rays, 3))), _unit(rng.standard_normal((n_rays, 3)))
        weight, shininess = rng.uniform(0.0, 1.0, n_rays), rng.uniform(1.0, 50.0, n_rays)
        expected = weight * np.power(np.maximum(0.0, np.einsum("ij,ij->i", n, _unit(view + light))), shininess)
        assert (_bits(optics.blinn(n, view, light, weight, shininess)) == _bits(expected)).all()

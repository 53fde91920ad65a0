"""SSIM (Wang et al. 2004) against closed cases and a brute-force evaluation of its definition."""

from __future__ import annotations

import numpy as np
import pytest

from core_tracer.optimise import ssim


def brute_force(x: np.ndarray, y: np.ndarray, c1: float, c2: float) -> float:
    """Eq. 13 window by window with an explicit 2-D Gaussian (weighted statistics, eq. 14-16)."""
    g = ssim.gaussian_window()
    w = np.outer(g, g)
    n = len(g)
    out = []
    for i in range(x.shape[0] - n + 1):
        for j in range(x.shape[1] - n + 1):
            a, b = x[i:i + n, j:j + n], y[i:i + n, j:j + n]
            ma, mb = (w * a).sum(), (w * b).sum()
            va, vb = (w * (a - ma) ** 2).sum(), (w * (b - mb) ** 2).sum()
            cov = (w * (a - ma) * (b - mb)).sum()
            out.append((2 * ma * mb + c1) * (2 * cov + c2) / ((ma**2 + mb**2 + c1) * (va + vb + c2)))
    return float(np.mean(out))


def test_an_image_is_identical_to_itself():
    x = np.random.default_rng(1).random((24, 30))
    assert ssim.ssim(x, x) == pytest.approx(1.0, abs=1e-12)


def test_two_flat_images_give_the_luminance_term_alone():
    # No variance: the structure term is C2 / C2 = 1 and SSIM = (2 mu_x mu_y + C1) / (mu_x^2 + mu_y^2 + C1).
    a, b = 0.3, 0.6
    c1 = (ssim.K1 * 1.0) ** 2
    got = ssim.ssim(np.full((16, 16), a), np.full((16, 16), b))
    assert got == pytest.approx((2 * a * b + c1) / (a * a + b * b + c1), rel=1e-9)


def test_the_window_is_normalised_and_symmetric():
    g = ssim.gaussian_window()
    assert g.sum() == pytest.approx(1.0) and np.allclose(g, g[::-1]) and len(g) == 11
    assert g[5] / g[6] == pytest.approx(np.exp(0.5 / 1.5**2))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_separable_filter_equals_the_definition_window_by_window(seed):
    rng = np.random.default_rng(seed)
    x = rng.random((17, 19))
    y = np.clip(0.7 * x + 0.2 * rng.random((17, 19)), 0, 1)
    c1, c2 = (ssim.K1) ** 2, (ssim.K2) ** 2
    assert ssim.ssim(x, y) == pytest.approx(brute_force(x, y, c1, c2), rel=1e-10)
    assert ssim.ssim(x, y) == pytest.approx(ssim.ssim(y, x), rel=1e-12)  # symmetric
    assert -1.0 <= ssim.ssim(x, 1 - x) < ssim.ssim(x, y) < 1.0


def test_too_small_or_unequal_images_are_refused():
    with pytest.raises(ValueError, match="at least 11"):
        ssim.ssim(np.zeros((10, 20)), np.zeros((10, 20)))
    with pytest.raises(ValueError, match="one shape"):
        ssim.ssim(np.zeros((20, 20)), np.zeros((20, 21)))

"""The structural similarity index (SSIM) of two images, as Wang, Bovik, Sheikh and Simoncelli
define it ("Image quality assessment: from error visibility to structural similarity", IEEE
Transactions on Image Processing 13(4), 2004, eq. 13 and section III-C): local means, variances
and covariance under an 11 x 11 circular-symmetric Gaussian window of standard deviation 1.5
pixels, K1 = 0.01, K2 = 0.03, L the dynamic range; the index is the mean of the SSIM map over the
windows that fit inside the image ("valid" positions). The same constants and window are those of
Zhou Wang's reference implementation (ssim.m, "SSIM Index, Version 1.0", 2003) and of
``tf.image.ssim`` (TensorFlow 2.7 API documentation: filter_size 11, filter_sigma 1.5, k1 0.01,
k2 0.03).

Images are compared on their display luma (``display_luma``): what a designer sees, through the
view transform, not the linear values.
"""

from __future__ import annotations

import numpy as np

from ..photometry.daylight import REC709_LUMINANCE

WINDOW = 11
SIGMA = 1.5
K1, K2 = 0.01, 0.03
# Rec. ITU-R BT.709-6 luma coefficients (item 3.2), applied to the display-encoded values (Y').
LUMA = REC709_LUMINANCE


def gaussian_window(size: int = WINDOW, sigma: float = SIGMA) -> np.ndarray:
    """The normalised 1-D Gaussian; the 2-D window is its outer product (separable)."""
    x = np.arange(size, dtype=np.float64) - (size - 1) / 2.0
    g = np.exp(-0.5 * (x / sigma) ** 2)
    return g / g.sum()


def _filter_valid(image: np.ndarray, g: np.ndarray) -> np.ndarray:
    """``image`` (H, W) filtered by the separable window ``g``, at the valid positions only."""
    n = len(g)
    rows = np.lib.stride_tricks.sliding_window_view(image, n, axis=0) @ g  # (H-n+1, W)
    return np.lib.stride_tricks.sliding_window_view(rows, n, axis=1) @ g  # (H-n+1, W-n+1)


def ssim_map(x: np.ndarray, y: np.ndarray, data_range: float = 1.0, window: int = WINDOW,
             sigma: float = SIGMA) -> np.ndarray:
    """The SSIM of every valid window position of two single-channel images of one shape."""
    x = np.asarray(x, dtype=np.float64)
    y = np.asarray(y, dtype=np.float64)
    if x.shape != y.shape or x.ndim != 2:
        raise ValueError(f"SSIM compares two single-channel images of one shape, got {x.shape} and {y.shape}")
    if min(x.shape) < window:
        raise ValueError(f"SSIM needs images of at least {window} x {window} px, got {x.shape[1]} x {x.shape[0]}")
    g = gaussian_window(window, sigma)
    c1, c2 = (K1 * data_range) ** 2, (K2 * data_range) ** 2
    mx, my = _filter_valid(x, g), _filter_valid(y, g)
    sxx = _filter_valid(x * x, g) - mx * mx
    syy = _filter_valid(y * y, g) - my * my
    sxy = _filter_valid(x * y, g) - mx * my
    return ((2 * mx * my + c1) * (2 * sxy + c2)) / ((mx * mx + my * my + c1) * (sxx + syy + c2))


def ssim(x: np.ndarray, y: np.ndarray, data_range: float = 1.0) -> float:
    """The mean SSIM (eq. 17 of the paper) of two single-channel images."""
    return float(ssim_map(x, y, data_range).mean())


def display_luma(shown: np.ndarray) -> np.ndarray:
    """Y' of display-encoded RGB in [0, 1] (H, W, 3)."""
    return np.asarray(shown, dtype=np.float64) @ np.asarray(LUMA)

"""How even a lit lens looks: Lmin/Lmax, Lmin/Lmean, the coefficient of variation, and the map of
the areas darker than a chosen fraction of the mean (the dark bands designers argue about).

Measured on the luminance image as an eye at a stated distance resolves it: the image is blurred by a
Gaussian whose full width at half maximum is the smallest detail the eye separates there, an arc
minute of visual angle (normal visual acuity, 1′: Snellen's 6/6 letter detail; CIE 196:2011 uses the
same 1′ for the resolution of the fovea), so s = D · tan(1′): 2.9 mm at 10 m. The blur is normalised
inside the lit lens (the mask): dark surroundings do not darken its edge (Knutsson and Westin,
"Normalized and differential convolution", CVPR 1993).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

EYE_RESOLUTION_ARCMIN = 1.0
DEFAULT_DISTANCE_M = 10.0
FWHM_PER_SIGMA = 2.0 * math.sqrt(2.0 * math.log(2.0))  # 2.3548


def eye_resolution_mm(distance_m: float, arcmin: float = EYE_RESOLUTION_ARCMIN) -> float:
    """The smallest detail in mm an eye at ``distance_m`` resolves: D tan(1′) (2.9 mm at 10 m)."""
    if not (math.isfinite(distance_m) and distance_m > 0):
        raise ValueError(f"viewing distance: {distance_m!r} m is not above 0")
    return distance_m * 1e3 * math.tan(math.radians(arcmin / 60.0))


def gaussian_blur(image: np.ndarray, sigma_px: float) -> np.ndarray:
    """``image`` (H, W) convolved with a normalised Gaussian of ``sigma_px`` (separable, zero outside;
    ``sigma_px`` 0: unchanged)."""
    if sigma_px <= 0:
        return image.astype(np.float64)
    radius = max(1, int(math.ceil(4.0 * sigma_px)))
    x = np.arange(-radius, radius + 1, dtype=np.float64)
    kernel = np.exp(-0.5 * (x / sigma_px) ** 2)
    kernel /= kernel.sum()
    out = image.astype(np.float64)
    for axis in (0, 1):
        out = np.apply_along_axis(lambda line: np.convolve(line, kernel, mode="same"), axis, out)
    return out


@dataclass(frozen=True)
class Homogeneity:
    """Figures of a lit lens's evenness, on the luminance blurred to the eye's resolution."""

    l_min: float  # cd/m²
    l_max: float
    l_mean: float
    uniformity_min_max: float  # Lmin / Lmax
    uniformity_min_mean: float  # Lmin / Lmean
    cv: float  # standard deviation / mean
    dark_fraction: float  # share of the lit area below ``dark_below`` × the mean
    dark_below: float
    distance_m: float
    resolution_mm: float
    blurred: np.ndarray  # (H, W) the blurred luminance, NaN outside the mask
    dark: np.ndarray  # (H, W) bool, the dark areas

    def as_dict(self) -> dict:
        return {"l_min_cd_m2": self.l_min, "l_max_cd_m2": self.l_max, "l_mean_cd_m2": self.l_mean,
                "lmin_over_lmax": self.uniformity_min_max, "lmin_over_lmean": self.uniformity_min_mean,
                "cv": self.cv, "dark_fraction": self.dark_fraction, "dark_below_fraction_of_mean": self.dark_below,
                "viewing_distance_m": self.distance_m, "eye_resolution_mm": self.resolution_mm}


def homogeneity(luminance: np.ndarray, mask: np.ndarray, pixel_mm: float, *,
                distance_m: float = DEFAULT_DISTANCE_M, dark_below: float = 0.5,
                resolution_mm: float | None = None) -> Homogeneity:
    """The figures of the lit area ``mask`` (H, W bool) of a luminance image (H, W, cd/m²) whose
    pixels are ``pixel_mm`` wide, blurred to what an eye at ``distance_m`` resolves (or to
    ``resolution_mm``; 0: not blurred)."""
    luminance = np.asarray(luminance, dtype=np.float64)
    mask = np.asarray(mask, dtype=bool)
    if luminance.shape != mask.shape or luminance.ndim != 2:
        raise ValueError(f"luminance {luminance.shape} and mask {mask.shape} must be the same (H, W)")
    if not mask.any():
        raise ValueError("lit area: the mask selects no pixel; allowed a mask with at least one pixel")
    if not 0.0 < dark_below < 1.0:
        raise ValueError(f"dark threshold: {dark_below!r} is not between 0 and 1 (a fraction of the mean)")
    resolution = eye_resolution_mm(distance_m) if resolution_mm is None else float(resolution_mm)
    sigma_px = resolution / FWHM_PER_SIGMA / pixel_mm
    weight = gaussian_blur(mask.astype(np.float64), sigma_px)
    summed = gaussian_blur(np.where(mask, luminance, 0.0), sigma_px)
    blurred = np.full(luminance.shape, np.nan)
    blurred[mask] = summed[mask] / weight[mask]
    values = blurred[mask]
    mean = float(values.mean())
    l_min, l_max = float(values.min()), float(values.max())
    dark = np.zeros(mask.shape, bool)
    dark[mask] = values < dark_below * mean
    return Homogeneity(l_min, l_max, mean, l_min / l_max if l_max > 0 else 0.0, l_min / mean if mean > 0 else 0.0,
                       float(values.std() / mean) if mean > 0 else 0.0, float(dark[mask].mean()), dark_below,
                       distance_m, resolution, blurred, dark)

"""Surroundings in physical units: sun by illuminance in lux, sky and environment by luminance,
night with street lighting.

- The CIE daylight series (``daylight_spectrum``): S(λ) = S0 + M1 S1 + M2 S2 with the chromaticity
  of the D illuminant at a correlated colour temperature, CIE 015:2018 §3.1 (the same formulas as
  colour-science's ``CCT_to_xy_CIE_D`` and ``sd_CIE_illuminant_D_series``, against which it is tested;
  M1 and M2 rounded to three decimals as CIE 015:2018 recommends).
- The sun (``sun_spectral_irradiance``): band-mean spectral irradiance in W/(m² nm) on a plane
  facing the sun, scaled so that E_v = Km ∫ E_λ V dλ equals the stated illuminance in lux in the
  bands themselves (exact at every K). Its spectrum defaults to the D series at ``SUN_CCT_K`` =
  5500 K: a design value for direct sunlight (bluer sky light excluded), not a measurement.
  ``CLEAR_DAY_SUN_LUX`` = 100 000 lx is the issue's "clear daylight" figure.
- The sky (``sky_spectral_radiance``): uniform radiance at a stated luminance, D65 by default (CIE's
  representative average daylight).
- Environment images (``environment_scale_for_luminance``, ``environment_scale_for_illuminance``):
  the factor that takes an equirectangular linear Rec.709 image to cd/m² per pixel unit, so that its
  mean luminance, or the illuminance it gives on an upward horizontal plane, is the stated one.
  The image's rows run from the zenith (top) to the nadir, as Blender's Environment Texture maps it.
- Night (``STREET_LIGHTING_LUX`` = 3 lx): the lower bound of ASAM OSI's ambient illumination level 4
  ("minimum lighting on collector roads"; ASAM Open Simulation Interface, EnvironmentalConditions::
  AmbientIllumination, levels 3 = [1, 3) lx and 4 = [3, 10) lx, citing road lighting standards).
"""

from __future__ import annotations

import functools
import math

import numpy as np

from .bands import Bands
from .cie import luminance_weights
from .illuminants import daylight_basis, illuminant_d65
from .spectrum import Spectrum

SUN_CCT_K = 5500.0
CLEAR_DAY_SUN_LUX = 100_000.0
STREET_LIGHTING_LUX = 3.0
REC709_LUMINANCE = (0.2126, 0.7152, 0.0722)  # Y of linear Rec.709 R, G, B (ITU-R BT.709-6 item 3.2)


def daylight_chromaticity(cct_k: float) -> tuple[float, float]:
    """xy of the CIE D illuminant at correlated colour temperature ``cct_k`` (4000 to 25 000 K)."""
    t = float(cct_k)
    if not (np.isfinite(t) and 4000.0 <= t <= 25000.0):
        raise ValueError(f"daylight colour temperature: {cct_k!r} K is outside 4000 to 25000 K")
    if t <= 7000.0:
        x = -4.6070e9 / t ** 3 + 2.9678e6 / t ** 2 + 0.09911e3 / t + 0.244063
    else:
        x = -2.0064e9 / t ** 3 + 1.9018e6 / t ** 2 + 0.24748e3 / t + 0.237040
    y = -3.000 * x * x + 2.870 * x - 0.275
    return x, y


@functools.lru_cache(maxsize=32)
def daylight_spectrum(cct_k: float) -> Spectrum:
    """The CIE D-series spectrum at ``cct_k`` (relative, S0 = 100 at 560 nm), 300–830 nm at 5 nm."""
    x, y = daylight_chromaticity(cct_k)
    m = 0.0241 + 0.2562 * x - 0.7341 * y
    m1 = round((-1.3515 - 1.7703 * x + 5.9114 * y) / m, 3)
    m2 = round((0.0300 - 31.4424 * x + 30.0717 * y) / m, 3)
    wavelengths, s = daylight_basis()
    return Spectrum(wavelengths, s[:, 0] + m1 * s[:, 1] + m2 * s[:, 2], f"CIE daylight {cct_k:g} K")


def _scaled_to(value: float, spectrum: Spectrum, bands: Bands, what: str) -> np.ndarray:
    if not (np.isfinite(value) and value >= 0):
        raise ValueError(f"{what}: {value!r} is not 0 or more")
    means = spectrum.band_means(bands)
    per_unit = float(means @ luminance_weights(bands))
    if not per_unit > 0:
        raise ValueError(f"{spectrum.name}: no visible light in {bands!r}")
    return means * (value / per_unit)


def sun_spectral_irradiance(illuminance_lux: float, bands: Bands, spectrum: Spectrum | None = None) -> np.ndarray:
    """(K,) band-mean spectral irradiance in W/(m² nm) normal to the sun giving ``illuminance_lux``."""
    return _scaled_to(illuminance_lux, spectrum or daylight_spectrum(SUN_CCT_K), bands, "sun illuminance (lx)")


def sky_spectral_radiance(luminance_cd_m2: float, bands: Bands, spectrum: Spectrum | None = None) -> np.ndarray:
    """(K,) band-mean spectral radiance in W/(m² sr nm) of a uniform sky of ``luminance_cd_m2``.

    A uniform sky of luminance L gives E = π L on a horizontal plane."""
    return _scaled_to(luminance_cd_m2, spectrum or illuminant_d65(), bands, "sky luminance (cd/m²)")


def _rows_latitude(height: int) -> np.ndarray:
    """(height + 1,) latitudes of the row edges of an equirectangular image, top (π/2) to bottom."""
    return math.pi / 2 - np.arange(height + 1) * (math.pi / height)


def _pixel_luminance(rgb: np.ndarray) -> np.ndarray:
    a = np.asarray(rgb, dtype=np.float64)
    if a.ndim != 3 or a.shape[2] != 3 or a.shape[0] < 1 or a.shape[1] < 1:
        raise ValueError(f"environment image: expected (height, width, 3), got {a.shape}")
    return a @ np.asarray(REC709_LUMINANCE)


def environment_scale_for_luminance(rgb: np.ndarray, luminance_cd_m2: float) -> float:
    """cd/m² per pixel unit so that the image's mean luminance over the sphere (by solid angle) is
    ``luminance_cd_m2``."""
    y = _pixel_luminance(rgb)
    lat = _rows_latitude(y.shape[0])
    band = np.sin(lat[:-1]) - np.sin(lat[1:])  # solid angle of each row / (2π/width · width) = /2π
    mean = float((y.mean(axis=1) * band).sum() / 2.0)  # Σ row mean × 2π band / 4π
    if not mean > 0:
        raise ValueError("environment image: it has no light to scale")
    return float(luminance_cd_m2) / mean


def environment_scale_for_illuminance(rgb: np.ndarray, illuminance_lux: float) -> float:
    """cd/m² per pixel unit so that the image gives ``illuminance_lux`` on an upward horizontal plane:
    E = ∫ L cos θ dω over the upper hemisphere, exact per row: (π/W)(sin² φ_top − sin² φ_bottom)."""
    y = _pixel_luminance(rgb)
    lat = np.clip(_rows_latitude(y.shape[0]), 0.0, None)  # rows below the horizon weigh 0
    weight = math.pi * (np.sin(lat[:-1]) ** 2 - np.sin(lat[1:]) ** 2)  # per row, times the row mean
    e = float((y.mean(axis=1) * weight).sum())
    if not e > 0:
        raise ValueError("environment image: its upper half has no light to scale")
    return float(illuminance_lux) / e

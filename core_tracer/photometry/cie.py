"""CIE 1931 colorimetry on bands: XYZ and luminance from band-mean spectral radiance, xy, Rec.709.

Units. A band value is a band-mean spectral radiance in W/(m² sr nm). ``xyz_matrix(bands)`` folds
the maximum luminous efficacy ``KM`` and each band's integral of x̄ ȳ z̄ into a (K, 3) matrix, so
``XYZ = L @ M`` gives Y as luminance in cd/m² (= lm/(m² sr)), X and Z on the same scale
(CIE 015:2018 eq. 7.1 with k = Km).

Why 683.002 and not 683. The SI fixes the luminous efficacy of monochromatic radiation of
540 × 10¹² Hz at exactly 683 lm/W (SI Brochure, 9th ed. 2019, definition of the candela). That
frequency is 555.016 nm in standard air, where the tabulated V(λ) = ȳ(λ) is slightly below its peak
value 1 at 555 nm; so the maximum of K(λ) = Km·V(λ) is Km = 683 · V(555 nm) / V(555.016 nm)
= 683.002 lm/W (CIE ILV 17-730 "luminous efficacy", note 3; CIE S 017:2020 17-21-092 "maximum
luminous efficacy"). Photometry with the tabulated ȳ must use 683.002 for a 540 THz line to come out
at exactly 683 lm/W. The two differ by 3 ppm; colour-science uses 683 (``CONSTANT_K_M``), so the
tests compare with it after the ratio 683.002/683.
"""

from __future__ import annotations

import functools

import numpy as np

from .bands import VISIBLE_NM, Bands
from .spectrum import Spectrum, fine_grid
from .tables import table

KM = 683.002  # lm/W, maximum luminous efficacy for photopic vision (CIE ILV 17-730 note 3)
K_CD = 683.0  # lm/W at 540 THz, the SI definition of the candela (SI Brochure 9th ed., 2019)
CMF_TABLE = "cie1931_2deg.csv"

# ITU-R BT.709-6 (06/2015) items 1.3 and 1.4: primaries and the D65 reference white in CIE 1931 xy.
# Blender's scene-linear space ("Linear Rec.709") uses these primaries and white.
REC709_PRIMARIES_XY = ((0.640, 0.330), (0.300, 0.600), (0.150, 0.060))
D65_WHITE_XY = (0.3127, 0.3290)


def cmfs() -> tuple[np.ndarray, np.ndarray]:
    """(wavelengths nm (N,), x̄ ȳ z̄ (N, 3)) of the CIE 1931 2° observer, 360–830 nm at 1 nm."""
    return table(CMF_TABLE)


@functools.lru_cache(maxsize=64)
def _xyz_matrix(bands: Bands) -> np.ndarray:
    wavelengths, xyz_bar = cmfs()
    # Only the carried bands count: a CMF tail outside them is light the tracer does not carry.
    m = KM * bands.integrals(*_zero_beyond(wavelengths, xyz_bar))
    m.flags.writeable = False
    return m


def xyz_matrix(bands: Bands) -> np.ndarray:
    """(K, 3) so that ``XYZ = L @ M`` for band-mean spectral radiance L in W/(m² sr nm); Y in cd/m².

    M[k] = Km ∫_band_k (x̄, ȳ, z̄) dλ: exact when the radiance is constant across each band."""
    return _xyz_matrix(bands)


def luminance_weights(bands: Bands) -> np.ndarray:
    """(K,) so that ``L @ w`` is luminance in cd/m² (the Y column of ``xyz_matrix``)."""
    return _xyz_matrix(bands)[:, 1]


def _zero_beyond(wavelengths: np.ndarray, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The table with a zero sample 1 nm beyond each end: a CMF is zero outside 360–830 nm, not held."""
    x = np.concatenate([[wavelengths[0] - 1.0], wavelengths, [wavelengths[-1] + 1.0]])
    zero = np.zeros((1, values.shape[1]))
    return x, np.vstack([zero, values, zero])


def xy(XYZ: np.ndarray, black: tuple[float, float] = D65_WHITE_XY) -> np.ndarray:
    """CIE 1931 chromaticity (..., 2) of XYZ (..., 3); where X + Y + Z is not above 0, ``black``."""
    XYZ = np.asarray(XYZ, dtype=np.float64)
    total = XYZ.sum(axis=-1, keepdims=True)
    lit = total > 0
    safe = np.where(lit, total, 1.0)
    return np.where(lit, XYZ[..., :2] / safe, np.asarray(black, dtype=np.float64))


def _rgb_to_xyz(primaries_xy, white_xy) -> np.ndarray:
    """The RGB → XYZ matrix of an RGB space (SMPTE RP 177-1993 §3.3): white (1, 1, 1) has Y = 1."""
    def column(x, y):
        return np.array([x / y, 1.0, (1.0 - x - y) / y])
    p = np.stack([column(*c) for c in primaries_xy], axis=1)
    scale = np.linalg.solve(p, column(*white_xy))
    return p * scale[None, :]


LINEAR_REC709_TO_XYZ = _rgb_to_xyz(REC709_PRIMARIES_XY, D65_WHITE_XY)
XYZ_TO_LINEAR_REC709 = np.linalg.inv(LINEAR_REC709_TO_XYZ)
LINEAR_REC709_TO_XYZ.flags.writeable = False
XYZ_TO_LINEAR_REC709.flags.writeable = False


def xyz_to_linear_rec709(XYZ: np.ndarray) -> np.ndarray:
    """Linear Rec.709 RGB (..., 3) of XYZ (..., 3) with no chromatic adaptation and no clipping:
    colours outside the gamut keep their negative components for the view transform to handle."""
    return np.asarray(XYZ, dtype=np.float64) @ XYZ_TO_LINEAR_REC709.T


def spectrum_xyz(spectrum: Spectrum) -> np.ndarray:
    """XYZ of a spectral radiance curve in W/(m² sr nm) over 380–780 nm, at 1 nm (Y in cd/m²)."""
    x = fine_grid(spectrum.wavelengths_nm, np.array(VISIBLE_NM))
    x = x[(x >= VISIBLE_NM[0]) & (x <= VISIBLE_NM[1])]
    wavelengths, xyz_bar = cmfs()
    bars = np.stack([np.interp(x, wavelengths, xyz_bar[:, c], left=0.0, right=0.0) for c in range(3)], axis=1)
    return KM * np.trapz(spectrum.at(x)[:, None] * bars, x, axis=0)


def luminous_efficacy(spectrum: Spectrum, lo: float = VISIBLE_NM[0], hi: float = VISIBLE_NM[1]) -> float:
    """Luminous efficacy of radiation in lm/W: Km ∫ S V dλ / ∫ S dλ, both over ``lo``–``hi`` nm.

    The radiant power counted is that within the carried range (380–780 nm by default), the power
    the tracer carries; a tungsten lamp's infrared is not in it."""
    x = fine_grid(spectrum.wavelengths_nm, np.array([lo, hi]))
    x = x[(x >= lo) & (x <= hi)]
    wavelengths, xyz_bar = cmfs()
    v = np.interp(x, wavelengths, xyz_bar[:, 1], left=0.0, right=0.0)
    s = spectrum.at(x)
    radiant = np.trapz(s, x)
    if not radiant > 0:
        raise ValueError(f"{spectrum.name}: no power between {lo:g} and {hi:g} nm")
    return float(KM * np.trapz(s * v, x) / radiant)

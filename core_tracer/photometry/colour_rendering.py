"""The CIE 13.3-1995 general colour rendering index Ra of a white light, from its spectrum.

CIE 13.3-1995 ("Method of measuring and specifying colour rendering properties of light sources"):

1. The test source's CIE 1931 XYZ (2° observer, ``cie.cmfs``) and its CIE 1960 UCS chromaticity
   u = 4X / (X + 15Y + 3Z), v = 6Y / (X + 15Y + 3Z).
2. Its correlated colour temperature T: the Planckian radiator nearest to it in (u, v) (CIE 015:2018
   §9.5), found here by a search in mired over the Planckian locus computed with the same observer.
3. The reference illuminant at T: a Planckian radiator below 5000 K (Planck's law, c2 = 1.4388 × 10⁻²
   m·K, CIE 015:2018 §3.1 and ITS-90), the CIE D series at and above 5000 K
   (``daylight.daylight_spectrum``, 4000 to 25 000 K).
4. The eight test colour samples TCS01–TCS08 (``data/cie133_tcs.csv``) under each, Y scaled to 100 for
   the source's own white; the test source's colours adapted to the reference's white by the von Kries
   transform in the CIE 1960 diagram (CIE 13.3 §5.5): c = (4 − u − 10v) / v, d = (1.708v + 0.404 −
   1.481u) / v, and with C = c_r / c_t, D = d_r / d_t,
   u' = (10.872 + 0.404 C c_i − 4 D d_i) / (16.518 + 1.481 C c_i − D d_i),
   v' = 5.520 / (16.518 + 1.481 C c_i − D d_i).
5. CIE 1964 U*V*W*: W* = 25 Y^(1/3) − 17, U* = 13 W* (u − u_r), V* = 13 W* (v − v_r), each sample's
   colour difference ΔE between the two, its special index R_i = 100 − 4.6 ΔE, and Ra the mean of
   R_1 … R_8.

Everything is sampled at 5 nm over 360–830 nm (the step CIE 13.3 tabulates the samples at); a
spectrum given on another grid is interpolated linearly and held at its end values beyond. It is
tested against colour-science 0.4.6's ``colour_rendering_index`` (which interpolates to 1 nm and finds
the CCT by Robertson's method) on illuminants A, FL2, LED-B5 and a reversing lamp's light: within 0.5
(tests/photometry/test_colour_rendering.py). CIE 13.3 applies to light near the Planckian locus
(its distance ΔC below 5.4 × 10⁻³); ``general_cri`` computes the index for any light, so callers keep
it to white light (``measures.export`` does: red and amber light are "n/a").
"""

from __future__ import annotations

import functools

import numpy as np

from .cie import cmfs
from .daylight import daylight_spectrum
from .tables import table

TCS_TABLE = "cie133_tcs.csv"
STEP_NM = 5.0
C2_M_K = 1.4388e-2  # second radiation constant in m·K (CIE 015:2018 §3.1, the ITS-90 value)
DAYLIGHT_FROM_K = 5000.0  # CIE 13.3 §5.2: Planckian reference below, D series at and above
MIRED_RANGE = (1e6 / 25000.0, 1e6 / 1000.0)  # CCTs searched: 1000 to 25 000 K (the D series' upper end)


@functools.cache
def _grid() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(wavelengths nm, x̄ ȳ z̄ (N, 3), TCS01–08 radiance factors (N, 8)) at 5 nm, 360–830 nm."""
    tcs_nm, tcs = table(TCS_TABLE)
    cmf_nm, xyz_bar = cmfs()
    if not np.allclose(np.diff(tcs_nm), STEP_NM) or tcs_nm[0] < cmf_nm[0] or tcs_nm[-1] > cmf_nm[-1]:
        raise ValueError(f"{TCS_TABLE}: expected samples every {STEP_NM:g} nm within the observer's range")
    xyz = np.stack([np.interp(tcs_nm, cmf_nm, xyz_bar[:, k]) for k in range(3)], axis=1)
    return tcs_nm, xyz, tcs


def _uv(XYZ: np.ndarray) -> np.ndarray:
    """CIE 1960 UCS (u, v) of XYZ (..., 3)."""
    X, Y, Z = XYZ[..., 0], XYZ[..., 1], XYZ[..., 2]
    den = X + 15.0 * Y + 3.0 * Z
    return np.stack([4.0 * X / den, 6.0 * Y / den], axis=-1)


def planck(wavelengths_nm: np.ndarray, temperature_k: float) -> np.ndarray:
    """Relative spectral radiance of a Planckian radiator: λ⁻⁵ / (exp(c2 / λT) − 1), 1 at 560 nm."""
    lam = np.asarray(wavelengths_nm, dtype=np.float64) * 1e-9
    ref = 560e-9
    return (ref / lam) ** 5 * np.expm1(C2_M_K / (ref * temperature_k)) / np.expm1(C2_M_K / (lam * temperature_k))


def _planck_uv(mired: float) -> np.ndarray:
    lam, xyz_bar, _ = _grid()
    return _uv(planck(lam, 1e6 / mired) @ xyz_bar)


def cct_of_uv(uv: np.ndarray) -> float:
    """The CCT in K of CIE 1960 (u, v): the Planckian radiator nearest in (u, v), by a grid search in
    mired (1 mired steps) refined by golden section to 10⁻⁶ mired."""
    target = np.asarray(uv, dtype=np.float64)

    def distance(m: float) -> float:
        return float(np.hypot(*(_planck_uv(m) - target)))

    grid = np.arange(MIRED_RANGE[0], MIRED_RANGE[1] + 1.0, 1.0)
    best = int(np.argmin([distance(m) for m in grid]))
    lo, hi = grid[max(best - 1, 0)], grid[min(best + 1, len(grid) - 1)]
    ratio = (np.sqrt(5.0) - 1.0) / 2.0
    while hi - lo > 1e-6:
        a, b = hi - ratio * (hi - lo), lo + ratio * (hi - lo)
        if distance(a) < distance(b):
            hi = b
        else:
            lo = a
    return 1e6 / (0.5 * (lo + hi))


def reference_illuminant(wavelengths_nm: np.ndarray, cct_k: float) -> np.ndarray:
    """CIE 13.3's reference at ``cct_k``: Planckian below 5000 K, the CIE D series from 5000 K."""
    if cct_k < DAYLIGHT_FROM_K:
        return planck(wavelengths_nm, cct_k)
    return daylight_spectrum(float(cct_k)).at(wavelengths_nm)


def _samples_uvw(source: np.ndarray, adapt_from: np.ndarray | None, white_uv: np.ndarray) -> np.ndarray:
    """(8, 3) CIE 1964 U*V*W* of the eight samples under ``source`` (at the 5 nm grid), relative to
    ``white_uv``; ``adapt_from`` (c_r/c_t, d_r/d_t) applies CIE 13.3's von Kries transform."""
    _, xyz_bar, tcs = _grid()
    k = 100.0 / float(source @ xyz_bar[:, 1])  # Y = 100 for the source itself
    XYZ = k * ((source[:, None] * tcs).T @ xyz_bar)  # (8, 3)
    uv = _uv(XYZ)
    if adapt_from is not None:
        c, d = _cd(uv)
        den = 16.518 + 1.481 * adapt_from[0] * c - adapt_from[1] * d
        uv = np.stack([(10.872 + 0.404 * adapt_from[0] * c - 4.0 * adapt_from[1] * d) / den, 5.520 / den], axis=-1)
    w = 25.0 * np.cbrt(XYZ[:, 1]) - 17.0
    return np.stack([13.0 * w * (uv[:, 0] - white_uv[0]), 13.0 * w * (uv[:, 1] - white_uv[1]), w], axis=-1)


def _cd(uv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """CIE 13.3's c and d of (u, v)."""
    u, v = uv[..., 0], uv[..., 1]
    return (4.0 - u - 10.0 * v) / v, (1.708 * v + 0.404 - 1.481 * u) / v


def special_cri(wavelengths_nm: np.ndarray, spd: np.ndarray) -> np.ndarray:
    """(8,) special colour rendering indices R_1 … R_8 of a light of relative spectral power ``spd``
    at ``wavelengths_nm`` (module docstring)."""
    x = np.asarray(wavelengths_nm, dtype=np.float64)
    y = np.asarray(spd, dtype=np.float64)
    if x.ndim != 1 or y.shape != x.shape or x.size < 2 or not np.all(np.diff(x) > 0):
        raise ValueError(f"colour rendering: expected increasing wavelengths and as many values, got {x.shape} "
                         f"and {y.shape}")
    if not (np.isfinite(y).all() and (y >= 0).all()):
        raise ValueError("colour rendering: the spectrum's values must be finite and 0 or more")
    lam, xyz_bar, _ = _grid()
    test = np.interp(lam, x, y)
    XYZ = test @ xyz_bar
    if not XYZ[1] > 0:
        raise ValueError("colour rendering: the spectrum has no visible light")
    uv_t = _uv(XYZ)
    cct = cct_of_uv(uv_t)
    reference = reference_illuminant(lam, cct)
    uv_r = _uv(reference @ xyz_bar)
    (c_t, d_t), (c_r, d_r) = _cd(uv_t), _cd(uv_r)
    under_reference = _samples_uvw(reference, None, uv_r)
    under_test = _samples_uvw(test, np.array([c_r / c_t, d_r / d_t]), uv_r)
    return 100.0 - 4.6 * np.linalg.norm(under_test - under_reference, axis=1)


def general_cri(wavelengths_nm: np.ndarray, spd: np.ndarray) -> float:
    """CIE 13.3-1995 general colour rendering index Ra: the mean of R_1 … R_8 (``special_cri``)."""
    return float(np.mean(special_cri(wavelengths_nm, spd)))

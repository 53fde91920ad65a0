"""The colour of a lamp's light in a direction, checked against the signal colours' regions.

The light's chromaticity in a direction is that of its intensity-weighted spectrum: the tristimulus
intensities (X, Y, Z in cd) that ``intensity`` integrates over the projected area, so x = X/(X+Y+Z),
y = Y/(X+Y+Z) (``Intensity.xyz``), the colour a photometer with a colorimetric head sees from far.

Regions, in CIE 1931 xy:
- UN R48 §2.29 (``photometry.regulation.R48_REGIONS``, cited there);
- SAE J578 APR2020 §3.1 (red, yellow, white): the vertices as tabulated by Tnlab, "SAE J578-2020:
  chromaticity requirements for ground vehicle lamps" (tnlab.org, read 2026-12-03; the SAE text is
  sold, not public). Its DEC2006 revision harmonised the red, yellow and white boundaries with the
  ECE's (SAE J578 DEC2006 abstract, fid-move.de), and the vertices are R48's corners.
A point on a boundary is inside (both regulations' boundaries are limits, "not greater than").
"""

from __future__ import annotations

import numpy as np

from ..photometry import cie
from ..photometry.regulation import R48_REGIONS
from ..photometry.spectrum import Spectrum

SAE_J578_REGIONS: dict[str, tuple[tuple[float, float], ...]] = {
    "red": ((0.665, 0.335), (0.645, 0.335), (0.721, 0.259), (0.735, 0.265)),
    "amber": ((0.560, 0.440), (0.545, 0.425), (0.597, 0.390), (0.609, 0.390)),  # J578's "yellow (amber)"
    "white": ((0.310, 0.348), (0.310, 0.283), (0.443, 0.382), (0.500, 0.382), (0.500, 0.440), (0.453, 0.440)),
}
REGIONS = {"UN R48 §2.29": R48_REGIONS, "SAE J578": SAE_J578_REGIONS}
EDGE_TOLERANCE = 1e-9  # how near an edge counts as on it


def inside(xy, corners) -> np.ndarray:
    """True where chromaticities ``xy`` (..., 2) lie inside or on the polygon ``corners`` (even-odd
    rule: a polygon that is not convex, R48's white, is handled)."""
    p = np.asarray(xy, dtype=np.float64)
    x, y = p[..., 0, None], p[..., 1, None]
    poly = np.asarray(corners, dtype=np.float64)
    x0, y0 = poly[:, 0], poly[:, 1]
    x1, y1 = np.roll(x0, -1), np.roll(y0, -1)
    with np.errstate(divide="ignore", invalid="ignore"):
        crossing_x = x0 + (y - y0) * (x1 - x0) / np.where(y1 != y0, y1 - y0, 1.0)
    crosses = ((y0 > y) != (y1 > y)) & (x < crossing_x)
    odd = np.count_nonzero(crosses, axis=-1) % 2 == 1
    length2 = (x1 - x0) ** 2 + (y1 - y0) ** 2
    t = np.clip(((x - x0) * (x1 - x0) + (y - y0) * (y1 - y0)) / length2, 0.0, 1.0)
    on_edge = np.hypot(x - (x0 + t * (x1 - x0)), y - (y0 + t * (y1 - y0))) <= EDGE_TOLERANCE
    return odd | np.any(on_edge, axis=-1)


def xy_of(xyz) -> np.ndarray:
    """Chromaticity (2,) of tristimulus values (3,) (an ``Intensity.xyz``)."""
    return cie.xy(np.asarray(xyz, dtype=np.float64))


def spectrum_xy(spectrum: Spectrum) -> np.ndarray:
    """Chromaticity of a spectral curve over 380–780 nm at 1 nm (``photometry.cie.spectrum_xyz``)."""
    return cie.xy(cie.spectrum_xyz(spectrum))


def check(xy, colour: str) -> dict[str, bool]:
    """Whether ``xy`` lies in ``colour``'s region of each regulation: {"UN R48 §2.29": …, "SAE J578": …}."""
    if colour not in SAE_J578_REGIONS:
        raise ValueError(f"signal colour: {colour!r} is not one of {', '.join(SAE_J578_REGIONS)}")
    return {name: bool(inside(xy, regions[colour])) for name, regions in REGIONS.items()}


def distance_outside(xy, corners) -> float:
    """0 inside; outside, the distance in xy to the region's nearest edge (how far a colour misses)."""
    if inside(xy, corners):
        return 0.0
    p = np.asarray(xy, dtype=np.float64)
    poly = np.asarray(corners, dtype=np.float64)
    a, b = poly, np.roll(poly, -1, axis=0)
    ab = b - a
    t = np.clip(((p - a) * ab).sum(axis=1) / (ab * ab).sum(axis=1), 0.0, 1.0)
    return float(np.min(np.linalg.norm(a + t[:, None] * ab - p, axis=1)))

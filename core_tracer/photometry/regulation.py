"""Colour regions of signal light in CIE 1931 xy: UN Regulation No. 48 §2.29.

UN R48 ("installation of lighting and light-signalling devices") §2.29, "Colour of the light
emitted from a device", gives each colour as boundaries and corner points (text as published in
the EU Official Journal, e.g. lexaris.io/book/version/documentflat/head/2048910):

- red: R12 yellow boundary y = 0.335, R23 the spectral locus, R34 the purple line, R41 purple
  boundary y = 0.980 − x; corners R1 (0.645, 0.335), R2 (0.665, 0.335), R3 (0.735, 0.265),
  R4 (0.721, 0.259);
- amber: A12 green boundary y = x − 0.120, A23 the spectral locus, A34 red boundary y = 0.390,
  A41 white boundary y = 0.790 − 0.670x; corners A1 (0.545, 0.425), A2 (0.560, 0.440),
  A3 (0.609, 0.390), A4 (0.597, 0.390);
- white: corners W1 (0.310, 0.348), W2 (0.453, 0.440), W3 (0.500, 0.440), W4 (0.500, 0.382),
  W5 (0.443, 0.382), W6 (0.310, 0.283).

Where a boundary is the spectral locus the corner polygon runs along x + y = 1 between the corners,
which is where the locus lies at those long wavelengths (z̄ ≈ 0): a physical light cannot lie
beyond it, so the polygon test is the regulation's test.
"""

from __future__ import annotations

import numpy as np

R48_REGIONS: dict[str, tuple[tuple[float, float], ...]] = {
    "red": ((0.645, 0.335), (0.665, 0.335), (0.735, 0.265), (0.721, 0.259)),
    "amber": ((0.545, 0.425), (0.560, 0.440), (0.609, 0.390), (0.597, 0.390)),
    "white": ((0.310, 0.348), (0.453, 0.440), (0.500, 0.440), (0.500, 0.382), (0.443, 0.382), (0.310, 0.283)),
}


def in_region(xy: np.ndarray, region: str) -> np.ndarray:
    """True where chromaticity ``xy`` (..., 2) lies inside (or on) R48's ``region``."""
    corners = R48_REGIONS.get(region)
    if corners is None:
        raise ValueError(f"colour region: {region!r} is not one of {', '.join(R48_REGIONS)}")
    p = np.asarray(xy, dtype=np.float64)
    x, y = p[..., 0, None], p[..., 1, None]
    poly = np.asarray(corners)
    x0, y0 = poly[:, 0], poly[:, 1]
    x1, y1 = np.roll(x0, -1), np.roll(y0, -1)
    # even-odd rule (the white region is not convex), with points on an edge counted inside
    crosses = ((y0 > y) != (y1 > y)) & (x < x0 + (y - y0) * (x1 - x0) / np.where(y1 != y0, y1 - y0, 1.0))
    inside = np.count_nonzero(crosses, axis=-1) % 2 == 1
    length = np.hypot(x1 - x0, y1 - y0)
    t = np.clip(((x - x0) * (x1 - x0) + (y - y0) * (y1 - y0)) / (length * length), 0.0, 1.0)
    near = np.hypot(x - (x0 + t * (x1 - x0)), y - (y0 + t * (y1 - y0))) <= 1e-9
    return inside | np.any(near, axis=-1)

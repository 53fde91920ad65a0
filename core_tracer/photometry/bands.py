"""Wavelength bands: the K intervals of 380–780 nm that the photometric tracer carries.

A band holds the mean of a spectral quantity over its interval (a band-mean spectral radiance in
W/(m² sr nm), a band-mean transmittance). ``Bands.average`` makes those means from a tabulated
curve exactly: the curve is taken as piecewise linear between its samples (as the CIE tables are
interpolated, CIE 015:2018 §7.2.1) and held at its end values beyond them, and each band's mean is
the integral of that polyline over the band divided by the band's width.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

VISIBLE_NM = (380.0, 780.0)  # the carried range: CIE 015:2018 computes colour over 380–780 nm at least
MAX_BANDS = 1000


def _frozen(a: np.ndarray) -> np.ndarray:
    a = np.array(a, dtype=np.float64)
    a.flags.writeable = False
    return a


@dataclass(frozen=True, eq=False)
class Bands:
    """K contiguous wavelength bands given by their K + 1 increasing edges in nm."""

    edges_nm: np.ndarray
    centres_nm: np.ndarray = field(init=False, repr=False)
    widths_nm: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        edges = np.asarray(self.edges_nm, dtype=np.float64)
        if edges.ndim != 1 or not 2 <= edges.size <= MAX_BANDS + 1:
            raise ValueError(f"band edges: expected 2 to {MAX_BANDS + 1} values, got shape {edges.shape}")
        if not np.all(np.isfinite(edges)) or not np.all(np.diff(edges) > 0):
            raise ValueError("band edges: expected finite, strictly increasing wavelengths in nm")
        object.__setattr__(self, "edges_nm", _frozen(edges))
        object.__setattr__(self, "centres_nm", _frozen(0.5 * (edges[:-1] + edges[1:])))
        object.__setattr__(self, "widths_nm", _frozen(np.diff(edges)))

    @property
    def k(self) -> int:
        """The number of bands."""
        return int(self.edges_nm.size - 1)

    @classmethod
    def uniform(cls, k: int, lo: float = VISIBLE_NM[0], hi: float = VISIBLE_NM[1]) -> Bands:
        """``k`` bands of equal width from ``lo`` to ``hi`` nm."""
        if not isinstance(k, (int, np.integer)) or not 1 <= k <= MAX_BANDS:
            raise ValueError(f"number of bands: {k!r} is not an integer from 1 to {MAX_BANDS}")
        if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
            raise ValueError(f"band range: {lo!r} to {hi!r} nm is not an increasing finite range")
        return cls(np.linspace(float(lo), float(hi), int(k) + 1))

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Bands) and np.array_equal(self.edges_nm, other.edges_nm)

    def __hash__(self) -> int:
        return hash(self.edges_nm.tobytes())

    def __repr__(self) -> str:
        return f"Bands(k={self.k}, {self.edges_nm[0]:g}–{self.edges_nm[-1]:g} nm)"

    def average(self, wavelengths_nm: np.ndarray, values: np.ndarray) -> np.ndarray:
        """Band means of a tabulated curve: (K,) for values (N,), (K, C) for values (N, C).

        Exact for the polyline through the samples (held constant beyond the first and last).
        """
        x = np.asarray(wavelengths_nm, dtype=np.float64)
        y = np.asarray(values, dtype=np.float64)
        if x.ndim != 1 or x.size < 1 or y.shape[:1] != x.shape:
            raise ValueError(f"band average: wavelengths {x.shape} and values {y.shape} do not match")
        if x.size > 1 and not np.all(np.diff(x) > 0):
            raise ValueError("band average: wavelengths must increase strictly")
        flat = y.reshape(x.size, -1)
        # Hold the end values out to the band edges, so the polyline covers every band.
        lo, hi = self.edges_nm[0], self.edges_nm[-1]
        if lo < x[0]:
            x, flat = np.concatenate([[lo], x]), np.vstack([flat[:1], flat])
        if hi > x[-1]:
            x, flat = np.concatenate([x, [hi]]), np.vstack([flat, flat[-1:]])
        integral = _cumulative_integral(x, flat, self.edges_nm)
        means = np.diff(integral, axis=0) / self.widths_nm[:, None]
        return means.reshape((self.k,) + y.shape[1:])

    def integrals(self, wavelengths_nm: np.ndarray, values: np.ndarray) -> np.ndarray:
        """Band integrals (mean × width) of a tabulated curve, e.g. nm-weighted CMF sums."""
        means = self.average(wavelengths_nm, values)
        return means * self.widths_nm.reshape((self.k,) + (1,) * (means.ndim - 1))


def _cumulative_integral(x: np.ndarray, y: np.ndarray, at: np.ndarray) -> np.ndarray:
    """∫_{x[0]}^{at} of the polyline (x, y) for each point of ``at`` (inside [x[0], x[-1]]): (len(at), C)."""
    seg_area = 0.5 * (y[1:] + y[:-1]) * np.diff(x)[:, None]
    cum = np.vstack([np.zeros((1, y.shape[1])), np.cumsum(seg_area, axis=0)])
    i = np.clip(np.searchsorted(x, at, side="right") - 1, 0, x.size - 2)
    t = at - x[i]
    width = x[i + 1] - x[i]
    slope = (y[i + 1] - y[i]) / width[:, None]
    return cum[i] + y[i] * t[:, None] + 0.5 * slope * (t * t)[:, None]

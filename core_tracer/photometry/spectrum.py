"""A tabulated spectral curve: a source's relative power, a filter's transmittance, a reflectance."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .bands import Bands

MAX_SAMPLES = 100_000
FINE_STEP_NM = 1.0  # products of two curves are sampled at least this finely (CIE 015:2018 uses 1 or 5 nm)


def _frozen(a: np.ndarray) -> np.ndarray:
    a = np.array(a, dtype=np.float64)
    a.flags.writeable = False
    return a


@dataclass(frozen=True, eq=False)
class Spectrum:
    """Values at increasing wavelengths in nm; linear between samples, held at the end values beyond.

    ``name`` says what it is (shown in errors and tables). Values are finite and not negative."""

    wavelengths_nm: np.ndarray
    values: np.ndarray
    name: str = "spectrum"

    def __post_init__(self) -> None:
        x = np.asarray(self.wavelengths_nm, dtype=np.float64)
        y = np.asarray(self.values, dtype=np.float64)
        if x.ndim != 1 or y.shape != x.shape or not 2 <= x.size <= MAX_SAMPLES:
            raise ValueError(f"{self.name}: expected 2 to {MAX_SAMPLES} (wavelength, value) pairs, "
                             f"got wavelengths {x.shape} and values {y.shape}")
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
            raise ValueError(f"{self.name}: wavelengths and values must be finite numbers")
        if not np.all(np.diff(x) > 0):
            raise ValueError(f"{self.name}: wavelengths must increase strictly")
        if np.any(y < 0):
            raise ValueError(f"{self.name}: values must be 0 or more")
        object.__setattr__(self, "wavelengths_nm", _frozen(x))
        object.__setattr__(self, "values", _frozen(y))

    def at(self, wavelengths_nm: np.ndarray | float) -> np.ndarray:
        """The curve at the given wavelengths (linear between samples, the end values beyond)."""
        return np.interp(wavelengths_nm, self.wavelengths_nm, self.values)

    def band_means(self, bands: Bands) -> np.ndarray:
        """(K,) band means of the curve (exact for its polyline)."""
        return bands.average(self.wavelengths_nm, self.values)

    def scaled(self, factor: float, name: str | None = None) -> Spectrum:
        return Spectrum(self.wavelengths_nm, self.values * float(factor), name or self.name)

    def times(self, other: Spectrum, name: str | None = None) -> Spectrum:
        """The product of two curves, sampled at both curves' samples and at least every 1 nm."""
        x = fine_grid(self.wavelengths_nm, other.wavelengths_nm)
        return Spectrum(x, self.at(x) * other.at(x), name or f"{self.name} × {other.name}")

    def __eq__(self, other: object) -> bool:
        return (isinstance(other, Spectrum) and np.array_equal(self.wavelengths_nm, other.wavelengths_nm)
                and np.array_equal(self.values, other.values))

    __hash__ = None  # mutable-looking contents; compare with ==

    def __repr__(self) -> str:
        return (f"Spectrum({self.name!r}, {self.wavelengths_nm.size} samples, "
                f"{self.wavelengths_nm[0]:g}–{self.wavelengths_nm[-1]:g} nm)")


def fine_grid(*grids: np.ndarray) -> np.ndarray:
    """The union of the grids' samples and a 1 nm grid over their common span."""
    lo = min(float(g[0]) for g in grids)
    hi = max(float(g[-1]) for g in grids)
    fine = np.arange(np.floor(lo), np.ceil(hi) + FINE_STEP_NM / 2, FINE_STEP_NM)
    return np.unique(np.concatenate([*grids, fine[(fine >= lo) & (fine <= hi)]]))

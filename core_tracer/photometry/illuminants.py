"""The CIE spectra shipped as data (``data/``): illuminant A, D65, LED-B5 and the daylight basis."""

from __future__ import annotations

import functools

import numpy as np

from .spectrum import Spectrum
from .tables import table


@functools.cache
def illuminant_a() -> Spectrum:
    """CIE standard illuminant A (Planckian radiator at 2856 K), relative, 100 at 560 nm."""
    wavelengths, power = table("illuminant_a.csv")
    return Spectrum(wavelengths, power[:, 0], "CIE illuminant A")


@functools.cache
def illuminant_d65() -> Spectrum:
    """CIE standard illuminant D65, relative, 100 at 560 nm."""
    wavelengths, power = table("illuminant_d65.csv")
    return Spectrum(wavelengths, power[:, 0], "CIE illuminant D65")


@functools.cache
def led_b5() -> Spectrum:
    """CIE illuminant LED-B5 (phosphor-converted white LED, CIE 015:2018 Table 10), relative."""
    wavelengths, power = table("led_b5.csv")
    return Spectrum(wavelengths, power[:, 0], "CIE illuminant LED-B5")


def daylight_basis() -> tuple[np.ndarray, np.ndarray]:
    """(wavelengths nm, (N, 3) S0 S1 S2) of the CIE daylight series (CIE 015:2018 Table 6)."""
    return table("daylight_basis.csv")

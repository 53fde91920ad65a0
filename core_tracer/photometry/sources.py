"""Light sources: spectra (incandescent, amber-coated, LEDs, measured CSV), named bulbs, and the
spectral radiance of a bulb of given flux.

A bulb in the tracer is a Lambertian sphere of radius r: a sphere radiating flux Φ uniformly has
exitance M = Φ / (4π r²) and luminance L_v = M / π = Φ / (4π² r²) (r in metres, L_v in cd/m²).
``bulb_spectral_radiance`` gives that luminance the bulb's spectral shape, band by band, scaled
so that the bands' own luminance (``L @ cie.luminance_weights(bands)``) is exactly L_v for every
K: the bulb is as bright as its flux says at any band count; only its colour converges with K.

Spectra:
- ``incandescent()``: CIE standard illuminant A (a Planckian radiator at 2856 K), the CIE's
  representative of tungsten-filament lighting (CIE 015:2018 §3.1).
- ``amber_coated()``: illuminant A times the transmittance of a selective amber bulb coating,
  modelled as a logistic cut-on (``materials.FILTERS['amber']``: edge 550 nm, slope 7 nm,
  0.001 → 0.90). This is a model chosen to meet UN R48's amber region (tested), not a measured
  coating; give a measured curve with ``from_csv`` when one is available.
- ``led(peak_nm, width_nm)``: the single-LED model of Y. Ohno, "Spectral design considerations for
  white LED color rendering", Optical Engineering 44(11):111302 (2005):
  S(λ) = (g + 2 g⁵)/3 with g = exp(−((λ − λ₀)/Δλ)²), Δλ the half spectral width (the curve's full
  width at half maximum is 0.921 Δλ). Same as colour-science's ``sd_single_led_Ohno2005``.
  ``LED_PRESETS`` give red and amber LEDs whose colour under that model lies inside UN R48's red
  and amber regions (tested); ``white_led()`` is CIE illuminant LED-B5, a phosphor-converted white
  LED (CIE 015:2018 Table 10).
- ``from_csv(path)``: a measured spectrum, two columns ``nm,value``.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field

import numpy as np

from .bands import VISIBLE_NM, Bands
from .cie import luminance_weights
from .illuminants import illuminant_a, led_b5
from .materials import FILTERS
from .spectrum import Spectrum

CSV_MAX_BYTES = 1_000_000
CSV_MAX_ROWS = 20_000
CSV_RANGE_NM = (200.0, 2000.0)  # a spectrum's wavelengths must lie in this range
CSV_MAX_VALUE = 1e30  # above this, a curve's integrals over the bands may overflow (1.7e308 did, issue 33)


def incandescent() -> Spectrum:
    """CIE illuminant A, relative spectral power (100 at 560 nm)."""
    return illuminant_a()


def amber_coated() -> Spectrum:
    """Illuminant A through the amber coating model (see the module's docstring)."""
    return illuminant_a().times(FILTERS["amber"].spectrum(), "amber-coated incandescent")


def led(peak_nm: float, width_nm: float, step_nm: float = 1.0) -> Spectrum:
    """Ohno (2005) single LED peaking at ``peak_nm`` with half spectral width ``width_nm``, 360–830 nm."""
    if not (np.isfinite(peak_nm) and 360.0 <= peak_nm <= 830.0):
        raise ValueError(f"LED peak: {peak_nm!r} nm is outside 360 to 830 nm")
    if not (np.isfinite(width_nm) and 1.0 <= width_nm <= 300.0):
        raise ValueError(f"LED width: {width_nm!r} nm is outside 1 to 300 nm")
    lam = np.arange(360.0, 830.0 + step_nm / 2, step_nm)
    g = np.exp(-(((lam - peak_nm) / width_nm) ** 2))
    return Spectrum(lam, (g + 2.0 * g ** 5) / 3.0, f"LED {peak_nm:g} nm / {width_nm:g} nm")


def white_led() -> Spectrum:
    """CIE illuminant LED-B5: a phosphor-converted white LED."""
    return led_b5()


# (peak nm, half spectral width nm) of the LED presets: this project's choices, inside R48's
# colour regions under Ohno's model (tests/photometry/test_sources.py checks it).
LED_PRESETS = {"red": (630.0, 20.0), "amber": (592.0, 17.0)}

SPECTRA = {
    "incandescent": incandescent,
    "amber_coated": amber_coated,
    "red_led": lambda: led(*LED_PRESETS["red"]),
    "amber_led": lambda: led(*LED_PRESETS["amber"]),
    "white_led": white_led,
}


def named_spectrum(name: str) -> Spectrum:
    """One of ``SPECTRA`` by name; a one-line error naming the allowed names otherwise."""
    make = SPECTRA.get(name)
    if make is None:
        raise ValueError(f"spectrum: {name!r} is not one of {', '.join(SPECTRA)}")
    return make()


# ---------------------------------------------------------------------------------------------
# Measured spectra


class SpectrumFileError(ValueError):
    """A spectrum file that cannot be used; ``str()`` is the one-line message naming the file."""


def from_csv(path: str | os.PathLike, *, max_bytes: int = CSV_MAX_BYTES) -> Spectrum:
    """A spectrum from a text file of ``nm,value`` rows (``#`` comments and one header line allowed).

    The file must be a regular file of at most ``max_bytes``, UTF-8, with 2 to 20 000 rows of two
    finite numbers, wavelengths strictly increasing within 200–2000 nm, values 0 or more and not all 0.
    Every failure is a ``SpectrumFileError`` naming the file (and the line)."""
    name = os.fspath(path)
    shown = os.path.basename(name) or name

    def fail(message: str) -> SpectrumFileError:
        return SpectrumFileError(f"{shown}: {message}")

    try:
        st = os.stat(name)
    except OSError as e:
        raise fail(f"cannot read the spectrum file ({e.strerror or e})") from None
    import stat

    if not stat.S_ISREG(st.st_mode):
        raise fail("not a regular file")
    if st.st_size > max_bytes:
        raise fail(f"file is {st.st_size} bytes; allowed at most {max_bytes} bytes")
    try:
        with open(name, "rb") as f:
            raw = f.read(max_bytes + 1)
    except OSError as e:
        raise fail(f"cannot read the spectrum file ({e.strerror or e})") from None
    if len(raw) > max_bytes:
        raise fail(f"file is over {max_bytes} bytes; allowed at most {max_bytes} bytes")
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise fail("not UTF-8 text") from None

    rows: list[tuple[float, float]] = []
    header_seen = False
    for number, line in enumerate(text.splitlines(), start=1):
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        cells = [c.strip() for c in line.replace(";", ",").replace("\t", ",").split(",")]
        if len(cells) != 2:
            raise fail(f"line {number}: expected two columns nm,value, got {len(cells)}")
        try:
            nm, value = float(cells[0]), float(cells[1])
        except ValueError:
            if not rows and not header_seen:
                header_seen = True  # one header line before the numbers
                continue
            raise fail(f"line {number}: {line[:40]!r} is not two numbers nm,value") from None
        if not (math.isfinite(nm) and math.isfinite(value)):
            raise fail(f"line {number}: values must be finite numbers")
        if not CSV_RANGE_NM[0] <= nm <= CSV_RANGE_NM[1]:
            raise fail(f"line {number}: wavelength {nm:g} nm is outside {CSV_RANGE_NM[0]:g} to {CSV_RANGE_NM[1]:g} nm")
        if value < 0:
            raise fail(f"line {number}: value {value:g} is negative; allowed 0 or more")
        if value > CSV_MAX_VALUE:
            raise fail(f"line {number}: value {value:g} is too large to integrate; allowed 0 to {CSV_MAX_VALUE:g} "
                       "(a spectrum is relative: any unit will do)")
        if rows and nm <= rows[-1][0]:
            raise fail(f"line {number}: wavelength {nm:g} nm does not increase (previous {rows[-1][0]:g} nm)")
        rows.append((nm, value))
        if len(rows) > CSV_MAX_ROWS:
            raise fail(f"more than {CSV_MAX_ROWS} rows; allowed 2 to {CSV_MAX_ROWS}")
    if len(rows) < 2:
        raise fail(f"found {len(rows)} rows of nm,value; allowed 2 to {CSV_MAX_ROWS}")
    data = np.array(rows)
    if not np.any(data[:, 1] > 0):
        raise fail("every value is 0; a spectrum needs some power")
    lo, hi = VISIBLE_NM
    if data[-1, 0] < lo or data[0, 0] > hi:  # held at its end value, it would be flat over the visible range
        raise fail(f"its wavelengths {data[0, 0]:g} to {data[-1, 0]:g} nm lie outside the visible range {lo:g} to "
                   f"{hi:g} nm, over which it would be held flat; allowed a curve with samples in {lo:g} to {hi:g} nm")
    return Spectrum(data[:, 0], data[:, 1], shown)


# ---------------------------------------------------------------------------------------------
# Named bulbs


@dataclass(frozen=True)
class BulbState:
    """One filament (or LED state) of a bulb: its luminous flux in lm at the test voltage."""

    flux_lm: float
    tolerance_pct: float | None = None  # the objective flux's ± % where the source states it
    value: str = "reference"  # "reference" (standard lamp) or "objective" (production lamps' nominal)


@dataclass(frozen=True)
class BulbType:
    """A standard light-source category: states (filaments) with flux, its spectrum, its source."""

    name: str
    spectrum: str  # a key of SPECTRA
    states: dict[str, BulbState] = field(default_factory=dict)
    source: str = ""


# UN Regulation No. 37 (filament light sources), category sheets, 12 V lamps at 13.5 V: the
# reference luminous flux (the flux a lamp's photometry is normalised to) where the sheet found
# gives it, else the objective flux of production lamps, with its tolerance. Looked up and not
# found (so left out rather than guessed): P21W, PY21W, W16W, and R128's LED categories.
BULB_TYPES: dict[str, BulbType] = {
    "P21/5W": BulbType(
        "P21/5W", "incandescent",
        {"stop": BulbState(440.0, 15.0), "tail": BulbState(35.0, 20.0)},
        "UN R37 sheet P21/5W/1 (12 V, 13.5 V: 440 lm ±15 % and 35 lm ±20 %; reference flux 440 and "
        "35 lm), as reproduced in Directive 97/24/EC ch. 2, Annex (gesetze.legal/eu/rl_97_24_eg/anlage_15)"),
    "R5W": BulbType(
        "R5W", "incandescent",
        {"on": BulbState(50.0)},
        "UN R37 category R5W, standard lamp reference luminous flux 50 lm at about 13.5 V, as adopted "
        "in GOST R 41.37 table 41 (ar-net.ru/doc/read/15584/17)"),
    "PY21/5W": BulbType(
        "PY21/5W", "amber_coated",
        {"stop": BulbState(270.0, 20.0, "objective"), "tail": BulbState(21.0, 20.0, "objective")},
        "UN R37 sheet PY21/5W/1 (amber, 12 V, 13.5 V: objective flux 270 lm and 21 lm ±20 %), as introduced "
        "by Supplement 41 to the 03 series, proposal ECE/TRANS/WP.29/GRE/2012/34"),
}


def bulb_luminance(flux_lm: float, radius_mm: float) -> float:
    """Luminance in cd/m² of a Lambertian sphere of radius ``radius_mm`` emitting ``flux_lm``:
    L = Φ / (π · 4π r²)."""
    if not (np.isfinite(flux_lm) and flux_lm >= 0):
        raise ValueError(f"bulb flux: {flux_lm!r} lm is not 0 or more")
    if not (np.isfinite(radius_mm) and radius_mm > 0):
        raise ValueError(f"bulb radius: {radius_mm!r} mm is not above 0")
    area = 4.0 * math.pi ** 2 * (radius_mm * 1e-3) ** 2
    luminance = flux_lm / area if area > 0 else math.inf  # a radius of 1e-320 mm squares to 0
    if not math.isfinite(luminance):
        raise ValueError(f"bulb radius: {radius_mm!r} mm is too small: its luminance Φ/(4π² r²) is not a finite "
                         "number")
    return float(luminance)


def spectral_shape(spectrum: Spectrum, bands: Bands) -> np.ndarray:
    """(K,) band means of ``spectrum`` scaled to luminance 1 cd/m² in these bands."""
    with np.errstate(over="ignore", invalid="ignore", under="ignore"):
        means = spectrum.band_means(bands)
        luminance = float(means @ luminance_weights(bands))
    if not math.isfinite(luminance) or not np.isfinite(means).all():
        raise ValueError(f"{spectrum.name}: its integral over {bands!r} is not a finite number")
    if not luminance > 0:
        raise ValueError(f"{spectrum.name}: no visible light in {bands!r}")
    shape = means / luminance
    if not np.isfinite(shape).all():
        raise ValueError(f"{spectrum.name}: too little visible light in {bands!r} to scale")
    return shape


def bulb_spectral_radiance(flux_lm: float, spectrum: Spectrum, radius_mm: float, bands: Bands) -> np.ndarray:
    """(K,) band-mean spectral radiance in W/(m² sr nm) of a Lambertian sphere bulb of flux
    ``flux_lm``: its luminance Φ/(4π² r²) with the spectral shape of ``spectrum``."""
    return bulb_luminance(flux_lm, radius_mm) * spectral_shape(spectrum, bands)

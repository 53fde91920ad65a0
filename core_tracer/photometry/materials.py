"""Lens plastics, coloured filters, reflector metals and body paint, as spectra.

Dispersion. ``refractive_index(n_d, abbe, λ)`` is the two-term Cauchy formula n(λ) = A + B/λ²
(Born & Wolf, Principles of Optics, 7th ed., §2.3.4 eq. 2.3.43 truncated after B) with A and B
chosen so that n(λ_d) = n_d exactly and n(λ_F) − n(λ_C) = (n_d − 1)/V_d exactly: the Abbe number
V_d = (n_d − 1)/(n_F − n_C) at the lines F = 486.13 nm (H), d = 587.56 nm (He) and C = 656.27 nm (H)
of ISO 7944:1998. Two data determine two coefficients; a plastic's dispersion across 400–700 nm
is described by them to about 1e-3 (Sultanova et al. 2009 fit Cauchy–Schott forms to their
measurements within their ±0.001 accuracy).

Materials (``MATERIALS``): n_d and V_d of PMMA and polycarbonate from one measurement of both,
N. Sultanova, S. Kasarova, I. Nikolov, "Dispersion Properties of Optical Polymers", Acta Physica
Polonica A 116(4):585–587 (2009), doi:10.12693/APhysPolA.116.585, table of indices and Abbe numbers:
PMMA n_d = 1.491, V_d = 59.2; PC n_d = 1.585, V_d = 29.1. Other sources spread: refractiveindex.info
gives PMMA n(587.6 nm) = 1.4914 with V_d = 52.6 from Kasarova et al., Opt. Mater. 29:1481 (2007);
the issue's "about 1.492 / 57 and 1.586 / 30" lies within that spread.

Filters. Internal transmittance (surface reflection excluded: Fresnel is the tracer's) of a lens
material at a stated thickness, as a smooth cut-on: a logistic step from ``t_min`` below the edge
to ``t_max`` above it, T(λ) = t_min + (t_max − t_min) / (1 + exp(−(λ − edge)/slope)). The presets'
parameters are design choices of this project (not measurements), chosen so that CIE illuminant A
through the red and amber presets lands inside UN R48's red and amber regions (checked by tests in
``tests/photometry``); ``absorption_per_mm`` turns a transmittance at a thickness into the
Beer–Lambert coefficient the tracer applies along a path: T(d) = exp(−α d).

Mirrors. Normal-incidence reflectance of bare aluminium and silver in air, R = |(N − 1)/(N + 1)|²
with N = n + ik = √ε(λ) from the Lorentz–Drude fits of A. D. Rakić, A. B. Djurišić, J. M. Elazar,
M. L. Majewski, "Optical properties of metallic films for vertical-cavity optoelectronic devices",
Applied Optics 37(22):5271–5283 (1998), Table 1 (parameters in eV as also listed in the Meep
materials library, NanoComp/meep python/materials.py). A real reflector is a vacuum-metallised
film under a protective coat; its angle dependence is the tracer's business, not this table's.

Body paint. ``rgb_to_reflectance`` is B. Smits, "An RGB-to-spectrum conversion for reflectances",
Journal of Graphics Tools 4(4):11–22 (1999): a linear RGB is written as white plus one secondary
plus one primary, each a tabulated basis spectrum (shipped in ``data/smits1999.csv``). For light
(environment pixels) ``rgb_to_illuminant`` multiplies the same reflectance by the white of the RGB
space, D65, as pbrt-v4's RGBIlluminantSpectrum does (Pharr, Jakob, Humphreys, Physically Based
Rendering, 4th ed. 2023, §4.6.6), so that RGB (1, 1, 1) is D65 light.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from .bands import Bands
from .cie import luminance_weights
from .illuminants import illuminant_d65
from .spectrum import Spectrum, fine_grid
from .tables import table

# Fraunhofer lines of ISO 7944:1998 (nm): F (hydrogen), d (helium), C (hydrogen)
LINE_F_NM, LINE_D_NM, LINE_C_NM = 486.13, 587.56, 656.27


def cauchy_coefficients(n_d: float, abbe: float) -> tuple[float, float]:
    """(A, B in nm²) of n(λ) = A + B/λ² through n_d with Abbe number ``abbe``. n_d = 1 (a lens's
    lowest allowed ior, an index-matched "no lens") has no dispersion: n = 1 at every wavelength."""
    if not (np.isfinite(n_d) and n_d >= 1.0):
        raise ValueError(f"refractive index n_d: {n_d!r} is not a number of 1 or more")
    if not (np.isfinite(abbe) and abbe > 0.0):
        raise ValueError(f"Abbe number: {abbe!r} is not a number above 0 (allowed: above 0; plastics 20 to 70)")
    b = (n_d - 1.0) / abbe / (LINE_F_NM ** -2 - LINE_C_NM ** -2)
    return n_d - b / LINE_D_NM ** 2, b


def refractive_index(n_d: float, abbe: float, wavelengths_nm: np.ndarray | float) -> np.ndarray:
    """n(λ) of a material with index n_d and Abbe number ``abbe`` (two-term Cauchy, exact at d, F−C)."""
    a, b = cauchy_coefficients(n_d, abbe)
    lam = np.asarray(wavelengths_nm, dtype=np.float64)
    return a + b / (lam * lam)


@dataclass(frozen=True)
class Material:
    """A transparent lens or prism-plate plastic: index at the d line and Abbe number, with source."""

    name: str
    n_d: float
    abbe: float
    source: str

    def index(self, wavelengths_nm: np.ndarray | float) -> np.ndarray:
        return refractive_index(self.n_d, self.abbe, wavelengths_nm)


_SULTANOVA_2009 = ("N. Sultanova, S. Kasarova, I. Nikolov, Dispersion Properties of Optical Polymers, "
                   "Acta Physica Polonica A 116(4):585 (2009), doi:10.12693/APhysPolA.116.585")
MATERIALS: dict[str, Material] = {
    "pmma": Material("PMMA (acrylic)", 1.491, 59.2, _SULTANOVA_2009),
    "polycarbonate": Material("polycarbonate", 1.585, 29.1, _SULTANOVA_2009),
}


# ---------------------------------------------------------------------------------------------
# Filters


@dataclass(frozen=True)
class CutOnFilter:
    """A logistic cut-on: internal transmittance t_min below ``edge_nm``, t_max above, over ``slope_nm``."""

    edge_nm: float
    slope_nm: float
    t_min: float
    t_max: float
    thickness_mm: float = 3.0  # the thickness at which the curve is the transmittance

    def __post_init__(self) -> None:
        checks = (
            ("edge", self.edge_nm, 300.0, 900.0), ("slope", self.slope_nm, 0.1, 500.0),
            ("t_min", self.t_min, 0.0, 1.0), ("t_max", self.t_max, 0.0, 1.0),
            ("thickness", self.thickness_mm, 0.01, 100.0),
        )
        for what, value, lo, hi in checks:
            if not (isinstance(value, (int, float)) and np.isfinite(value) and lo <= value <= hi):
                raise ValueError(f"filter {what}: {value!r} is outside {lo:g} to {hi:g}")

    def transmittance(self, wavelengths_nm: np.ndarray | float) -> np.ndarray:
        lam = np.asarray(wavelengths_nm, dtype=np.float64)
        z = np.clip((lam - self.edge_nm) / self.slope_nm, -700.0, 700.0)
        return self.t_min + (self.t_max - self.t_min) / (1.0 + np.exp(-z))

    def spectrum(self, step_nm: float = 1.0) -> Spectrum:
        lam = np.arange(360.0, 830.0 + step_nm / 2, step_nm)
        return Spectrum(lam, self.transmittance(lam), "cut-on filter")


def cut_on_filter(edge_nm: float, slope_nm: float, t_min: float, t_max: float,
                  thickness_mm: float = 3.0) -> CutOnFilter:
    """A smooth cut-on filter (see ``CutOnFilter``); its curve holds at ``thickness_mm``."""
    return CutOnFilter(float(edge_nm), float(slope_nm), float(t_min), float(t_max), float(thickness_mm))


# Design presets at 3 mm (this project's choices; the red and amber ones meet UN R48's colour
# regions under illuminant A, tested). t_min is kept above 0 so that the absorption stays finite.
FILTERS: dict[str, CutOnFilter] = {
    "clear": CutOnFilter(edge_nm=400.0, slope_nm=10.0, t_min=1.0, t_max=1.0),
    "red": CutOnFilter(edge_nm=605.0, slope_nm=7.0, t_min=0.001, t_max=0.90),
    "amber": CutOnFilter(edge_nm=550.0, slope_nm=7.0, t_min=0.001, t_max=0.90),
    "smoke": CutOnFilter(edge_nm=500.0, slope_nm=80.0, t_min=0.30, t_max=0.50),
}


def absorption_per_mm(transmittance_at_thickness: np.ndarray | float, thickness_mm: float) -> np.ndarray:
    """Beer–Lambert absorption coefficient α in 1/mm from internal transmittance T at thickness d:
    α = −ln(T)/d, so that a path of length s transmits exp(−α s). T must be in (0, 1]."""
    t = np.asarray(transmittance_at_thickness, dtype=np.float64)
    if not (np.isfinite(thickness_mm) and thickness_mm > 0):
        raise ValueError(f"thickness: {thickness_mm!r} mm is not above 0")
    if not np.all(np.isfinite(t)) or np.any(t <= 0.0) or np.any(t > 1.0):
        raise ValueError("transmittance: every value must be above 0 and at most 1")
    return -np.log(t) / float(thickness_mm)


# ---------------------------------------------------------------------------------------------
# Reflector metals


@dataclass(frozen=True)
class LorentzDrude:
    """Rakić et al. (1998) Lorentz–Drude permittivity: energies in eV."""

    plasma_ev: float
    f0: float
    gamma0_ev: float
    oscillators: tuple[tuple[float, float, float], ...]  # (f_j, ω_j eV, Γ_j eV)

    def permittivity(self, wavelengths_nm: np.ndarray) -> np.ndarray:
        # photon energy in eV: hc = 1239.84193 eV nm
        w = 1239.84193 / np.asarray(wavelengths_nm, dtype=np.float64)
        wp2 = self.plasma_ev ** 2
        eps = 1.0 - self.f0 * wp2 / (w * (w + 1j * self.gamma0_ev))
        for f, wj, gj in self.oscillators:
            eps = eps + f * wp2 / (wj * wj - w * w - 1j * w * gj)
        return eps


# Rakić et al., Appl. Opt. 37:5271 (1998), Table 1 (Lorentz–Drude), as in NanoComp/meep python/materials.py
RAKIC_1998 = {
    "aluminium": LorentzDrude(14.98, 0.523, 0.047, ((0.227, 0.162, 0.333), (0.050, 1.544, 0.312),
                                                     (0.166, 1.808, 1.351), (0.030, 3.473, 3.382))),
    "silver": LorentzDrude(9.01, 0.845, 0.048, ((0.065, 0.816, 3.886), (0.124, 4.481, 0.452),
                                                 (0.011, 8.185, 0.065), (0.840, 9.083, 0.916))),
}


def normal_reflectance(n_complex: np.ndarray, n_outside: float = 1.0) -> np.ndarray:
    """Fresnel reflectance at normal incidence from a medium of index ``n_outside``: |(N−n)/(N+n)|²."""
    r = (n_complex - n_outside) / (n_complex + n_outside)
    return np.abs(r) ** 2


@functools.cache
def mirror_reflectance(metal: str) -> Spectrum:
    """Normal-incidence reflectance of bare ``aluminium`` or ``silver`` in air, 360–830 nm at 1 nm."""
    if metal not in RAKIC_1998:
        raise ValueError(f"mirror finish: {metal!r} is not one of {', '.join(sorted(RAKIC_1998))}")
    lam = np.arange(360.0, 831.0)
    n = np.sqrt(RAKIC_1998[metal].permittivity(lam))
    n = np.where(n.imag < 0, -n, n)  # the root with k ≥ 0 (absorbing)
    return Spectrum(lam, normal_reflectance(n), f"{metal} mirror")


MIRRORS = ("aluminium", "silver")


# ---------------------------------------------------------------------------------------------
# Smits (1999) RGB → reflectance, and its illuminant variant

SMITS_BASES = ("white", "cyan", "magenta", "yellow", "red", "green", "blue")


def smits_basis() -> tuple[np.ndarray, np.ndarray]:
    """(wavelengths nm (10,), basis reflectances (10, 7) in the order of ``SMITS_BASES``)."""
    return table("smits1999.csv")


def smits_weights(rgb: np.ndarray) -> np.ndarray:
    """(..., 7) weights of the Smits bases for linear RGB (..., 3) (negative components read as 0).

    Smits (1999) §3: the smallest component times white, the middle minus the smallest times the
    secondary of the two larger, the largest minus the middle times the largest's primary."""
    c = np.maximum(np.asarray(rgb, dtype=np.float64), 0.0)
    if c.shape[-1:] != (3,):
        raise ValueError(f"RGB: expected (..., 3) values, got shape {c.shape}")
    r, g, b = c[..., 0], c[..., 1], c[..., 2]
    w = np.zeros(c.shape[:-1] + (7,))
    white, cyan, magenta, yellow, red, green, blue = range(7)
    red_least = (r <= g) & (r <= b)
    green_least = ~red_least & (g <= r) & (g <= b)
    blue_least = ~red_least & ~green_least
    # red smallest: white·r, cyan·(min(g, b) − r), then blue or green for the rest
    m = red_least
    w[..., white] += np.where(m, r, 0)
    w[..., cyan] += np.where(m, np.minimum(g, b) - r, 0)
    w[..., blue] += np.where(m & (g <= b), b - g, 0)
    w[..., green] += np.where(m & (g > b), g - b, 0)
    m = green_least
    w[..., white] += np.where(m, g, 0)
    w[..., magenta] += np.where(m, np.minimum(r, b) - g, 0)
    w[..., blue] += np.where(m & (r <= b), b - r, 0)
    w[..., red] += np.where(m & (r > b), r - b, 0)
    m = blue_least
    w[..., white] += np.where(m, b, 0)
    w[..., yellow] += np.where(m, np.minimum(r, g) - b, 0)
    w[..., green] += np.where(m & (r <= g), g - r, 0)
    w[..., red] += np.where(m & (r > g), r - g, 0)
    return w


@functools.lru_cache(maxsize=32)
def _basis_band_means(bands: Bands, illuminant: bool) -> np.ndarray:
    wavelengths, basis = smits_basis()
    if not illuminant:
        return bands.average(wavelengths, basis).T  # (7, K)
    d65 = illuminant_d65()  # the white of Rec.709
    x = fine_grid(wavelengths, d65.wavelengths_nm)
    lit = np.stack([np.interp(x, wavelengths, basis[:, j]) for j in range(7)], axis=1) * d65.at(x)[:, None]
    means = bands.average(x, lit).T  # (7, K)
    # RGB (1, 1, 1) (the white basis alone) has luminance exactly 1 cd/m² in these bands
    return means / float(means[0] @ luminance_weights(bands))


def illuminant_basis(bands: Bands) -> np.ndarray:
    """(7, K): the band means of Smits's seven basis spectra times D65, as ``rgb_to_illuminant``
    weights them (``smits_weights(rgb) @ illuminant_basis(bands)`` is ``rgb_to_illuminant``)."""
    return _basis_band_means(bands, True)


def rgb_to_reflectance(rgb: np.ndarray, bands: Bands) -> np.ndarray:
    """(..., K) band-mean reflectance of body paint given as linear Rec.709 RGB (..., 3) (Smits 1999)."""
    return smits_weights(rgb) @ _basis_band_means(bands, False)


def rgb_to_illuminant(rgb: np.ndarray, bands: Bands) -> np.ndarray:
    """(..., K) band-mean spectral radiance of light given as linear Rec.709 RGB (..., 3).

    The Smits reflectance times D65, scaled so that RGB (1, 1, 1) has luminance 1 cd/m² in ``bands``
    exactly (at any K); times the cd/m² a pixel value of 1 stands for (``daylight.
    environment_scale_for_luminance`` or ``..._for_illuminance``) it is W/(m² sr nm)."""
    return smits_weights(rgb) @ _basis_band_means(bands, True)


def reflectance_spectrum(rgb: tuple[float, float, float]) -> Spectrum:
    """The Smits reflectance of one RGB as a curve at the 10 basis wavelengths (for tables and plots)."""
    wavelengths, basis = smits_basis()
    return Spectrum(wavelengths, basis @ smits_weights(np.asarray(rgb, dtype=np.float64)), f"Smits RGB {tuple(rgb)}")

"""The photometric mode (docs/photometric.md): a scene's light in lm, lx and cd/m², its plastics,
filters, finishes and paint, as values per wavelength band for the engine to carry.

The engine works on K bands instead of R, G, B (``Lighting.channels``); every value here is a band
mean: spectral radiance in W/(m² sr nm), spectral irradiance in W/(m² nm), reflectances and
transmittances. A ray carries its attenuation deferred (``Throughput``: Fresnel at a few wavelength
nodes, lengths through absorbing materials, reflections off the finish), expanded to the K bands
only where light is found (a leaf), whose bands are turned to CIE XYZ with Y in cd/m² (``to_xyz``)
as they are added to a pass (``Band.add``): the render's image and passes are XYZ.

What differs from the paper's model, surface by surface:

- bulb: a Lambertian sphere of flux Φ, radiance Φ / (4π² r²) with its spectrum's shape
  (``photometry.sources.bulb_spectral_radiance``), 0 when off;
- LED dies (in place of the bulb): flat, of area A and flux Φ each, radiance Φ / (π A) head-on with
  their spectrum's shape times the far-field file's f(θ, φ) (``photometry.far_field``; 1 when
  Lambertian); the reflector's glow has no LED term (docs/photometric.md);
- lens and prism plate: Fresnel per band and per polarisation (the rays carry their s-polarised
  share, ``Rays.k_s``) with n(λ) from the material's n_d and Abbe number; the rays' directions
  follow n_d (dispersion in Fresnel only: the measured difference on the cut lenses is in
  docs/photometric.md); absorption per band from the filter's internal transmittance at its
  thickness (Beer–Lambert);
- reflector: no appearance constant; its finish's spectral reflectance ρ(λ) split into a mirror
  share (1 − s) and a glow share s spread by the normalised Blinn lobe (n + 8)/(8π) cos^n β
  over the bulb's irradiance (``surfaces.bulb_irradiance``) and the sun's (phantom light);
- body paint: the Smits (1999) reflectance of its RGB, Lambertian, with the paper's highlight
  weight w on the normalised lobe; no ambient term;
- socket, side wall and housing: unlit (they end a path with 0; their light is not modelled);
- sun: CIE daylight 5500 K at ``light.illuminance_lux`` on a surface facing it;
- surroundings: the environment image as light (Smits illuminant spectra of its pixels) scaled to
  its stated illuminance or mean luminance; without one, black.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, replace

import numpy as np

from ..photometry import daylight, far_field, materials, sources
from ..photometry.bands import VISIBLE_NM, Bands
from ..photometry.cie import xyz_matrix
from ..photometry.spectrum import Spectrum
from ..scene.led_array import LedArray, uses_leds
from ..scene.reading import SceneError
from . import optics
from .lamp_table import LampTable

# The bands carried: K uniform bands over 380–780 nm. Chosen by measurement against 81 bands (5 nm)
# on every photometric preset (benchmarks/bench_photometric_bands.py, tests/photometry/
# test_band_convergence.py, docs/photometric.md): the red stop and tail lamps (illuminant A through a
# red cut-on) need the most; at 96 px their lit lens's xy is 0.0041 off at K = 16, 0.00099 at 32,
# 0.00057 at 40 (10 nm), and its luminance 1.9 %, 0.39 %, 0.22 %. 32 sits on the xy limit (0.001);
# 40 keeps a margin (xy at 57 % of it, luminance at 44 % of 0.5 %). A scene with narrower spectra (an
# LED line) is traced on these bands refined where its light is (``spectral_bands.scene_bands``).
DEFAULT_BANDS = 40
FINISHES = {"aluminised": "aluminium", "silvered": "silver"}
MIN_TRANSMITTANCE = 1e-9  # a measured filter's 0 read as this, so that its absorption stays finite


def bands_of(k: int | None) -> Bands:
    return Bands.uniform(int(k or DEFAULT_BANDS))


@dataclass(frozen=True)
class PhotometricSun:
    """The sun of the photometric mode: a direction and its spectral irradiance on a surface facing
    it (K,), W/(m² nm); it lights Lambertian paint, E ρ cos θ / π, and adds the highlight w of a
    normalised Blinn lobe, w (n + 8)/(8π) cos^n β E cos θ."""

    direction: np.ndarray
    light: np.ndarray  # E(λ) per band
    illuminance: float  # lx
    cosine_weighted = True  # the phantom light takes the cosine toward the sun (``sunlight._scattered``)

    @property
    def strength(self) -> float:
        return self.illuminance

    def shade(self, normal: np.ndarray, view: np.ndarray, diffuse: np.ndarray, specular, shininess) -> np.ndarray:
        L = self.direction
        cos_theta = np.maximum(0.0, normal @ L if normal.ndim == 1 else
                               normal[:, 0] * L[0] + normal[:, 1] * L[1] + normal[:, 2] * L[2])
        cos_beta = np.maximum(0.0, optics.dot(normal, optics.normalize(view + L)))
        shininess = np.asarray(shininess, dtype=np.float64)
        lobe = np.asarray(specular) * (shininess + 8.0) / (8.0 * math.pi) * np.power(cos_beta, shininess)
        out = np.broadcast_to(diffuse, (len(normal), len(self.light))) * (cos_theta / math.pi)[:, None]
        out = out + (lobe * cos_theta)[:, None]
        return out * self.light


@dataclass(frozen=True)
class Photometric:
    """What a photometric render needs beyond the paper's: the bands, XYZ per band, the paint,
    and the factor from the environment image's pixel values to cd/m²."""

    bands: Bands
    to_xyz: np.ndarray  # (K, 3): band-mean radiance → XYZ, Y in cd/m² (``photometry.cie.xyz_matrix``)
    sun: PhotometricSun
    light_to_xyz: np.ndarray  # (7, 3): Smits's illuminant basis (``materials.illuminant_basis``) to XYZ

    @property
    def channels(self) -> int:
        return self.bands.k

    def light(self, rgb: np.ndarray) -> np.ndarray:
        """Band values (N, K) of light given as linear Rec.709 (N, 3) in cd/m² per unit (an
        environment's radiance or irradiance, its scale applied): Smits spectra times D65."""
        return materials.rgb_to_illuminant(rgb, self.bands)

    def light_xyz(self, rgb: np.ndarray) -> np.ndarray:
        """``light(rgb) @ to_xyz`` without the bands: X, Y, Z (N, 3) of light seen as it is (an eye
        ray that sees the world; no attenuation to apply per band)."""
        return materials.smits_weights(rgb) @ self.light_to_xyz

    def reflectance(self, rgb) -> np.ndarray:
        """Band reflectances (K,) or (N, K) of paint given as linear RGB (Smits 1999)."""
        return materials.rgb_to_reflectance(np.asarray(rgb, dtype=np.float64), self.bands)


def setup(scene: dict, bands: Bands, sun_direction: np.ndarray) -> Photometric:
    """The photometric light of a normalised scene on ``bands`` (``spectral_bands.render_bands``)."""
    lux = float(scene["light"]["illuminance_lux"])
    sun = PhotometricSun(np.asarray(sun_direction, dtype=np.float64), daylight.sun_spectral_irradiance(lux, bands),
                         lux)
    to_xyz = np.ascontiguousarray(xyz_matrix(bands))
    return Photometric(bands, to_xyz, sun, materials.illuminant_basis(bands) @ to_xyz)


def environment_scale(scene: dict, pixels: np.ndarray) -> float:
    """cd/m² per unit of the environment image's pixel values, from its stated illuminance or mean
    luminance (``photometry.daylight``)."""
    env = scene["environment"]
    try:
        if env["scale_by"] == "luminance":
            return daylight.environment_scale_for_luminance(pixels, env["luminance_cd_m2"])
        return daylight.environment_scale_for_illuminance(pixels, env["illuminance_lux"])
    except ValueError as e:
        raise SceneError("environment.scale_by", f"{e}; allowed an image with light in it") from None


# ---------------------------------------------------------------------------------------------
# Lamps


def bulb_spectrum(bulb: dict, where: str) -> tuple[float, Spectrum]:
    """(flux in lm, spectrum) of a normalised bulb section: its named type's, or its own."""
    if bulb["type"] != "custom":
        kind = sources.BULB_TYPES[bulb["type"]]
        if bulb["state"] not in kind.states:
            raise SceneError(f"{where}.state", f'"{bulb["state"]}" is not a filament of a {bulb["type"]} bulb; '
                                               f"allowed one of {', '.join(kind.states)}")
        return kind.states[bulb["state"]].flux_lm, sources.named_spectrum(kind.spectrum)
    if bulb["spectrum"] == "led":
        return bulb["flux_lm"], sources.led(bulb["led_peak_nm"], bulb["led_width_nm"])
    if bulb["spectrum"] == "file":
        return bulb["flux_lm"], _read_curve(bulb["spectrum_file"], f"{where}.spectrum_file")
    return bulb["flux_lm"], sources.named_spectrum(bulb["spectrum"])


def _spectrum_field(bulb: dict, where: str) -> str:
    """The field that chose a bulb's spectrum, for a message."""
    if bulb["type"] != "custom":
        return f"{where}.type"
    return f"{where}.{ {'led': 'led_peak_nm', 'file': 'spectrum_file'}.get(bulb['spectrum'], 'spectrum')}"


def bulb_radiance(bulb: dict, bands: Bands, where: str = "bulb") -> np.ndarray:
    """(K,) spectral radiance of a bulb, W/(m² sr nm); 0 when it is off. A spectrum without visible
    light or a radius whose luminance is not finite is a ``SceneError`` naming the field."""
    if not bulb["on"]:
        return np.zeros(bands.k)
    flux, spectrum = bulb_spectrum(bulb, where)
    try:
        shape = sources.spectral_shape(spectrum, bands)
    except ValueError as e:
        detail = (f"an LED of {bulb['led_peak_nm']:g} nm and half width {bulb['led_width_nm']:g} nm"
                  if bulb["type"] == "custom" and bulb["spectrum"] == "led" else str(e).split(":")[0])
        raise SceneError(_spectrum_field(bulb, where), f"{detail} gives no usable light in {VISIBLE_NM[0]:g} to "
                                                       f"{VISIBLE_NM[1]:g} nm ({str(e).split(': ', 1)[-1]}); "
                                                       "allowed a spectrum with visible light") from None
    try:
        luminance = sources.bulb_luminance(flux, bulb["radius"])
    except ValueError:
        raise SceneError(f"{where}.radius", f"{bulb['radius']:g} mm is too small: the bulb's luminance "
                                            f"Φ/(4π² r²) at {flux:g} lm is not a finite number; allowed "
                                            f"{MIN_BULB_RADIUS_MM:g} mm or more") from None
    radiance = luminance * shape
    if not np.isfinite(radiance).all():
        raise SceneError(f"{where}.radius", f"{bulb['radius']:g} mm is too small: the bulb's radiance at {flux:g} lm "
                                            f"is not a finite number; allowed {MIN_BULB_RADIUS_MM:g} mm or more")
    return radiance


MIN_BULB_RADIUS_MM = 1e-3  # what the messages offer: 1 µm, far above where Φ/(4π² r²) overflows


def check_lamps(scene: dict, k: int | None = None, curves: bool = True) -> None:
    """Everything a photometric render computes from each lamp's spectra, computed now on ``k`` bands
    (None: the render's default) and checked, so that a scene that passes ``validate`` or the panel
    renders (issue 33): every bulb's radiance as if lit (visible light, a finite luminance for its
    radius), every filter's band transmittance (0 to 1, finite) and absorption. Measured curves are
    read by the full paths ``scene.beside.with_spectrum_files`` gave; ``curves`` False leaves out what
    needs them (Blender's panel, which checks at every redraw without the files). Raises ``SceneError``."""
    if scene.get("light_model", "paper") != "photometric":
        return
    bands = bands_of(k)
    for i, lamp in enumerate(scene["lamps"]):
        where = f"lamps[{i}]"
        parts = [("lens", lamp["lens"])]
        if lamp.get("collection", "reflector") == "prism_plate":
            parts.append(("prism_plate", lamp["prism_plate"]))
        for name, part in parts:
            if not curves and part["filter"] == "file":
                continue
            mu = absorption(part, bands, f"{where}.{name}")
            if not np.isfinite(mu).all():
                raise SceneError(f"{where}.{name}.filter", "its absorption is not a finite number; allowed "
                                                           "transmittances above 0")
        bulb = lamp["bulb"]
        if curves or not (bulb["type"] == "custom" and bulb["spectrum"] == "file"):
            bulb_radiance({**bulb, "on": True}, bands, f"{where}.bulb")
        if uses_leds(lamp):  # the dies' radiance as if lit, and their far field
            if curves or lamp["led"]["spectrum"] != "file":
                led_radiance({**lamp, "bulb": {**bulb, "on": True}}, bands, where)
            if curves:
                led_pattern(lamp, where)


def led_spectrum(led: dict, where: str) -> Spectrum:
    """The spectrum of a normalised ``led`` section's dies."""
    if led["spectrum"] == "led":
        return sources.led(led["led_peak_nm"], led["led_width_nm"])
    if led["spectrum"] == "file":
        return _read_curve(led["spectrum_file"], f"{where}.spectrum_file")
    return sources.named_spectrum(led["spectrum"])


def led_radiance(lamp: dict, bands: Bands, where: str) -> np.ndarray:
    """(K,) spectral radiance of one of a lamp's LED dies seen head-on if it were Lambertian:
    L = Φ / (π A) with its spectrum's shape (``photometry.sources.die_spectral_radiance``); 0 when the
    lamp is off or lit by its bulb."""
    if not (uses_leds(lamp) and lamp["bulb"]["on"]):
        return np.zeros(bands.k)
    led = lamp["led"]
    area = LedArray.of(led).die_area_mm2
    return sources.die_spectral_radiance(led["flux_lm"], led_spectrum(led, f"{where}.led"), area, bands)


def led_pattern(lamp: dict, where: str) -> far_field.Pattern:
    """The dies' luminance relative to a Lambertian die's (``photometry.far_field``): 1 for a
    Lambertian die, from the far-field file (its full path, ``scene.beside``) otherwise."""
    led = lamp.get("led")
    if not uses_leds(lamp) or led["distribution"] == "lambertian":
        return far_field.Pattern.lambertian()
    path, field = led["far_field_file"], f"{where}.led.far_field_file"
    if not os.path.isabs(path):
        raise SceneError(field, f'"{path}" was not found beside the document; allowed an .ies or .ldt file beside '
                                "the JSON, given when the document is loaded from its file")
    try:
        return far_field.Pattern.of(far_field.read_far_field(path))
    except ValueError as e:
        raise SceneError(field, str(e)) from None


def index_of(part: dict) -> tuple[float, float]:
    """(n_d, Abbe number) of a lens or prism plate (its material; custom: its ior and abbe)."""
    if part["material"] == "custom":
        return float(part["ior"]), float(part["abbe"])
    material = materials.MATERIALS[part["material"]]
    return material.n_d, material.abbe


def band_index(part: dict, bands: Bands) -> np.ndarray:
    """(K,) refractive index of a lens or prism plate at the bands' centres."""
    return materials.refractive_index(*index_of(part), bands.centres_nm)


def filter_curve(part: dict, where: str) -> Spectrum:
    """A part's filter: its internal transmittance at its ``filter_thickness`` per wavelength."""
    kind = part["filter"]
    if kind == "file":
        curve = _read_curve(part["filter_file"], f"{where}.filter_file")
        if float(curve.values.max()) > 1.0:
            raise SceneError(f"{where}.filter_file", "holds transmittances above 1; allowed internal "
                                                     "transmittances from 0 to 1")
        return curve
    if kind == "custom":
        low, high = part["filter_range"]
        return materials.cut_on_filter(part["filter_edge_nm"], part["filter_slope_nm"], low, high).spectrum()
    return materials.FILTERS[kind].spectrum()


def filter_transmittance(part: dict, bands: Bands, where: str) -> np.ndarray:
    """(K,) band-mean internal transmittance of a part's filter at its ``filter_thickness``."""
    return np.clip(filter_curve(part, where).band_means(bands), MIN_TRANSMITTANCE, 1.0)


def absorption(part: dict, bands: Bands, where: str) -> np.ndarray:
    """(K,) Beer–Lambert coefficient per mm: the filter's band transmittance at its thickness."""
    return materials.absorption_per_mm(filter_transmittance(part, bands, where), part["filter_thickness"])


def finish_reflectance(reflector: dict, bands: Bands) -> np.ndarray:
    """(K,) band-mean normal-incidence reflectance of the reflector's metal coat."""
    return materials.mirror_reflectance(FINISHES[reflector["finish"]]).band_means(bands)


# The wavelength nodes Fresnel is evaluated at along a branch (``Throughput``): Fresnel's factors
# depend on the wavelength only through n(λ), smooth in it, and are interpolated to the K bands at
# a leaf. Chosen by measurement (docs/photometric.md, "Speed"): every photometric preset's lit lens
# against Fresnel per band.
FRESNEL_NODES = 8


@dataclass(frozen=True)
class Throughput:
    """A branch's accumulated attenuation per band, kept deferred (docs/photometric.md, "Speed"):

        k(λ) = F(λ) · exp(−α_lens(λ) d_lens − α_plate(λ) d_plate) · ρ(λ)^m

    F, the product of the Fresnel factors (s and p shares, each surface's reflectance or
    transmittance, and the reflector's mirror share 1 − s), depends on λ only through n(λ), smooth
    in it: the rays carry it at a few wavelength nodes (``Rays.k``, ``k_s``: (N, J)), equally
    spaced in 1/λ² (n is linear in 1/λ², two-term Cauchy), and it is interpolated piecewise
    linearly in 1/λ² to the K bands at a leaf (``to_bands``). The rest is carried as three numbers a
    ray (``Rays.travelled``): mm through the lens's material, mm through the plate's, and
    reflections off the reflector's finish ρ. A leaf expands them to K bands (``bands``), so the
    per-band work is done once per leaf, not at every surface.

    The cut-off (a branch ends when every band is below it) takes an upper bound of max_λ k(λ):
    max over nodes of F (the interpolation weights are convex: no band exceeds the largest node)
    times exp(−min α_lens d_lens − min α_plate d_plate) · (max ρ)^m (``reach``); branches whose
    bound is near the cut-off are tested band by band (``rays.alive``)."""

    # The columns of ``Rays.travelled``: what a ray has crossed and met so far.
    LENS_MM = 0  # mm through the lens's material
    PLATE_MM = 1  # mm through the prism plate's or the light guide's
    REFLECTIONS = 2  # reflections off the reflector's finish
    TRAVELLED = 3

    nodes_nm: np.ndarray  # (J,)
    to_bands: np.ndarray  # (J, K) float32: node values to band values, each band's column summing to 1
    ior_nodes: np.ndarray  # (L, J) lens index at the nodes, per lamp (Fresnel)
    plate_ior_nodes: np.ndarray  # (L, J)
    exponents: np.ndarray  # (3 L, K) float32: per lamp the rows −α_lens(λ), −α_plate(λ), ln ρ(λ)
    bounds: np.ndarray  # (L, 3): per lamp max over bands of each row of ``exponents``

    @classmethod
    def of(cls, lamps: LampTable, bands: Bands, nodes: int | None = None) -> Throughput:
        rows = np.stack([-lamps.absorption, -lamps.plate_absorption,
                         np.log(np.maximum(lamps.reflector_bands, MIN_TRANSMITTANCE))], axis=1)  # (L, 3, K)
        exponents, bounds = rows.reshape(-1, bands.k).astype(np.float32), rows.max(axis=2)  # bands(): float32
        nodes = min(max(2, int(nodes or FRESNEL_NODES)), bands.k)
        if nodes == bands.k:  # a node at each band's centre: Fresnel per band, exactly
            return cls(bands.centres_nm, np.eye(bands.k, dtype=np.float32), lamps.ior_bands, lamps.plate_ior_bands,
                       exponents, bounds)
        u_bands = 1.0 / bands.centres_nm**2
        u_nodes = np.linspace(u_bands[0], u_bands[-1], nodes)  # blue to red
        nodes_nm = 1.0 / np.sqrt(u_nodes)
        to_bands = np.zeros((nodes, bands.k))
        for k, u in enumerate(u_bands):  # piecewise linear in 1/λ² between the two nodes around u
            i = min(nodes - 2, int(np.searchsorted(-u_nodes, -u, side="right")) - 1)
            t = (u - u_nodes[i]) / (u_nodes[i + 1] - u_nodes[i])
            to_bands[i, k] += 1.0 - t
            to_bands[i + 1, k] += t
        ior_nodes = np.stack([_index_at(row, nodes_nm, bands) for row in lamps.ior_bands])
        plate_ior_nodes = np.stack([_index_at(row, nodes_nm, bands) for row in lamps.plate_ior_bands])
        return cls(nodes_nm, to_bands.astype(np.float32), ior_nodes, plate_ior_nodes, exponents, bounds)

    def reach(self, travelled: np.ndarray, lamp: np.ndarray) -> np.ndarray:
        """(N,) upper bound over the bands of exp(−α_lens d_lens − α_plate d_plate) ρ^m."""
        bound = self.bounds.take(lamp, axis=0)
        bound *= travelled
        return np.exp(bound[:, 0] + bound[:, 1] + bound[:, 2])  # numpy sums short rows slowly

    def bands(self, k: np.ndarray, travelled: np.ndarray, lamp: np.ndarray) -> np.ndarray:
        """(N, K) accumulated attenuation per band of branches whose Fresnel product at the nodes
        is ``k`` (N, J), having ``travelled`` (N, 3), in lamps ``lamp``. In float32 (relative error
        below 1e-5 a band: the exponent's rounding times its size; twice as fast as float64, the
        leaves' matrix products and exponentials being the mode's largest per-band work)."""
        out = k.astype(np.float32) @ self.to_bands
        n, lamps = len(k), len(self.bounds)
        size = self.TRAVELLED
        spread = np.zeros((n, size * lamps), np.float32)  # each ray's three numbers in its lamp's block of rows
        rows = np.arange(n)
        for j in range(size):
            spread[rows, size * lamp + j] = travelled[:, j]
        exponent = spread @ self.exponents
        out *= np.exp(exponent, out=exponent)
        return out


def _index_at(band_index: np.ndarray, nodes_nm: np.ndarray, bands: Bands) -> np.ndarray:
    """A material's n at the nodes from its n at the band centres: n is linear in 1/λ² (two-term
    Cauchy, ``materials.refractive_index``), so the line through the first and last band's values."""
    u = 1.0 / bands.centres_nm**2
    slope = (band_index[-1] - band_index[0]) / (u[-1] - u[0])
    return band_index[0] + slope * (1.0 / nodes_nm**2 - u[0])


def photometric_lamps(table: LampTable, scene: dict, bands: Bands) -> LampTable:
    """The paper's lamp table with the photometric values per lamp and band: bulb radiance, the
    lens's and plate's n_d (directions), n(λ) (Fresnel) and absorption, the reflector's finish and
    its mirror and glow shares; no appearance colours (module docstring)."""
    k, n = bands.k, len(scene["lamps"])
    zeros = np.zeros((n, k))
    rows: dict[str, list] = {key: [] for key in ("ior", "ior_bands", "absorption", "plate_ior", "plate_ior_bands",
                                                  "plate_absorption", "bulb_radiance", "reflector_bands",
                                                  "reflectance", "scatter", "led_radiance")}
    patterns = []
    for i, lamp in enumerate(scene["lamps"]):
        where = f"lamps[{i}]"
        lens, refl = lamp["lens"], lamp["reflector"]
        rows["ior"].append(index_of(lens)[0])
        rows["ior_bands"].append(band_index(lens, bands))
        rows["absorption"].append(absorption(lens, bands, f"{where}.lens"))
        guide = lamp.get("light_guide", {})
        if lamp.get("collection", "reflector") == "prism_plate" or guide.get("enabled"):
            # a guide's rod is the lamp's second dielectric, as a plate is (``paths.IN_GUIDE``)
            plate, part = (guide, "light_guide") if guide.get("enabled") else (lamp["prism_plate"], "prism_plate")
            rows["plate_ior"].append(index_of(plate)[0])
            rows["plate_ior_bands"].append(band_index(plate, bands))
            rows["plate_absorption"].append(absorption(plate, bands, f"{where}.{part}"))
        else:
            rows["plate_ior"].append(1.0)
            rows["plate_ior_bands"].append(np.ones(k))
            rows["plate_absorption"].append(np.zeros(k))
        rows["bulb_radiance"].append(bulb_radiance(lamp["bulb"], bands, f"{where}.bulb")
                                      if not uses_leds(lamp) else np.zeros(k))
        rows["led_radiance"].append(led_radiance(lamp, bands, where))
        patterns.append(led_pattern(lamp, where))
        rows["reflector_bands"].append(finish_reflectance(refl, bands))
        share = refl["scatter_share"]
        rows["reflectance"].append(1.0 - share)
        # the glow's share on the normalised Blinn lobe (n + 8)/(8 pi) (Akenine-Moeller et al.,
        # Real-Time Rendering, 3rd ed. 2008, eq. 7.49)
        rows["scatter"].append(share * (refl["shininess"] + 8.0) / (8.0 * math.pi) if not uses_leds(lamp) else 0.0)
    values = {key: np.array(value, dtype=np.float64) for key, value in rows.items()}
    return replace(table, **values, led_patterns=tuple(patterns), wall_color=zeros, lens_diffuse=zeros,
                   reflector_color=zeros, socket_color=zeros, housing_color=zeros)


def _read_curve(path: str, where: str) -> Spectrum:
    """A measured curve by the full path the loader gave it (``scene.beside.with_spectrum_files``)."""
    if not os.path.isabs(path):
        raise SceneError(where, f'"{path}" was not found beside the document; allowed a .csv file beside the JSON, '
                                "given when the document is loaded from its file")
    try:
        return sources.from_csv(path)
    except ValueError as e:
        raise SceneError(where, str(e)) from None

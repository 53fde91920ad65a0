"""The photometric mode (docs/photometric.md): a scene's light in lm, lx and cd/m², its plastics,
filters, finishes and paint, as values per wavelength band for the engine to carry.

The engine carries K bands instead of R, G, B (``Lighting.channels``); every value here is a band
mean: spectral radiance in W/(m² sr nm), spectral irradiance in W/(m² nm), reflectances and
transmittances. The image is turned to CIE XYZ with Y in cd/m² band by band (``to_xyz``) before it
leaves a worker, so the render's image and passes are XYZ.

What differs from the paper's model, surface by surface:

- bulb: a Lambertian sphere of flux Φ, radiance Φ / (4π² r²) with its spectrum's shape
  (``photometry.sources.bulb_spectral_radiance``), 0 when off;
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

from ..images import display
from ..photometry import daylight, materials, output, sources
from ..photometry.bands import Bands
from ..photometry.cie import xyz_matrix
from ..photometry.spectrum import Spectrum
from ..scene.reading import SceneError
from . import optics
from .lamp_table import LampTable

# The bands carried: K uniform bands over 380–780 nm. Chosen by measurement against 81 bands (5 nm)
# on every photometric preset (benchmarks/bench_photometric_bands.py, tests/photometry/
# test_band_convergence.py, docs/photometric.md): the red stop and tail lamps (illuminant A through a
# red cut-on) need the most; at 96 px their lit lens's xy is 0.0041 off at K = 16, 0.00099 at 32,
# 0.00057 at 40 (10 nm), and its luminance 1.9 %, 0.39 %, 0.22 %. 32 sits on the xy limit (0.001);
# 40 keeps a margin (xy at 57 % of it, luminance at 44 % of 0.5 %).
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

    @property
    def channels(self) -> int:
        return self.bands.k

    def light(self, rgb: np.ndarray) -> np.ndarray:
        """Band values (N, K) of light given as linear Rec.709 (N, 3) in cd/m² per unit (an
        environment's radiance or irradiance, its scale applied): Smits spectra times D65."""
        return materials.rgb_to_illuminant(rgb, self.bands)

    def reflectance(self, rgb) -> np.ndarray:
        """Band reflectances (K,) or (N, K) of paint given as linear RGB (Smits 1999)."""
        return materials.rgb_to_reflectance(np.asarray(rgb, dtype=np.float64), self.bands)


def setup(scene: dict, k: int | None, sun_direction: np.ndarray) -> Photometric:
    """The photometric light of a normalised scene on ``k`` bands (None: ``DEFAULT_BANDS``)."""
    bands = bands_of(k)
    lux = float(scene["light"]["illuminance_lux"])
    sun = PhotometricSun(np.asarray(sun_direction, dtype=np.float64), daylight.sun_spectral_irradiance(lux, bands),
                         lux)
    return Photometric(bands, np.ascontiguousarray(xyz_matrix(bands)), sun)


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


def bulb_radiance(bulb: dict, bands: Bands, where: str = "bulb") -> np.ndarray:
    """(K,) spectral radiance of a bulb, W/(m² sr nm); 0 when it is off."""
    if not bulb["on"]:
        return np.zeros(bands.k)
    flux, spectrum = bulb_spectrum(bulb, where)
    return sources.bulb_spectral_radiance(flux, spectrum, bulb["radius"], bands)


def index_of(part: dict) -> tuple[float, float]:
    """(n_d, Abbe number) of a lens or prism plate (its material; custom: its ior and abbe)."""
    if part["material"] == "custom":
        return float(part["ior"]), float(part["abbe"])
    material = materials.MATERIALS[part["material"]]
    return material.n_d, material.abbe


def band_index(part: dict, bands: Bands) -> np.ndarray:
    """(K,) refractive index of a lens or prism plate at the bands' centres."""
    return materials.refractive_index(*index_of(part), bands.centres_nm)


def filter_transmittance(part: dict, bands: Bands, where: str) -> np.ndarray:
    """(K,) band-mean internal transmittance of a part's filter at its ``filter_thickness``."""
    kind = part["filter"]
    if kind == "file":
        curve = _read_curve(part["filter_file"], f"{where}.filter_file")
        if float(curve.values.max()) > 1.0:
            raise SceneError(f"{where}.filter_file", "holds transmittances above 1; allowed internal "
                                                     "transmittances from 0 to 1")
        return np.maximum(curve.band_means(bands), MIN_TRANSMITTANCE)
    if kind == "custom":
        low, high = part["filter_range"]
        curve = materials.cut_on_filter(part["filter_edge_nm"], part["filter_slope_nm"], low, high).spectrum()
    else:
        curve = materials.FILTERS[kind].spectrum()
    return np.clip(curve.band_means(bands), MIN_TRANSMITTANCE, 1.0)


def absorption(part: dict, bands: Bands, where: str) -> np.ndarray:
    """(K,) Beer–Lambert coefficient per mm: the filter's band transmittance at its thickness."""
    return materials.absorption_per_mm(filter_transmittance(part, bands, where), part["filter_thickness"])


def finish_reflectance(reflector: dict, bands: Bands) -> np.ndarray:
    """(K,) band-mean normal-incidence reflectance of the reflector's metal coat."""
    return materials.mirror_reflectance(FINISHES[reflector["finish"]]).band_means(bands)


def photometric_lamps(table: LampTable, scene: dict, bands: Bands) -> LampTable:
    """The paper's lamp table with the photometric values per lamp and band: bulb radiance, the
    lens's and plate's n_d (directions), n(λ) (Fresnel) and absorption, the reflector's finish and
    its mirror and glow shares; no appearance colours (module docstring)."""
    k, n = bands.k, len(scene["lamps"])
    zeros = np.zeros((n, k))
    rows: dict[str, list] = {key: [] for key in ("ior", "ior_bands", "absorption", "plate_ior", "plate_ior_bands",
                                                  "plate_absorption", "bulb_intensity", "reflector_bands",
                                                  "reflectance", "scatter")}
    for i, lamp in enumerate(scene["lamps"]):
        where = f"lamps[{i}]"
        lens, refl = lamp["lens"], lamp["reflector"]
        rows["ior"].append(index_of(lens)[0])
        rows["ior_bands"].append(band_index(lens, bands))
        rows["absorption"].append(absorption(lens, bands, f"{where}.lens"))
        if lamp.get("collection", "reflector") == "prism_plate":
            plate = lamp["prism_plate"]
            rows["plate_ior"].append(index_of(plate)[0])
            rows["plate_ior_bands"].append(band_index(plate, bands))
            rows["plate_absorption"].append(absorption(plate, bands, f"{where}.prism_plate"))
        else:
            rows["plate_ior"].append(1.0)
            rows["plate_ior_bands"].append(np.ones(k))
            rows["plate_absorption"].append(np.zeros(k))
        rows["bulb_intensity"].append(bulb_radiance(lamp["bulb"], bands, f"{where}.bulb"))
        rows["reflector_bands"].append(finish_reflectance(refl, bands))
        share = refl["scatter_share"]
        rows["reflectance"].append(1.0 - share)
        # the glow's share on the normalised Blinn lobe (n + 8)/(8 pi) (Akenine-Moeller et al.,
        # Real-Time Rendering, 3rd ed. 2008, eq. 7.49)
        rows["scatter"].append(share * (refl["shininess"] + 8.0) / (8.0 * math.pi))
    values = {key: np.array(value, dtype=np.float64) for key, value in rows.items()}
    return replace(table, **values, wall_color=zeros, lens_diffuse=zeros, reflector_color=zeros,
                   socket_color=zeros, housing_color=zeros)


def _read_curve(path: str, where: str) -> Spectrum:
    """A measured curve by the full path the loader gave it (``scene.beside.with_spectrum_files``)."""
    if not os.path.isabs(path):
        raise SceneError(where, f'"{path}" was not found beside the document; allowed a .csv file beside the JSON, '
                                "given when the document is loaded from its file")
    try:
        return sources.from_csv(path)
    except ValueError as e:
        raise SceneError(where, str(e)) from None


# ---------------------------------------------------------------------------------------------
# Display


def exposure_ev100(XYZ: np.ndarray | list[np.ndarray], scene: dict) -> float:
    """The camera's EV100 for a photometric image (or several shown together, one exposure): the
    scene's ``camera.ev100``, or with ``camera.exposure`` "auto" the project's automatic exposure
    (``images.display.auto_exposure``: the lit lens's bright end just below the view's shoulder)
    expressed as an EV100."""
    camera = scene["camera"]
    if camera.get("exposure", "auto") == "ev100":
        return float(camera["ev100"])
    images = XYZ if isinstance(XYZ, list) else [XYZ]
    stops = display.auto_exposure([output.scene_linear_rec709(image, 0.0) for image in images])
    return float(np.clip(-stops, -20.0, 30.0))  # 2^stops / (1.2 · 2^0) = 1 / (1.2 · 2^EV100)


def display_linear(XYZ: np.ndarray, ev100: float) -> np.ndarray:
    """Blender's scene-linear (linear Rec.709, float32) of an XYZ image in cd/m² at camera ``ev100``:
    what the view transform takes at exposure 0 (out-of-gamut colours unclipped)."""
    return output.scene_linear_rec709(XYZ, ev100).astype(np.float32)

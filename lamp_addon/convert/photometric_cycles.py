"""Cycles values for a photometric design: the same light in Blender's radiometric units.

Blender's lights are radiometric. The Blender manual (Shader Nodes > Emission) says point, spot and
area lights are given in watts, sun lights in watts per square metre, and that a material's Emission
of Strength 1 shows its Color exactly (Strength × Color is the radiance the camera sees). Cycles'
source agrees: Blender's sync sets a light's strength to color × energy × 2^exposure
(intern/cycles/blender/light.cpp, ``sync_light``), and ``LightManager::device_update_lights``
(src/scene/light.cpp) turns a point light's radiant flux P into the radiance of its sphere of radius r
with eval_fac = 1 / (4π r²) × 1/π, L = P / (4π² r²), the Lambertian sphere bulb of the tracer, and
uses a sun's (angle 0) strength as its irradiance (eval_fac 1). Cycles carries three colour
channels, so each light becomes a power (or radiance) and a colour that carries its spectrum's
luminous efficiency:

- a source of luminous flux Φ (lm) with spectrum S radiates Φ_e = Φ / K_r watts, where
  K_r = 683 lm/W × ∫V·S dλ / ∫S dλ is its luminous efficacy of radiation over 380–780 nm, the range
  the tracer carries (``photometry.cie.luminous_efficacy``);
- its colour is C = RGB(S) / Y(S) × K_r / 683: linear Rec.709 of the spectrum at unit luminance
  (clipped into the gamut at its own luminance where it lies outside: amber and red LEDs), times its
  luminous efficiency. Then Cycles' pixel values times 683 lm/W are linear Rec.709 of the
  XYZ the tracer gives in cd/m², whatever the spectrum: one film exposure, 683 / (1.2 · 2^EV100),
  shows Cycles at the tracer's EV100 (``film_exposure``);
- the bulb (a Lambertian sphere of radius r) is an Emission of radiance L_e = Φ_e / (4π² r²)
  W/(m² sr) and colour C, so Strength × Color = L_e × C: what a Blender point light of radius r,
  power Φ_e W and colour C shows;
- the sun is a Sun light of strength E_e = E_v / K_r W/m² (E_v its illuminance in lx, its spectrum
  CIE daylight at 5500 K) and colour C;
- a lens or prism plate is glass of the material's n_d (a plate's rings keep the shape its own ior
  gives them, as in the tracer), absorbing per channel the RGB of its filter's
  transmittance under the lamp's own bulb, T_c = RGB_c(S·T) / RGB_c(S), as −ln(T_c) / thickness per
  mm (Beer–Lambert at the filter's thickness); a colour outside Rec.709 (legal red) is clipped into it
  at its own luminance: Cycles cannot carry the colour;
- the reflector mirrors and glows with its finish's reflectance under the bulb (its luminance
  share: aluminium and silver are near-neutral), split by the glow share; no appearance constant;
- the environment image's Background strength is the tracer's scale (cd/m² per pixel unit) / 683;
- what the tracer leaves unlit (socket, side wall, housing, the lens's own diffuse colour, the
  background, the ambient term) is black.

``equivalent`` writes these into the paper's fields of a scene, which ``design.materials`` turns
into node values as it always does, so the Cycles objects of a photometric design carry them.
"""

from __future__ import annotations

import copy
import math

import numpy as np

from ...core_tracer.photometry import cie, daylight, materials
from ...core_tracer.photometry.spectrum import Spectrum
from ...core_tracer.raytrace import spectral
from . import cycles

MIN_TRANSMITTANCE = 1e-6  # a channel the filter blocks: absorption stays finite
BLACK = [0.0, 0.0, 0.0]


def film_exposure(ev100: float) -> float:
    """Cycles' Film exposure showing its radiometric image at camera ``ev100``: 683 / (1.2 · 2^EV100)
    (``photometry.output.exposure_scale`` of luminance 683 × pixel)."""
    return cie.KM / (1.2 * 2.0 ** float(ev100))


def unit_rgb(spectrum: Spectrum) -> np.ndarray:
    """Linear Rec.709 of ``spectrum`` at luminance 1 (unclipped)."""
    xyz = cie.spectrum_xyz(spectrum)
    return cie.xyz_to_linear_rec709(xyz / xyz[1])


def in_gamut(rgb: np.ndarray) -> np.ndarray:
    """Linear Rec.709 clipped into the gamut at its own luminance (an amber or red LED's negative
    green or blue): what Cycles' channels can carry, as bright as the light."""
    rgb = np.asarray(rgb, dtype=np.float64)
    if rgb.min() >= 0:
        return rgb
    weights = np.asarray(daylight.REC709_LUMINANCE)
    clipped = np.maximum(rgb, 0.0)
    return clipped * float(rgb @ weights) / float(clipped @ weights)


def light_color(spectrum: Spectrum) -> np.ndarray:
    """C = RGB(S) / Y(S) × K_r / 683: the colour of a Blender light of spectrum S (module doc),
    ``in_gamut``."""
    return in_gamut(unit_rgb(spectrum)) * cie.luminous_efficacy(spectrum) / cie.KM


def bulb_light(bulb: dict, where: str = "bulb") -> dict:
    """A bulb's Cycles values: ``flux_lm``, ``efficacy_lm_per_w`` (K_r), ``power_w`` (Φ_e),
    ``radiance`` (L_e, W/(m² sr)) and ``color`` (C)."""
    flux, spectrum = spectral.bulb_spectrum(bulb, where)
    efficacy = cie.luminous_efficacy(spectrum)
    power = flux / efficacy
    r = bulb["radius"] * 1e-3
    return {"flux_lm": flux, "efficacy_lm_per_w": efficacy, "power_w": power,
            "radiance": power / (4.0 * math.pi ** 2 * r * r), "color": light_color(spectrum), "spectrum": spectrum}


def sun_light(illuminance_lux: float) -> dict:
    """The sun's Cycles values: ``strength`` E_e in W/m² and ``color`` C (CIE daylight 5500 K)."""
    spectrum = daylight.daylight_spectrum(daylight.SUN_CCT_K)
    efficacy = cie.luminous_efficacy(spectrum)
    return {"strength": float(illuminance_lux) / efficacy, "color": light_color(spectrum),
            "efficacy_lm_per_w": efficacy}


def _filter_curve(part: dict, where: str) -> Spectrum:
    kind = part["filter"]
    if kind == "file":
        return spectral._read_curve(part["filter_file"], f"{where}.filter_file")
    if kind == "custom":
        low, high = part["filter_range"]
        return materials.cut_on_filter(part["filter_edge_nm"], part["filter_slope_nm"], low, high).spectrum()
    return materials.FILTERS[kind].spectrum()


def rgb_under(curve: Spectrum, source: Spectrum) -> np.ndarray:
    """Per channel, the share of ``source``'s linear Rec.709 that passes (or is reflected by) ``curve``:
    RGB_c(S · T) / RGB_c(S), in (0, 1]. Light the curve leaves outside Rec.709 (legal red has a
    negative green) is clipped into it at its own luminance, so that Cycles keeps the luminance it
    cannot keep the colour of."""
    seen = in_gamut(cie.xyz_to_linear_rec709(cie.spectrum_xyz(source.times(curve))))
    lit = in_gamut(cie.xyz_to_linear_rec709(cie.spectrum_xyz(source)))
    with np.errstate(divide="ignore", invalid="ignore"):
        share = np.where(lit > 0, seen / lit, 1.0)
    return np.clip(share, MIN_TRANSMITTANCE, 1.0)


def filter_absorption(part: dict, source: Spectrum, where: str) -> list[float]:
    """Absorption per mm per channel of a lens's or plate's filter under ``source`` (module doc)."""
    transmittance = rgb_under(_filter_curve(part, where), source)
    return [float(a) for a in -np.log(transmittance) / part["filter_thickness"]]


def equivalent(scene: dict) -> dict:
    """The paper's appearance fields of a normalised photometric ``scene`` set to its Cycles values
    (module doc); a paper scene as it is."""
    if scene.get("light_model", "paper") != "photometric":
        return scene
    out = copy.deepcopy(scene)
    sun = sun_light(scene["light"]["illuminance_lux"])
    light = out["light"]
    # materials.sun: energy = pi (1 - ambient) strength, colour sun_color
    light.update(ambient=0.0, strength=sun["strength"] / math.pi, sun_color=[float(c) for c in sun["color"]],
                 follow_environment_color=False)
    out["background"] = list(BLACK)
    env = out["environment"]
    if env["world"] != "none":
        from ...core_tracer.raytrace import environment

        pixels = environment.from_scene(scene).pixels
        env["strength"] = spectral.environment_scale(scene, pixels) / cie.KM
    for i, lamp in enumerate(out["lamps"]):
        where = f"lamps[{i}]"
        bulb = bulb_light(lamp["bulb"], f"{where}.bulb")
        source = bulb["spectrum"]
        lamp["bulb"]["intensity"] = [float(c) for c in bulb["radiance"] * bulb["color"]]
        lens = lamp["lens"]
        for key in ("transmitted_color", "reference_thickness"):
            lens.pop(key, None)
        lens.update(ior=spectral.index_of(lens)[0], absorption=filter_absorption(lens, source, f"{where}.lens"),
                    diffuse_color=list(BLACK), side_wall_color=list(BLACK))
        plate = lamp["prism_plate"]
        if lamp.get("collection", "reflector") == "prism_plate":
            plate.update(glass_ior=spectral.index_of(plate)[0],  # its rings keep the design's ior, as the tracer's
                         absorption=filter_absorption(plate, source, f"{where}.prism_plate"))
        plate["housing_color"] = list(BLACK)
        refl = lamp["reflector"]
        finish = materials.mirror_reflectance(spectral.FINISHES[refl["finish"]])
        rho = float(rgb_under(finish, source) @ np.asarray(daylight.REC709_LUMINANCE))
        share = refl["scatter_share"]
        refl.update(color=list(BLACK), reflectance=(1.0 - share) * rho, scatter=share * rho)
        refl[cycles.SCATTER_AS_LOBE] = True  # its glow is physical: the lobe, not eq. 3's emission
        lamp["socket"]["color"] = list(BLACK)
    return out

"""The panel's words for the photometric mode's fields and the light model (``spec``'s photometric
fields): labels a lamp designer uses ("Bulb Type", "Filament", "Sun Illuminance (lx)") instead of
the JSON keys, and names for their choices ("PMMA (Acrylic)", "Red LED") instead of identifiers.

Only fields listed here get these words; every other field keeps the name made from its key
(``properties.display_name``). Choices keep their JSON identifiers as Blender identifiers, so
saved files and presets are unchanged.
"""

from __future__ import annotations

from ...core_tracer.photometry import sources
from ...core_tracer.scene import spec as S

_OPTICS = {"material": "Material", "abbe": "Abbe Number", "filter": "Filter", "filter_edge_nm": "Filter Edge",
           "filter_slope_nm": "Filter Slope", "filter_range": "Filter Transmittance Below, Above",
           "filter_file": "Filter File (.csv)", "filter_thickness": "Filter Thickness"}

# (section, key, label without its unit: the unit follows in brackets, as for every field); a list,
# since sections are matched by identity (a Section holds a dict and has no hash)
_LABELS = [
    (S.SCENE, "light_model", "Light Model"),
    (S.CAMERA, "exposure", "Exposure"),
    (S.CAMERA, "ev100", "Exposure Value at ISO 100"),
    (S.LIGHT, "illuminance_lux", "Sun Illuminance"),
    (S.ENVIRONMENT, "scale_by", "Brightness By"),
    (S.ENVIRONMENT, "illuminance_lux", "Illuminance"),
    (S.ENVIRONMENT, "luminance_cd_m2", "Mean Luminance"),
    (S.REFLECTOR, "finish", "Finish"),
    (S.REFLECTOR, "scatter_share", "Glow Share"),
    (S.BULB, "type", "Bulb Type"),
    (S.BULB, "state", "Filament"),
    (S.BULB, "flux_lm", "Flux"),
    (S.BULB, "spectrum", "Spectrum"),
    (S.BULB, "led_peak_nm", "LED Peak"),
    (S.BULB, "led_width_nm", "LED Width"),
    (S.BULB, "spectrum_file", "Spectrum File (.csv)"),
    # the LEDs' (their distribution keeps its own words: Lambertian, File)
    (S.LED, "flux_lm", "Flux per LED"),
    (S.LED, "spectrum", "Spectrum"),
    (S.LED, "led_peak_nm", "LED Peak"),
    (S.LED, "led_width_nm", "LED Width"),
    (S.LED, "spectrum_file", "Spectrum File (.csv)"),
    (S.LED, "far_field_file", "Far-Field File (.ies, .ldt)"),
    *((S.LENS, key, words) for key, words in _OPTICS.items()),
    *((S.PRISM_PLATE, key, words) for key, words in _OPTICS.items()),
    *((S.LIGHT_GUIDE, key, words) for key, words in _OPTICS.items()),
]


def _bulb_description(name: str) -> str:
    kind = sources.BULB_TYPES[name]
    states = ", ".join(f"{state} {value.flux_lm:g} lm" for state, value in kind.states.items())
    return f"{name}: {states}, {kind.spectrum.replace('_', '-')} (UN R37)"


# choice identifier -> (name shown, tooltip)
_CHOICES = {
    "paper": ("Paper", "The paper's RGB model: brightness relative, colours as red, green and blue"),
    "photometric": ("Photometric", "Light as a spectrum in physical units: bulbs in lm, sun in lx, images in "
                                   "cd/m2, lens colours as filter curves"),
    "auto": ("Auto", "A light meter's exposure, chosen for each image"),
    "ev100": ("EV100", "One fixed exposure value, so that designs show their true difference in brightness"),
    "custom": ("Custom", "Set the values yourself"),
    **{name: (name, _bulb_description(name)) for name in S.BULB_TYPES},
    "stop": ("Stop", "The bright filament (stop lamp)"),
    "tail": ("Tail", "The dim filament (tail lamp)"),
    "on": ("On", "The single filament"),
    "incandescent": ("Incandescent", "A filament bulb: CIE illuminant A, 2856 K"),
    "amber_coated": ("Amber-Coated", "A filament bulb with an amber coat"),
    "red_led": ("Red LED", "A red LED, peak {:g} nm".format(sources.LED_PRESETS["red"][0])),
    "amber_led": ("Amber LED", "An amber LED, peak {:g} nm".format(sources.LED_PRESETS["amber"][0])),
    "white_led": ("White LED", "A phosphor white LED"),
    "led": ("LED (Peak, Width)", "An LED of the peak wavelength and width you set"),
    "file": ("CSV File", "A measured curve: a .csv of wavelength (nm), value rows beside the .blend or preset"),
    "pmma": ("PMMA (Acrylic)", "Acrylic: refractive index 1.491 at the d line, Abbe number 59.2"),
    "polycarbonate": ("Polycarbonate (PC)", "Polycarbonate: refractive index 1.585 at the d line, Abbe number 29.1"),
    "clear": ("Clear", "Colourless"),
    "red": ("Red", "A red filter (rear lamps)"),
    "amber": ("Amber", "An amber filter (direction indicators)"),
    "smoke": ("Smoke", "A grey tint"),
    "aluminised": ("Aluminised", "Vacuum-deposited aluminium"),
    "silvered": ("Silvered", "A silver coat"),
    "illuminance": ("Illuminance", "By the illuminance it gives on an upward-facing surface (lx)"),
    "luminance": ("Luminance", "By its mean luminance over all directions (cd/m2)"),
}


def label(section: S.Section, key: str) -> str | None:
    """The panel's label of field ``key`` of ``section`` without its unit, or None for a field
    named from its key."""
    return next((words for sec, k, words in _LABELS if sec is section and k == key), None)


def choice_item(value: str, fallback: str) -> tuple[str, str]:
    """(name, tooltip) of a choice of a field listed here (``fallback`` names an unknown one)."""
    return _CHOICES.get(value, (fallback, ""))


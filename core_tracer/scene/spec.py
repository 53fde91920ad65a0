"""The field declarations of a ``lamp-scene/2`` document.

Every parameter of a lamp design is declared here once, with its unit, allowed range, default
and description. The validator (``validate``), the field table of docs/scene-format.md, the JSON presets and
the Blender properties (``lamp_addon/design/properties.py``) all follow from these declarations.
The kinds of field (``Num``, ``Section``, the either/or rule ``OneOf`` …) are ``field_kinds``'s.

Lengths are millimetres, absorption coefficients per millimetre, angles degrees, colours
linear RGB (docs/model.md §2).
"""

# long: every field of the document is declared here once, as the project's rules ask (one place to read)

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

from .field_kinds import Alternative, Choice, Flag, ListOf, Num, OneOf, Section, Spec, Tags, Text

SCHEMA = "lamp-scene/2"
# Earlier versions this one reads: a lamp-scene/1 document is a lamp-scene/2 one without "freeform"
# (``validate.parse_scene`` migrates it on load).
OLDER_SCHEMAS = ("lamp-scene/1",)
MAX_LAMPS = 4
MAX_IMAGE_SIDE = 8192
# Rays per pixel at most: 256 brings an edge to within a fraction of a percent of its converged
# value (Cycles' own default for final renders is 4096 with adaptive sampling; the tracer has no noise
# from lighting, only from edges, so far fewer suffice).
MAX_SAMPLES = 256
# mm: the camera must stand at least this far from its target to have a view direction.
MIN_CAMERA_DISTANCE = 1e-6
# At most this many cuts across the lens diameter: the cut cell walk then crosses a bounded
# number of cells (about sqrt 2 times this) and its cell arithmetic stays exact.
MAX_CUTS_ACROSS = 1000


def _color(default, doc, hi=1.0) -> Num:
    return Num(tuple(default), 0.0, hi, unit="", doc=doc, size=3, subtype="color")


def _length(default, doc, lo=0.0, hi=10000.0, lo_open=True) -> Num:
    return Num(default, lo, hi, lo_open=lo_open, unit="mm", doc=doc, subtype="distance")


def _position(default, doc, size=3) -> Num:
    return Num(tuple(default), -1.0e5, 1.0e5, unit="mm", doc=doc, size=size, subtype="xyz")


# ---------------------------------------------------------------------------------------------
# The photometric mode (docs/photometric.md): light in lm, cd/m² and lx, carried as a spectrum.
# Its fields say "Photometric:" first; the paper mode ignores them (and the photometric mode
# ignores the paper's appearance values: bulb intensity, reflector colour, socket and wall colours).

LIGHT_MODELS = ("paper", "photometric")
# The named bulbs of core_tracer.photometry.sources.BULB_TYPES (a test keeps the two lists equal).
BULB_TYPES = ("P21/5W", "R5W", "PY21/5W")  # appended: Blender stores an enum by its index
BULB_STATES = ("stop", "tail", "on")  # P21/5W: stop and tail filaments; single-filament bulbs: on
BULB_SPECTRA = ("incandescent", "amber_coated", "red_led", "amber_led", "white_led", "led", "file")
MATERIALS = ("pmma", "polycarbonate", "custom")
FILTERS = ("clear", "red", "amber", "smoke", "custom", "file")
SPECTRUM_SUFFIXES = (".csv",)


def _optics(default_filter: str, what: str) -> dict:
    """The photometric fields of a transparent part (the lens, the prism plate): its plastic and
    its colour filter."""
    return {
        "material": Choice("pmma", MATERIALS,
                           f"Photometric: the plastic of {what}, which sets its refractive index per wavelength "
                           "(pmma: acrylic, index 1.491 at the d line, Abbe 59.2; polycarbonate: 1.585, Abbe 29.1; "
                           "custom: its own refractive index at the d line and Abbe number)"),
        "abbe": Num(57.0, 10.0, 100.0,
                    doc=f"Photometric, custom material: how little {what}'s index changes with wavelength "
                        "(Abbe number V_d; acrylic about 57, polycarbonate about 30)"),
        "filter": Choice(default_filter, FILTERS,
                         f"Photometric: the colour of {what} as an internal transmittance curve at "
                         "the filter thickness (clear, red, amber, smoke; custom: a smooth cut-on at the filter edge; "
                         "file: a measured curve)"),
        "filter_edge_nm": Num(605.0, 300.0, 900.0, unit="nm",
                              doc="Photometric, custom filter: the wavelength where the transmittance is half way "
                                  "up its cut-on"),
        "filter_slope_nm": Num(7.0, 0.1, 500.0, unit="nm",
                               doc="Photometric, custom filter: how gradual the cut-on is (the logistic's scale)"),
        "filter_range": Num((0.001, 0.9), 0.0, 1.0, size=2,
                            doc="Photometric, custom filter: internal transmittance well below and well above the "
                                "edge, at the filter thickness (the lower above 0)"),
        "filter_file": Text("", "Photometric, filter file: a .csv of nm,transmittance rows beside the document, the "
                                "internal transmittance at the filter thickness", max_len=120),
        "filter_thickness": _length(3.0, f"Photometric: the thickness of {what} at which the filter curve is its "
                                         "internal transmittance (Beer-Lambert gives every other path length)",
                                    hi=100.0),
    }


_OPTICS_SHOWN = (("abbe", "material", ("custom",)), ("filter_edge_nm", "filter", ("custom",)),
                 ("filter_slope_nm", "filter", ("custom",)), ("filter_range", "filter", ("custom",)),
                 ("filter_file", "filter", ("file",)))


CAMERA = Section(
    {
        "type": Choice("perspective", ("perspective", "orthographic"), "Projection of the camera"),
        "position": _position((0, -800, 0), "Eye position (the lamp faces -Y, so y < 0)"),
        "target": _position((0, 0, 0), "Point the camera looks at"),
        "up": Num((0, 0, 1), -1.0, 1.0, doc="Up direction of the image", size=3, nonzero=True,
                  subtype="direction"),
        "fov_deg": Num(16.0, 0.1, 170.0, unit="deg",
                       doc="Perspective: full field of view across the fitted image side"),
        "width": _length(250.0, "Orthographic: width of the view across the fitted image side",
                         hi=1.0e5),
        "sensor_fit": Choice("auto", ("auto", "horizontal", "vertical"),
                             "Which image side the field of view spans (auto: the larger, as Blender)"),
        "shift": Num((0.0, 0.0), -2.0, 2.0, doc="Lens shift in fractions of the fitted side (as Blender)",
                     size=2),
        "exposure": Choice("auto", ("auto", "ev100"),
                           "Photometric: how the image is exposed for display: auto (a light meter's choice per "
                           "image), or a fixed EV100, one physical exposure so that designs compare"),
        "ev100": Num(9.0, -20.0, 30.0, unit="EV",
                     doc="Photometric: the camera's exposure value at ISO 100; a luminance of 1.2 x 2^EV100 cd/m2 "
                         "shows as display white"),
    },
    "The view of the tracer (and of Blender's scene camera); defaults frame the body",
)

IMAGE = Section(
    {
        "width": Num(512, 1, MAX_IMAGE_SIDE, unit="px", doc="Image width in pixels", integer=True),
        "height": Num(512, 1, MAX_IMAGE_SIDE, unit="px", doc="Image height in pixels", integer=True),
        "samples": Num(1, 1, MAX_SAMPLES, integer=True,
                       doc="Smoothness of edges: rays traced per pixel, spread over it by Cycles' pixel filter "
                           "(Blackman-Harris, 1.5 px); 1 is the paper's single ray through the pixel centre"),
        "edge_samples": Num(0, 0, 32, integer=True,
                            doc="Cleaner images of the bulbs and LED dies seen through the lens: a pixel whose samples "
                                "of them disagree takes this many times its samples more, along the light's main "
                                "branches (0: off; 8 cuts the lit lens's noise to about 0.4 at some 2.2x the rays)"),
    },
    "Image size and samples per pixel",
)

GLARE = Section(
    {
        "on": Flag(False, "Spread the light of the brightest pixels by the eye's glare (off in the paper)"),
        "threshold": Num(1.0, 0.0, 1.0e6, lo_open=True,
                         doc="Linear level above which a pixel's light spreads (1 = display white at 0 EV)"),
        "strength": Num(1.0, 0.0, 1.0,
                        doc="Fraction of the light above the threshold that spreads (1 = the eye's glare)"),
    },
    "Glare of the eye around bright pixels (Spencer et al. 1995, photopic bloom), applied to the linear image",
)

LIGHT = Section(
    {
        "direction": Num((0.3, -1.0, 0.6), -1.0e3, 1.0e3, size=3, nonzero=True, subtype="direction",
                         doc="Where the light comes from: the direction from the lamp toward it (L in eq. 1)"),
        "color": _color((1, 1, 1),
                        "Colour and strength of the light's highlights on body and lens (R1G1B1 in eq. 1)", hi=1000.0),
        "ambient": Num(0.25, 0.0, 1.0,
                       doc="How bright surfaces facing away from the light still look (ambient d in eq. 1); "
                           "with surroundings their light takes its place"),
        "strength": Num(1.0, 0.0, 1000.0,
                        doc="Strength of the sun: scales its light on body and lens (the (1 - d) cos term and the "
                            "highlight of eq. 1) and its phantom light in the reflectors; 0 is no sun (night)"),
        "sun_color": _color((1, 1, 1), "Colour of the sunlight on the paint (scales the (1 - d) cos term of eq. 1; "
                                       "the highlight's colour is color)", hi=1000.0),
        "phantom": Flag(False, "Sunlight entering through the lens lights the reflector, so an unlit lamp facing a "
                               "low sun looks lit (phantom light; off in the paper)"),
        "follow_environment": Flag(False, "Take the sun's direction from the environment image: the direction of "
                                          "its brightest region (direction is then ignored); the sun stands for the "
                                          "image's own, which is taken out of the image"),
        "follow_environment_color": Flag(False, "Take the sun's colour from the environment image: the colour of its "
                                                "brightest region at luminance 1 (sun_color is then ignored; strength "
                                                "still sets how bright the sun is)"),
        "illuminance_lux": Num(100000.0, 0.0, 200000.0, unit="lx",
                               doc="Photometric: the sun's illuminance on a surface facing it (clear day about "
                                   "100 000 lx; 0 is no sun), its spectrum CIE daylight at 5500 K"),
    },
    "The sun: the directional light of equation (1)",
    # what the environment image gives is not asked for again (a flag's value is a bool)
    shown_when=(("direction", "follow_environment", (False,)), ("sun_color", "follow_environment_color", (False,))),
)

BUNDLED_WORLDS = ("city", "courtyard", "forest", "interior", "night", "studio", "sunrise", "sunset")

ENVIRONMENT = Section(
    {
        "world": Choice("none", ("none", *BUNDLED_WORLDS, "file"),
                        "What surrounds the lamp: none (the background colour, as in the paper), one of Blender's "
                        "bundled world images by name, or the image in file"),
        "file": Text("", "An equirectangular .exr or .hdr image (used when world is \"file\"); a preset names "
                    "a file beside itself", max_len=1000),
        "strength": Num(1.0, 0.0, 1.0e4, doc="Brightness of the environment (the Background node's Strength)"),
        "rotation_deg": Num(0.0, -360.0, 360.0, unit="deg",
                            doc="Turn of the environment about the vertical axis (a Mapping node's Z rotation)"),
        "scale_by": Choice("illuminance", ("illuminance", "luminance"),
                           "Photometric: how the image is brought to physical units: by the illuminance it gives "
                           "on an upward-facing surface, or by its mean luminance"),
        "illuminance_lux": Num(10000.0, 0.0, 200000.0, lo_open=True, unit="lx",
                               doc="Photometric: the illuminance the environment gives on an upward-facing surface "
                                   "(overcast day about 10 000 lx, street lighting at night a few lx)"),
        "luminance_cd_m2": Num(1000.0, 0.0, 1.0e6, lo_open=True, unit="cd/m2",
                               doc="Photometric: the environment's mean luminance over all directions"),
    },
    "The world around the lamp: seen around it, mirrored by the lens and lighting the body",
    shown_when=(("file", "world", ("file",)), ("illuminance_lux", "scale_by", ("illuminance",)),
                ("luminance_cd_m2", "scale_by", ("luminance",))),
)

BODY = Section(
    {
        "center": _position((0, 0), "Centre [x, z] of the front face in the plane y = 0", size=2),
        "size": Num((220.0, 120.0), 0.0, 1.0e4, lo_open=True, unit="mm", size=2, subtype="xyz",
                    doc="Width (x) and height (z) of the front face"),
        "depth": _length(80.0, "Depth of the box into +y"),
        "color": _color((0.6, 0.6, 0.62), "Colour of the body's paint (diffuse R0G0B0 in eq. 1)"),
        "specular": Num(0.5, 0.0, 1.0, doc="How strongly the body reflects the light as a highlight (w in eq. 1)"),
        "shininess": Num(30.0, 0.0, 1.0e4,
                         doc="How small and sharp the body's highlight is: higher is glossier (n in eq. 1)"),
    },
    "The opaque box that holds the lamps",
)

LENS_SHAPES = ("flat", "cylindrical")

LENS = Section(
    {
        "outline": Choice("round", ("round", "rectangular"),
                          "Shape of the lens seen from the front: round (radius), or rectangular (width, height, "
                          "corner_radius), a square lamp; the side wall, body opening and reflector rim follow it"),
        "radius": _length(45.0, "Size of the round lens (radius R)", hi=1000.0),
        "width": _length(90.0, "Rectangular lens: width (x) of the outline", hi=2000.0),
        "height": _length(60.0, "Rectangular lens: height (z) of the outline", hi=2000.0),
        "corner_radius": Num(8.0, 0.0, 1000.0, unit="mm", subtype="distance",
                             doc="Rectangular lens: radius of its rounded corners, at most half the smaller side "
                                 "(0: sharp corners)"),
        "thickness": _length(3.0,
                             "Thickness of the lens plate before the cuts: thicker looks deeper in colour (t)",
                             hi=100.0),
        "ior": Num(1.49, 1.0, 3.0,
                   doc="How strongly the lens bends light: higher makes the cut pattern stronger (refractive index n)"),
        "absorption": Num((0.02, 1.5, 1.6), 0.0, 100.0, unit="1/mm", size=3, subtype="rgb",
                          doc="How much red, green and blue the lens absorbs per mm: 0 is clear (A in eq. 2)"),
        "transmitted_color": Num((0.9, 0.05, 0.05), 0.0, 1.0, lo_open=True, size=3, subtype="color",
                                 doc="Colour of the lens as seen through reference_thickness of it, with a colour "
                                     "picker (instead of absorption)"),
        "reference_thickness": _length(3.0, "Thickness of lens through which transmitted_color is seen", hi=100.0),
        "diffuse_color": _color((0.05, 0.0, 0.0), "Colour of the lens surface itself, seen unlit (diffuse, eq. 1)"),
        "specular": Num(0.8, 0.0, 1.0, doc="How strongly the lens reflects the light as a highlight (w in eq. 1)"),
        "shininess": Num(60.0, 0.0, 1.0e4,
                         doc="How small and sharp the lens's highlight is: higher is glossier (n in eq. 1)"),
        "side_wall_color": _color((0.05, 0.02, 0.02), "Colour of the lens's opaque rim"),
        "shape": Choice("flat", LENS_SHAPES,
                        "Shape of the outer face: flat, or cylindrical (a vertical-axis cylinder of wrap_radius "
                        "that curves away toward wrap_toward, so the lamp wraps from the tail round to the side)"),
        "wrap_radius": _length(100.0, "Radius of the cylindrical outer face: smaller wraps further round the side; "
                                      "at least the lens diameter plus thickness and cuts", hi=10000.0),
        "wrap_toward": Choice("+x", ("+x", "-x"), "Side toward which a cylindrical lens curves away from the viewer"),
        **_optics("red", "the lens"),
    },
    "The lens disk; its colour is given by absorption, or by transmitted_color at "
    "reference_thickness (never both)",
    one_of=(OneOf(
        "color",
        (Alternative(("transmitted_color", "reference_thickness"), "Transmitted Colour",
                     "The colour seen through the lens, picked with a colour picker",
                     same_as=(("reference_thickness", "thickness"),)),
         Alternative(("absorption",), "Absorption", "How strongly the lens absorbs red, green and blue "
                                                    "per mm (A in eq. 2)")),
        default="absorption", preferred="transmitted_color",
        doc="How the lens colour is given"),),
    shown_when=(("radius", "outline", ("round",)), ("width", "outline", ("rectangular",)),
                ("height", "outline", ("rectangular",)), ("corner_radius", "outline", ("rectangular",)),
                ("wrap_radius", "shape", ("cylindrical",)), ("wrap_toward", "shape", ("cylindrical",)),
                *_OPTICS_SHOWN),
)

CUT_TYPES = ("fisheye", "sawtooth", "flutes")
# mm: the highest saw-tooth ridge (pitch x tan(tooth angle)), as for the fish-eye cut height.
MAX_TOOTH_HEIGHT = 100.0

CUTS = Section(
    {
        "pitch": _length(9.0,
                         "Size of the cuts: the side of each fish-eye cell, or the spacing of the saw-tooth "
                         "ridges; at most the lens diameter (pitch p)", hi=1000.0),
        "height": Num(1.5, 0.0, 100.0, unit="mm",
                      doc="Depth of each fish-eye cut (or flute): deeper spreads the light more; 0 is a flat inner "
                          "face; at most pitch / sqrt 2, a hemisphere (flutes: pitch / 2, a half cylinder) (h)",
                      subtype="distance"),
        "type": Choice("fisheye", CUT_TYPES,
                       "Shape of the cuts: fisheye, a square grid of spherical lenslets (the paper's); "
                       "sawtooth, parallel prismatic ridges that bend the light to one side; or flutes, "
                       "parallel cylindrical ridges that spread it across them"),
        "tooth_angle": Num(20.0, 0.0, 60.0, unit="deg",
                           doc="Saw-tooth: slope of each ridge's inclined facet from the lens plane: steeper "
                               "bends the light further; 0 is a flat inner face; the ridges stand "
                               "pitch x tan(angle) high, at most 100 mm"),
        "orientation": Num(0.0, -180.0, 180.0, unit="deg",
                           doc="Saw-tooth and flutes: direction of the ridges in the lens plane, from +x toward "
                               "+z (0: horizontal ridges; saw-tooth facets then rise toward +z)"),
    },
    "The cuts on the inner face of the lens: fish-eye (spherical), saw-tooth (prismatic ridges) or flutes "
    "(cylindrical ridges)",
)
# The fields of the cuts that each type uses (an editor shows only these).
CUT_TYPE_FIELDS = {"fisheye": ("pitch", "height"), "sawtooth": ("pitch", "tooth_angle", "orientation"),
                   "flutes": ("pitch", "height", "orientation")}

REFLECTOR = Section(
    {
        "focal_length": _length(18.0,
                                "Depth of the reflector bowl: shorter is deeper (focal length f of the paraboloid)",
                                hi=1000.0),
        "gap": Num(0.0, 0.0, 1000.0, unit="mm", subtype="distance",
                   doc="Space between the back of the cuts and the reflector's rim"),
        "color": _color((0.3, 0.3, 0.3), "Colour of the reflector seen unlit (constant on the first hit)"),
        "reflectance": Num(0.8, 0.0, 1.0,
                           doc="How much of the bulb's light the reflector mirrors (mirror reflectance)"),
        "scatter": Num(0.8, 0.0, 1.0, doc="How much light the reflector scatters as a soft glow (w in eq. 3)"),
        "shininess": Num(20.0, 0.0, 1.0e4, doc="How tight the reflector's glow is: higher is tighter (n in eq. 3)"),
        "finish": Choice("aluminised", ("aluminised", "silvered"),
                         "Photometric: the reflector's metal coat, which sets its reflectance per wavelength"),
        "scatter_share": Num(0.1, 0.0, 1.0,
                             doc="Photometric: the share of the reflected light spread into a soft glow (a "
                                 "normalised lobe of the reflector's shininess); the rest is mirrored"),
    },
    "The paraboloid reflector behind the lens",
)

BULB = Section(
    {
        "radius": _length(8.0, "Size of the bulb; it must fit inside the reflector", hi=1000.0),
        "offset": Num((0.0, 0.0, 0.0), -1000.0, 1000.0, unit="mm", size=3, subtype="xyz",
                      doc="Where the bulb sits, from the reflector's focus [x, y, z]: at the focus the lamp "
                          "lights most evenly"),
        "intensity": _color((8.0, 7.0, 6.0), "Brightness and colour of the bulb's light (I0 per R, G, B)", hi=1.0e4),
        "on": Flag(True, "Whether the lamp is switched on"),
        "type": Choice("custom", ("custom", *BULB_TYPES),
                       "Photometric: a standard bulb by its category (UN R37), which gives its flux and spectrum; "
                       "custom: its own flux and spectrum"),
        "state": Choice("stop", BULB_STATES,
                        "Photometric: which filament of the bulb is lit (P21/5W, PY21/5W: stop or tail; "
                        "single-filament bulbs: on)"),
        "flux_lm": Num(440.0, 0.0, 100000.0, unit="lm",
                       doc="Photometric, custom bulb: the luminous flux the bulb emits in all directions"),
        "spectrum": Choice("incandescent", BULB_SPECTRA,
                           "Photometric, custom bulb: the colour of its light (incandescent: CIE illuminant A; "
                           "amber-coated; red, amber or white LED; led: peak and width; file: a measured curve)"),
        "led_peak_nm": Num(630.0, 360.0, 830.0, unit="nm", doc="Photometric, LED spectrum: the peak wavelength"),
        "led_width_nm": Num(20.0, 1.0, 300.0, unit="nm",
                            doc="Photometric, LED spectrum: the half spectral width (Ohno 2005's model)"),
        "spectrum_file": Text("", "Photometric, spectrum file: a .csv of nm,value rows beside the document",
                              max_len=120),
    },
    "The spherical bulb, the light source",
    shown_when=(("state", "type", BULB_TYPES), ("flux_lm", "type", ("custom",)),
                ("spectrum", "type", ("custom",)), ("led_peak_nm", "spectrum", ("led",)),
                ("led_width_nm", "spectrum", ("led",)), ("spectrum_file", "spectrum", ("file",))),
)

SOCKET = Section(
    {
        "radius": _length(5.0, "Size of the bulb socket behind the bulb", hi=1000.0),
        "color": _color((0.1, 0.1, 0.1), "Colour of the bulb socket"),
    },
    "The cylindrical socket from the reflector vertex to the bulb centre",
)

# The LED source (docs/photometric.md, "LED sources"): flat emitting dies instead of the bulb.
LIGHT_SOURCES = ("bulb", "led")
LED_SPECTRA = ("red_led", "amber_led", "white_led", "led", "file")
LED_DISTRIBUTIONS = ("lambertian", "file")
FAR_FIELD_SUFFIXES = (".ies", ".ldt")
MAX_LED_COUNT = 32  # dies across (or up) an array at most

LED = Section(
    {
        "position": _position((0.0, 30.0, 0.0), "Centre of the LED array in the lamp's frame [x, y, z]: x and z "
                                                "from the lens axis, y the depth behind the outer lens face"),
        "normal": Num((0.0, -1.0, 0.0), -1.0, 1.0, size=3, nonzero=True, subtype="direction",
                      doc="The direction the dies face, their emitting side (-y: toward the lens); the array's "
                          "rows run across it, level with the lamp (its columns up, toward +z)"),
        "die_size": Num((1.0, 1.0), 0.0, 100.0, lo_open=True, unit="mm", size=2, subtype="xyz",
                        doc="Width (across) and height (up) of each emitting die"),
        "columns": Num(1, 1, MAX_LED_COUNT, integer=True, doc="LEDs across the array (1: a single LED)"),
        "rows": Num(1, 1, MAX_LED_COUNT, integer=True, doc="LEDs up the array"),
        "pitch": Num((5.0, 5.0), 0.0, 1000.0, unit="mm", size=2, subtype="xyz",
                     doc="Centre-to-centre spacing of the LEDs across and up; at least the die size"),
        "flux_lm": Num(20.0, 0.0, 10000.0, unit="lm",
                       doc="Photometric: the luminous flux each die emits into the half space it faces"),
        "spectrum": Choice("red_led", LED_SPECTRA,
                           "Photometric: the colour of the LEDs' light (red or amber LED of Ohno 2005's model; "
                           "white: phosphor-converted, CIE LED-B5; led: peak and width; file: a measured curve)"),
        # the LED spectrum's peak and width, or its file, as the bulb's
        **{key: BULB.fields[key] for key in ("led_peak_nm", "led_width_nm", "spectrum_file")},
        "distribution": Choice("lambertian", LED_DISTRIBUTIONS,
                               "Photometric: how each die's light spreads with direction: lambertian (I = I0 cos "
                               "theta), or file: the supplier's far-field intensity, applied as the die's luminance "
                               "I / (A cos theta) (wrong for an eye closer than about ten die sizes)"),
        "far_field_file": Text("", "Photometric, far-field file: the LED's intensity distribution as an IES LM-63 "
                                   "(.ies) or EULUMDAT (.ldt) file beside the document; its axis (gamma 0) is the "
                                   "die's normal, its C 0 plane the array's across direction; only its shape is "
                                   "used, the die emits flux_lm", max_len=120),
    },
    "LED dies, the light source when the lamp's source is led: flat emitters of given size in a grid "
    "(in the paper mode each die shows the bulb's intensity)",
    shown_when=(("led_peak_nm", "spectrum", ("led",)), ("led_width_nm", "spectrum", ("led",)),
                ("spectrum_file", "spectrum", ("file",)), ("far_field_file", "distribution", ("file",))),
)

# At most this many prism rings across the plate's radius: the ring walk then crosses a bounded
# number of rings and the profile stays a table of a few hundred numbers.
MAX_RINGS = 500

PRISM_PLATE = Section(
    {
        "gap": _length(4.0, "Space between the back of the lens cuts and the plate's flat front face", hi=1000.0),
        "thickness": _length(2.0, "Thickness of the plate from its flat front face to the bottoms of the rings",
                             hi=100.0),
        "focal_length": _length(50.0,
                                "Distance from the bottoms of the rings back to the plate's focus, where the bulb "
                                "sits (plus the bulb offset); longer is a flatter plate", hi=1000.0),
        "pitch": _length(2.0, "Width of each concentric prism ring: finer rings collimate more exactly", hi=1000.0),
        "ior": Num(1.49, 1.0, 3.0, lo_open=True,
                   doc="How strongly the plate bends light (refractive index; clear acrylic 1.49)"),
        "absorption": Num((0.001, 0.001, 0.001), 0.0, 100.0, unit="1/mm", size=3, subtype="rgb",
                          doc="How much red, green and blue the plate absorbs per mm (clear acrylic: almost 0)"),
        "housing_depth": _length(60.0, "Depth of the opaque housing behind the plate, from the bottoms of the rings "
                                       "to its back", hi=1000.0),
        "housing_color": _color((0.08, 0.08, 0.08), "Colour of the opaque housing behind the plate"),
        **_optics("clear", "the plate"),
    },
    "A transparent plate between bulb and lens whose back carries concentric prism rings (a Fresnel lens) "
    "that bend the bulb's light parallel to the lamp axis; used instead of the reflector when the lamp's "
    "collection is prism_plate",
    shown_when=_OPTICS_SHOWN,
)


GUIDE_SECTIONS = ("round", "rectangular")
GUIDE_LIT_ENDS = ("one", "both")
GUIDE_PATHS = ("straight", "arc")
# At most this many extraction prisms along a guide: the prism walk crosses a bounded number of cells.
MAX_GUIDE_PRISMS = 2000

LIGHT_GUIDE = Section(
    {
        "enabled": Flag(False, "Photometric: whether the lamp has a light guide, a transparent rod lit at its "
                               "end by the lamp's LEDs (source led, placed facing an end face), whose "
                               "extraction prisms send the light out toward the lens (docs/model.md 8.7a)"),
        "section": Choice("round", GUIDE_SECTIONS,
                          "Photometric: the cross-section of the guide: round (diameter) or rectangular (width across "
                          "the guide in the lens plane, thickness along the lamp axis)"),
        "diameter": _length(6.0, "Photometric, round guide: the diameter of the rod", hi=100.0),
        "width": _length(6.0, "Photometric, rectangular guide: its width across the guide, in the lens plane",
                         hi=100.0),
        "thickness": _length(4.0, "Photometric, rectangular guide: its thickness along the lamp axis", hi=100.0),
        "path": Choice("straight", GUIDE_PATHS,
                       "Photometric: the guide's axis: straight (length), or a circular arc in the lens plane "
                       "(arc_radius, arc_sweep; rectangular section only) bending toward the left of orientation"),
        "length": _length(80.0, "Photometric: the length of the straight guide from end face to end face",
                          hi=2000.0),
        "arc_radius": _length(100.0, "Photometric, arc guide: the radius of its axis, from the arc's centre",
                              hi=10000.0),
        "arc_sweep": Num(60.0, 1.0, 180.0, unit="deg",
                         doc="Photometric, arc guide: the angle its axis turns through from end face to end face"),
        "center": _position((0.0, 0.0), "Photometric: the middle of the guide [x, z] from the lamp axis, in the "
                                         "lens plane (of an arc guide: the middle of its axis)", size=2),
        "depth": _length(15.0, "Photometric: how far behind the lens's outer face the guide's axis lies (y)",
                         hi=1000.0),
        "orientation": Num(0.0, -180.0, 180.0, unit="deg",
                           doc="Photometric: the guide's direction in the lens plane, from the x axis toward z (of an "
                               "arc guide: its direction at its middle)"),
        "prism_pitch": _length(2.0, "Photometric: the spacing of the extraction prisms along the guide's back",
                               hi=100.0),
        "prism_depth": Num(0.4, 0.0, 50.0, unit="mm", subtype="distance",
                           doc="Photometric: how deep each V-shaped extraction prism is cut into the guide's back "
                               "(0: a clear guide, no prisms)"),
        "prism_angle": Num(45.0, 5.0, 85.0, unit="deg",
                           doc="Photometric: the angle of each prism facet to the guide's axis (45: light running "
                               "along the guide is sent straight out toward the lens)"),
        "lit_ends": Choice("one", GUIDE_LIT_ENDS,
                           "Photometric: which ends of the guide its LEDs light: one (the lamp's LED array, facing "
                           "an end face) or both (that array and its mirror image through the guide's middle, "
                           "facing the other end face, each die with the same flux)"),
        **_optics("clear", "the guide"),
    },
    "Photometric: a light guide behind the lens, a rod of acrylic or polycarbonate lit at its end by the lamp's "
    "LEDs, with V-shaped extraction prisms cut along its back",
    shown_when=(("diameter", "section", ("round",)), ("width", "section", ("rectangular",)),
                ("thickness", "section", ("rectangular",)), ("length", "path", ("straight",)),
                ("arc_radius", "path", ("arc",)), ("arc_sweep", "path", ("arc",)), *_OPTICS_SHOWN),
)

COLLECTIONS = ("reflector", "prism_plate")

LAMP_FUNCTIONS = ("custom", "tail", "stop", "turn", "reversing", "position", "fog")

LAMP = Section(
    {
        "center": _position((0, 0), "Centre [x, z] of the lens in the plane y = 0", size=2),
        "function": Choice("custom", LAMP_FUNCTIONS,
                           "What the lamp is for; choosing one in Blender sets its lens colour and bulb "
                           "brightness and names its parts (custom: set them yourself)"),
        "lens": LENS,
        "cuts": CUTS,
        "collection": Choice("reflector", COLLECTIONS,
                             "How the bulb's light is gathered into a beam: the paraboloid reflector, or a "
                             "prism plate in front of the bulb with a shallow housing behind"),
        "reflector": REFLECTOR,
        "prism_plate": PRISM_PLATE,
        "bulb": BULB,
        "socket": SOCKET,
        "source": Choice("bulb", LIGHT_SOURCES,
                         "The light source: bulb, the spherical bulb on its socket (the paper's); or led, flat "
                         "LED dies (the led section) in place of bulb and socket"),
        "led": LED,
        "light_guide": LIGHT_GUIDE,
    },
    "One lamp: lens, cuts, reflector, bulb and socket (or LEDs; photometric, a light guide they light)",
)

SCENE = Section(
    {
        "schema": Choice(SCHEMA, (SCHEMA,), "Format and version of the document"),
        "light_model": Choice("paper", LIGHT_MODELS,
                              "How light is modelled: paper, the paper's RGB model with relative brightness; or "
                              "photometric, light as a spectrum in physical units (lm, cd/m2, lx; "
                              "docs/photometric.md)"),
        "name": Text("Untitled lamp", "The design's name, shown in the preset browser and on study sheets"),
        "author": Text("", "Who made the design, shown in the preset browser"),
        "description": Text("", "Notes on the design, shown in the preset browser", max_len=2000),
        "tags": Tags("Keywords the preset browser's search finds the design by"),
        "camera": CAMERA,
        "image": IMAGE,
        "light": LIGHT,
        "background": _color((0, 0, 0), "Colour seen around the lamp, where rays leave the scene (0 in the paper)"),
        "environment": ENVIRONMENT,
        "glare": GLARE,
        "body": BODY,
        "lamps": ListOf(LAMP, 1, MAX_LAMPS, "The lamps, 1 to 4"),
    },
    "A lamp-scene/2 document",
    optional=("camera",),
)

# ---------------------------------------------------------------------------------------------
# The optional top-level "freeform" section: the designer's own meshes, read from a glTF binary
# beside the document, each with a lamp role. It is declared apart from SCENE (``validate`` reads
# it as its own section) because it is a list of meshes, not design properties: the Blender
# properties generated from SCENE keep to the parametric lamp. Role values reuse the
# parametric fields where they mean the same, with the same defaults.

FREEFORM_ROLES = ("lens", "reflector", "bulb", "socket", "side_wall", "body")
MAX_FREEFORM_PARTS = 256
MAX_MESH_NAME = 63  # Blender's longest object name

# The photometric fields (docs/photometric.md) come with each role as the parametric part has them:
# the lens's plastic and filter, the reflector's finish and glow share, the bulb's flux and spectrum
# (its size is its mesh's: a Lambertian emitter of the mesh's area, docs/model.md "Free-form").
_BULB_SOURCE = ("intensity", "on", "type", "state", "flux_lm", "spectrum", "led_peak_nm", "led_width_nm",
                "spectrum_file")

FREEFORM_ROLE_SECTIONS = {
    "lens": Section(
        {key: LENS.fields[key] for key in ("ior", "absorption", "transmitted_color", "reference_thickness",
                                           "diffuse_color", "specular", "shininess", *_optics("red", "the lens"))},
        "A closed lens mesh: refracts (Fresnel, Snell), absorbs over the path inside it (eq. 2)",
        one_of=(OneOf("color",
                      (Alternative(("transmitted_color", "reference_thickness"), "Transmitted Colour",
                                   "The colour seen through reference_thickness of the lens"),
                       Alternative(("absorption",), "Absorption", "Absorption per mm (A in eq. 2)")),
                      default="absorption", preferred="transmitted_color", doc="How the lens colour is given"),),
        shown_when=_OPTICS_SHOWN,
    ),
    "reflector": Section({key: REFLECTOR.fields[key] for key in ("color", "reflectance", "scatter", "shininess",
                                                                 "finish", "scatter_share")},
                         "A mirror: constant colour on the first hit, Blinn scatter toward the bulbs (eq. 3)"),
    "bulb": Section({key: BULB.fields[key] for key in _BULB_SOURCE}
                    | {"radius": _length(0.0, "Photometric: the radius of the sphere the mesh stands for (a "
                                              "converted bulb's), which sets its luminance Φ/(4π² r²) and the "
                                              "glow it lights; 0: a Lambertian emitter of the mesh's own area",
                                         hi=1000.0, lo_open=False)},
                    "A light source; rays that reach it end with its intensity (photometric: its luminance, "
                    "a Lambertian emitter of its flux over the mesh's area, or over the sphere it stands for)",
                    shown_when=tuple(rule for rule in BULB.shown_when if rule[0] in _BULB_SOURCE)),
    "socket": Section({"color": SOCKET.fields["color"]}, "Opaque, ends a ray with its colour"),
    "side_wall": Section({"color": LENS.fields["side_wall_color"]}, "Opaque, ends a ray with its colour"),
    "body": Section({key: BODY.fields[key] for key in ("color", "specular", "shininess")},
                    "Opaque housing shaded by equation (1)"),
}

FREEFORM_PART = Section(
    {
        "object": Text("", "Name of the mesh in the mesh file (the Blender object's name)", max_len=MAX_MESH_NAME),
        "role": Choice("body", FREEFORM_ROLES, "What the mesh is in the lamp"),
        **FREEFORM_ROLE_SECTIONS,
    },
    "One mesh with its role and the role's values (only the key named by the role)",
    optional=FREEFORM_ROLES,
)

FREEFORM = Section(
    {
        "mesh_file": Text("", "The glTF binary (.glb) beside the document holding the meshes by name",
                          max_len=120),
        "parts": ListOf(FREEFORM_PART, 1, MAX_FREEFORM_PARTS, "The meshes and their roles"),
    },
    "Free-form parts: the designer's own meshes traced with the paper's model",
)


@dataclass(frozen=True)
class FieldInfo:
    """One leaf field with its dotted path, for tables and property generation."""

    path: str
    spec: Spec


def iter_fields(section: Section = SCENE, prefix: str = "") -> Iterator[FieldInfo]:
    """Every leaf field below ``section``, depth first, lamps as ``lamps[].…``."""
    for key, spec in section.fields.items():
        path = f"{prefix}{key}"
        if isinstance(spec, Section):
            yield from iter_fields(spec, path + ".")
        elif isinstance(spec, ListOf):
            yield from iter_fields(spec.item, path + "[].")
        else:
            yield FieldInfo(path, spec)


def iter_sections(section: Section = SCENE, prefix: str = "") -> Iterator[tuple[str, Section]]:
    """``(path, section)`` of ``section`` and every section below it, lamps as ``lamps[]``."""
    yield prefix.rstrip("."), section
    for key, spec in section.fields.items():
        if isinstance(spec, Section):
            yield from iter_sections(spec, f"{prefix}{key}.")
        elif isinstance(spec, ListOf):
            yield from iter_sections(spec.item, f"{prefix}{key}[].")


def lookup(path: str) -> Spec:
    """The spec of a dotted path such as ``lamps[].lens.ior`` or ``lens.ior`` (lamp-relative)."""
    node: Spec = SCENE
    parts = path.replace("[]", "").split(".")
    if parts[0] in LAMP.fields and parts[0] not in SCENE.fields:
        node = LAMP
    for part in parts:
        if isinstance(node, ListOf):
            node = node.item
        if not isinstance(node, Section) or part not in node.fields:
            raise KeyError(path)
        node = node.fields[part]
    return node

"""Linear RGB to what a screen shows: exposure, then a view transform of Blender's colour management.

One pipeline for every display-referred image the project writes (PNG renders, study sheets,
preset thumbnails, the Compare side by side): the tracer's linear Rec.709 values are scaled by
2^EV (the exposure), then mapped to the sRGB display by a *view* of Blender's OpenColorIO
configuration (AgX, Standard, Filmic, Khronos PBR Neutral, False Color, ...), then quantised to
8 bits. Outside Blender OpenImageIO applies Blender's own ``config.ocio``
(``ImageBufAlgo.ociodisplay``), which gives exactly what Blender shows for the same view
(BLENDER-NOTES.md, "Blender's colour management outside Blender").

Where Blender's configuration cannot be found (no bpy module, no Blender install, no
``LAMP_OCIO_CONFIG``) or OpenImageIO is missing, only the Standard view can be applied: it is the
plain sRGB transfer function, which needs no configuration. A request for any other view then
falls back to Standard and the transform carries a one-sentence ``note`` saying so, for the
caller to tell the user once.

Automatic exposure (``auto_exposure``), in the spirit of Speos's automatic adaptation: the
brightest region of the image (the lit lens) is placed just below the view's shoulder, so its
cut pattern reads instead of clipping to a flat disk. See ``auto_exposure`` for the measure.
"""

from __future__ import annotations

import glob
import importlib.util
import math
import os
import sys
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ..photometry import output

DISPLAY = "sRGB"
SCENE_LINEAR = "Linear Rec.709"  # the tracer's values: linear, Rec.709 primaries (Blender's scene linear)
STANDARD = "Standard"
# What a designer sees in Blender by default (a new scene's view transform is AgX): a CLI PNG
# should look like the same design rendered in Blender, and AgX rolls bright colours off
# instead of clipping them.
DEFAULT_VIEW = "AgX"
# The view the project chooses for pictures of lamps where the choice is ours (study and optimiser
# sheets, the measure report, Blender's "Lamp View" button): lit red and amber keep their hue.
# Measured on the four-lamp night preset (photometric, EV100 12 and one stop more), the median
# display codes of the lit stop lens and amber turn lens (tools/make_lamp_view_image.py,
# docs/lamp-view-agx-filmic.png): AgX washes red to salmon (255, 155, 154) and amber to peach
# (246, 160, 108, hue 22°); Khronos PBR Neutral washes further (254, 184, 184; amber hue 12°);
# Standard keeps the hue (255, 0, 0; amber hue 40°) but clips, with no roll-off; Filmic keeps red
# red (250, 0, 0) and amber amber (236, 166, 0, hue 42°) and rolls the highlights off. Filmic
# ships with Blender 4.2 to 5.0.
LAMP_VIEW = "Filmic"
# The views of Blender 4.2–5.0's configuration for the sRGB display, for help texts and for
# checking a name before a long render when no configuration is at hand.
KNOWN_VIEWS = ("AgX", "Standard", "Filmic", "Filmic Log", "Khronos PBR Neutral", "False Color",
               "ACES 1.3", "ACES 2.0", "Raw")
CONFIG_ENV = "LAMP_OCIO_CONFIG"  # a config.ocio to use instead of Blender's
MAX_EXPOSURE = 16.0
# Memory stays bounded whatever the image size: the view transform works on strips of rows of at
# most this many pixels, and the automatic exposure measures an evenly strided sample of at most
# AUTO_SAMPLE_PIXELS pixels (every pixel of an image up to 2048 x 2048).
STRIP_PIXELS = 1 << 20
AUTO_SAMPLE_PIXELS = 2048 * 2048

# Automatic exposure: where the lit lens's bright end is put (linear value after exposure) and
# how that bright end is found. 0.7 is half a stop below display white in Standard (code 219)
# and in AgX keeps a red lens red (R 199, G 68) rather than the pale pink of an overexposed one.
AUTO_TARGET = 0.7
AUTO_REGION_STOPS = 4.0  # the lit region: within 4 stops of the image's bright end
AUTO_PERCENTILE = 99.0  # the lit region's bright end, ignoring the brightest 1 % (glints of the bulb)
AUTO_BRIGHT_END = 99.9  # the image's bright end that bounds the lit region


# ---------------------------------------------------------------------------------------------
# Finding Blender's configuration


def _config_in(datafiles: str) -> str | None:
    path = os.path.join(datafiles, "colormanagement", "config.ocio")
    return path if os.path.isfile(path) else None


def _bpy_module_config() -> str | None:
    """The configuration inside the bpy wheel, found without importing bpy (which takes a second
    and would load Blender into a process that only writes images)."""
    try:
        spec = importlib.util.find_spec("bpy")
    except (ImportError, ValueError):
        return None
    folders = list(spec.submodule_search_locations or []) if spec is not None else []
    for folder in folders:
        found = sorted(glob.glob(os.path.join(folder, "*", "datafiles", "colormanagement", "config.ocio")))
        if found:
            return found[-1]  # the newest version folder
    return None


def _running_blender_config() -> str | None:
    # Inside Blender bpy is already loaded: ask it for its own data files (never import it here).
    bpy = sys.modules.get("bpy")
    utils = getattr(bpy, "utils", None)
    if utils is None or not hasattr(utils, "system_resource"):
        return None
    try:
        folder = utils.system_resource("DATAFILES", path="colormanagement")
    except (TypeError, ValueError, AttributeError):
        return None
    return _config_in(os.path.dirname(folder)) if folder else None


def _installed_blender_configs() -> list[str]:
    """Blender installs in their usual places (newest version last in each)."""
    patterns = [
        "/usr/share/blender/*/datafiles/colormanagement/config.ocio",
        "/opt/blender*/*/datafiles/colormanagement/config.ocio",
        "/Applications/Blender.app/Contents/Resources/*/datafiles/colormanagement/config.ocio",
        os.path.join(os.environ.get("ProgramFiles", r"C:\Program Files"), "Blender Foundation", "Blender*", "*",
                     "datafiles", "colormanagement", "config.ocio"),
    ]
    found: list[str] = []
    for pattern in patterns:
        found += sorted(glob.glob(pattern))
    return found


def find_config() -> str | None:
    """Blender's ``config.ocio``: ``$LAMP_OCIO_CONFIG``, the running Blender's, the bpy module's, or a
    Blender install's; None when there is none. Looked for once (per value of ``$LAMP_OCIO_CONFIG``):
    the first call inside Blender must come from the main thread, as every use of ``bpy``."""
    return _find_config(os.environ.get(CONFIG_ENV, ""))


@lru_cache(maxsize=4)
def _find_config(own: str) -> str | None:
    if own:
        return own if os.path.isfile(own) else None
    for found in (_running_blender_config(), _bpy_module_config()):
        if found:
            return found
    installed = _installed_blender_configs()
    return installed[-1] if installed else None


def optional_oiio():
    """OpenImageIO, or None where it is not installed."""
    try:
        import OpenImageIO
    except ImportError as e:
        # pybind11 turns a Ctrl-C or SIGTERM that lands during the module's initialisation into an
        # ImportError: that is the interrupt, not a missing module (taken for one, the next import
        # would fail with "type already registered").
        if isinstance(e.__cause__ or e.__context__, KeyboardInterrupt):
            raise (e.__cause__ or e.__context__) from None
        return None
    return OpenImageIO


@lru_cache(maxsize=8)
def _views_of(config: str) -> tuple[str, ...]:
    oiio = optional_oiio()
    colors = oiio.ColorConfig(config)
    return tuple(colors.getViewNameByIndex(DISPLAY, i) for i in range(colors.getNumViews(DISPLAY)))


# ---------------------------------------------------------------------------------------------
# The transform


@dataclass(frozen=True)
class ViewTransform:
    """A view of the sRGB display, ready to apply. ``view`` is what is applied, ``asked`` what was
    asked for; ``note`` says in words why they differ ("" when they do not)."""

    view: str
    asked: str
    config: str | None
    note: str = ""

    def to_display(self, linear: np.ndarray, exposure: float = 0.0) -> np.ndarray:
        """Display values in [0, 1] (float32, H, W, 3) of linear RGB ``linear`` at ``exposure`` stops."""
        rgb = np.ascontiguousarray(np.asarray(linear, dtype=np.float32) * np.float32(2.0 ** exposure))
        if self.config is None:
            return srgb_encode(rgb).astype(np.float32)
        oiio = optional_oiio()
        height, width = rgb.shape[:2]
        buf = oiio.ImageBuf(oiio.ImageSpec(width, height, 3, oiio.FLOAT))
        buf.set_pixels(oiio.ROI(0, width, 0, height, 0, 1, 0, 3), rgb)
        out = oiio.ImageBufAlgo.ociodisplay(buf, DISPLAY, self.view, SCENE_LINEAR, colorconfig=self.config)
        if out.has_error:
            raise RuntimeError(f"the {self.view} view cannot be applied ({out.geterror()})")
        shown = np.asarray(out.get_pixels(oiio.FLOAT), dtype=np.float32).reshape(height, width, 3)
        return np.clip(shown, 0.0, 1.0)

    def to_display8(self, linear: np.ndarray, exposure: float = 0.0) -> np.ndarray:
        """8-bit display codes (uint8, H, W, 3), rounded to nearest, of ``linear`` at ``exposure`` stops.

        Strip by strip (views work pixel by pixel, so the codes are those of the whole image at once):
        the float temporaries stay a few MB at any image size."""
        image = np.asarray(linear)
        height, width = image.shape[:2]
        codes = np.empty((height, width, 3), dtype=np.uint8)
        rows = max(1, STRIP_PIXELS // max(1, width))
        for y in range(0, height, rows):
            codes[y:y + rows] = np.rint(self.to_display(image[y:y + rows], exposure) * 255.0)
        return codes

    def to_linear(self, shown: np.ndarray, exposure: float = 0.0) -> np.ndarray:
        """The inverse of ``to_display`` (exact up to quantisation where the view did not clip)."""
        v = np.ascontiguousarray(np.asarray(shown, dtype=np.float32))
        if self.config is None:
            rgb = srgb_decode(v)
        else:
            oiio = optional_oiio()
            height, width = v.shape[:2]
            buf = oiio.ImageBuf(oiio.ImageSpec(width, height, 3, oiio.FLOAT))
            buf.set_pixels(oiio.ROI(0, width, 0, height, 0, 1, 0, 3), v)
            out = oiio.ImageBufAlgo.ociodisplay(buf, DISPLAY, self.view, SCENE_LINEAR, inverse=True,
                                                colorconfig=self.config)
            rgb = np.asarray(out.get_pixels(oiio.FLOAT), dtype=np.float32).reshape(height, width, 3)
        return (rgb / 2.0 ** exposure).astype(np.float32)


def view_transform(view: str = DEFAULT_VIEW, config: str | None = None) -> ViewTransform:
    """The transform for ``view`` with Blender's configuration (``config`` or ``find_config()``).

    Standard needs no configuration. Another view without a configuration or without OpenImageIO
    falls back to Standard with a ``note``. A view the configuration does not have raises
    ``ValueError`` naming the views it has.
    """
    config = config or find_config()
    oiio = optional_oiio()
    if config is None or oiio is None:
        if view != STANDARD:
            missing = "OpenImageIO is not installed" if oiio is None else _why_no_config()
            note = f"{missing}, so images use the Standard view (plain sRGB) instead of {view}"
            if view not in KNOWN_VIEWS:
                raise ValueError(f"{view!r} is not a view; allowed {', '.join(KNOWN_VIEWS)}")
            return ViewTransform(STANDARD, view, None, note)
        return ViewTransform(STANDARD, view, None)
    views = _views_of(config)
    if view not in views:
        raise ValueError(f"{view!r} is not a view of Blender's colour management; allowed {', '.join(views)}")
    if view == STANDARD:
        return ViewTransform(STANDARD, view, None)  # the sRGB transfer function, exactly (no config needed)
    return ViewTransform(view, view, config)


def _why_no_config() -> str:
    own = os.environ.get(CONFIG_ENV)
    if own:
        return f"{CONFIG_ENV} names no file ({own})"
    return f"Blender's colour configuration was not found (no bpy module, no Blender install, no {CONFIG_ENV})"


def available_views(config: str | None = None) -> tuple[str, ...]:
    """The views that can be asked for: those of Blender's configuration, else the known names."""
    config = config or find_config()
    if config is None or optional_oiio() is None:
        return KNOWN_VIEWS
    return _views_of(config)


# ---------------------------------------------------------------------------------------------
# Exposure


def auto_exposure(linear: np.ndarray | list[np.ndarray]) -> float:
    """Stops that put the lit lens just below the view's shoulder (rounded to 1/10 stop).

    The measure, per pixel, is its brightest channel m = max(R, G, B) (a channel that clips is
    what flattens a coloured lens). The image's bright end is the 99.9th percentile of m; the lit
    region is every pixel within ``AUTO_REGION_STOPS`` of it (the lit lens; the body, the
    socket and the black background lie further below); the region's 99th percentile of m is
    placed at ``AUTO_TARGET``. Several images (a study's variants, the two halves of a Compare)
    are measured together, so they share one exposure. A black image gets 0.
    """
    images = linear if isinstance(linear, list) else [linear]
    m = np.concatenate([_sample(np.asarray(a)).max(axis=-1).astype(np.float32).ravel() for a in images])
    m = m[np.isfinite(m) & (m > 0.0)]
    if m.size == 0:
        return 0.0
    bright_end = float(np.percentile(m, AUTO_BRIGHT_END))
    region = m[m >= bright_end * 2.0 ** -AUTO_REGION_STOPS]
    key = float(np.percentile(region, AUTO_PERCENTILE))
    if key <= 0.0:
        return 0.0
    ev = math.log2(AUTO_TARGET / key)
    return round(max(-MAX_EXPOSURE, min(MAX_EXPOSURE, ev)), 1)


def _sample(image: np.ndarray) -> np.ndarray:
    """``image`` itself up to ``AUTO_SAMPLE_PIXELS`` pixels, else every k-th row and column of it."""
    pixels = image.shape[0] * image.shape[1]
    step = math.ceil(math.sqrt(pixels / AUTO_SAMPLE_PIXELS)) if pixels > AUTO_SAMPLE_PIXELS else 1
    return image[::step, ::step]


def resolve_exposure(exposure: float | str | None, linear: np.ndarray | list[np.ndarray]) -> float:
    """``exposure`` stops as given, or ``auto_exposure(linear)`` for None or ``"auto"``."""
    if exposure is None or exposure == "auto":
        return auto_exposure(linear)
    return float(exposure)


# ---------------------------------------------------------------------------------------------
# The sRGB transfer function (the Standard view)


def srgb_encode(linear: np.ndarray) -> np.ndarray:
    """The sRGB transfer function (IEC 61966-2-1) of linear values, clipped to [0, 1]."""
    x = np.clip(np.asarray(linear, dtype=np.float64), 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1.0 / 2.4) - 0.055)


def srgb_decode(encoded: np.ndarray) -> np.ndarray:
    """The inverse of ``srgb_encode``: display values in [0, 1] back to linear."""
    v = np.asarray(encoded, dtype=np.float64)
    return np.where(v <= 0.04045, v / 12.92, np.power((v + 0.055) / 1.055, 2.4))


# ---------------------------------------------------------------------------------------------
# From an image to a display: the one path (issue 31 item 1)
#
# Every picture made for a person (F12 and the viewport through Blender's own view, the Image
# Editor's images, study and optimiser sheets, Compare, the Light Panel, thumbnails, the measure
# report) goes through ``shown``: what its pixels are is said by its scene's light model, never
# guessed by the caller. Two conversions done apart once showed a red photometric lamp gold on a
# study sheet (XYZ taken for R, G, B) while F12 showed it red.

PAPER = "paper"  # linear Rec.709 radiance in the paper's units (eq. 1): Blender's scene-linear as it is
PHOTOMETRIC = "photometric"  # CIE 1931 XYZ, Y = luminance in cd/m² (raytrace.spectral)


def light_model(scene: dict) -> str:
    """What a scene's image holds: ``PAPER`` or ``PHOTOMETRIC``."""
    return scene.get("light_model", PAPER)


@dataclass(frozen=True)
class Exposure:
    """How a group of images shown together was exposed: ``ev100`` the camera EV100 of its
    photometric images (None when there are none), ``stops`` brighter on top of it (Blender's
    exposure slider), ``paper_stops`` the exposure of its paper-mode images (None when none)."""

    ev100: float | None = None
    stops: float = 0.0
    paper_stops: float | None = None

    def words(self) -> str:
        """How the pictures are exposed, for a caption ("EV100 9.6 +1.0 EV", "+2.3 EV")."""
        parts = []
        if self.ev100 is not None:
            parts.append(f"EV100 {self.ev100:.1f}" + (f" {self.stops:+.1f} EV" if self.stops else ""))
        if self.paper_stops is not None:
            parts.append(f"{self.paper_stops:+.1f} EV")
        return ", ".join(parts)


@dataclass(frozen=True)
class Shown:
    """What ``shown`` returns: the pictures (one per image, float32 H, W, 3) and their exposure."""

    pixels: list[np.ndarray]
    exposure: Exposure


def exposure_for(images: list[np.ndarray], scenes: list[dict], *, ev100: float | str | None = None,
                 stops: float = 0.0, exposure: float | str | None = "auto") -> Exposure:
    """ONE exposure for images shown together (``shown``'s parameters)."""
    photometric = [i for i, scene in enumerate(scenes) if light_model(scene) == PHOTOMETRIC]
    paper = [i for i in range(len(scenes)) if i not in set(photometric)]
    camera = None
    if photometric:
        xyz = [np.asarray(images[i]) for i in photometric]
        first = scenes[photometric[0]]
        if ev100 is None:
            camera = exposure_ev100(xyz, first)
        elif ev100 == "auto":
            camera = exposure_ev100(xyz, {**first, "camera": {**first["camera"], "exposure": "auto"}})
        else:
            camera = float(ev100)
    paper_stops = resolve_exposure(exposure, [np.asarray(images[i]) for i in paper]) if paper else None
    return Exposure(camera, float(stops), paper_stops)


def scene_linear(image: np.ndarray, model: str, exposure: Exposure) -> np.ndarray:
    """Blender's scene-linear (linear Rec.709, float32, unclipped) of one image of light model
    ``model`` at ``exposure``: what a view transform takes at exposure 0. Photometric:
    XYZ → Rec.709 scaled by 1 / (1.2 · 2^EV100) (``photometry.output.exposure_scale``) and 2^stops;
    paper: the RGB scaled by 2^paper_stops."""
    if model == PHOTOMETRIC:
        if exposure.ev100 is None:
            raise ValueError("a photometric image needs an EV100 to be shown")
        rgb = output.scene_linear_rec709(image, exposure.ev100) * 2.0 ** exposure.stops
        return np.asarray(rgb, dtype=np.float32)
    if model != PAPER:
        raise ValueError(f"light_model: {model!r} is not one of {PAPER}, {PHOTOMETRIC}")
    rgb = np.asarray(image, dtype=np.float32)
    return rgb * np.float32(2.0 ** exposure.paper_stops) if exposure.paper_stops else rgb


def shown(images: np.ndarray | list[np.ndarray], scenes: dict | list[dict], *, view: ViewTransform | None,
          ev100: float | str | None = None, stops: float = 0.0, exposure: float | str | None = "auto",
          fixed: Exposure | None = None) -> Shown:
    """The one way from rendered images to what a person sees.

    ``images``: one image or several shown together, each (H, W, 3) as its scene's light model makes
    it (``scenes``: one normalised scene per image, or one for all): paper, linear Rec.709 radiance;
    photometric, CIE XYZ with Y in cd/m².

    Exposure, one for the group so that a brighter lamp shows brighter: every photometric image at
    ONE camera EV100 (``ev100`` a number, "auto" measured over all of them, None the first
    photometric scene's camera) and ``stops`` more; every paper image at ONE ``exposure`` (stops, or
    "auto" measured over all of them). ``fixed`` gives the exposure outright (a render shown band by
    band keeps the one chosen before it started).

    ``view``: display values in [0, 1] through that view of Blender's configuration (files); None:
    scene-linear Rec.709 at that exposure, for Blender to apply the scene's view as to any render
    (F12, the viewport, the Image Editor's images).
    """
    group = [images] if isinstance(images, np.ndarray) else list(images)
    models_of = [scenes] * len(group) if isinstance(scenes, dict) else list(scenes)
    if len(models_of) != len(group):
        raise ValueError(f"expected one scene per image ({len(group)}), got {len(models_of)}")
    chosen = fixed or exposure_for(group, models_of, ev100=ev100, stops=stops, exposure=exposure)
    pixels = [scene_linear(image, light_model(scene), chosen) for image, scene in zip(group, models_of, strict=True)]
    if view is not None:
        pixels = [view.to_display(p) for p in pixels]
    return Shown(pixels, chosen)


def exposure_ev100(XYZ: np.ndarray | list[np.ndarray], scene: dict) -> float:
    """The camera's EV100 for a photometric image (or several shown together, one exposure): the
    scene's ``camera.ev100``, or with ``camera.exposure`` "auto" the project's automatic exposure
    (``auto_exposure``: the lit lens's bright end just below the view's shoulder)
    expressed as an EV100."""
    camera = scene["camera"]
    if camera.get("exposure", "auto") == "ev100":
        return float(camera["ev100"])
    images = XYZ if isinstance(XYZ, list) else [XYZ]
    stops = auto_exposure([output.scene_linear_rec709(image, 0.0) for image in images])
    return float(np.clip(-stops, -20.0, 30.0))  # 2^stops / (1.2 · 2^0) = 1 / (1.2 · 2^EV100)


def display_linear(XYZ: np.ndarray, ev100: float) -> np.ndarray:
    """Blender's scene-linear (linear Rec.709, float32) of an XYZ image in cd/m² at camera ``ev100``:
    what the view transform takes at exposure 0 (out-of-gamut colours unclipped)."""
    return output.scene_linear_rec709(XYZ, ev100).astype(np.float32)

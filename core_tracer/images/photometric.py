"""A photometric render to files and to the screen (docs/photometric.md, "Outputs").

A photometric render's image and passes are CIE 1931 XYZ with Y in cd/m² (``raytrace.spectral``).
What leaves here:

- an .exr keeps the physical values: channels X, Y, Z (Y = luminance in cd/m²) and x, y, with the
  units in the header (``write_photometric_exr``);
- a .png is what a camera at EV100 shows: XYZ → linear Rec.709 (Blender's scene-linear, unclipped,
  ``display.display_linear``) scaled by 1 / (1.2 · 2^EV100), then Blender's view transform (AgX
  by default) as for the paper mode's images; the out-of-gamut red of a lamp is rolled off by the
  view, not clipped by us. ``stops`` brightens or darkens on top, as Blender's exposure slider;
- a false-colour .png maps log10 luminance on a ramp with a cd/m² legend
  (``false_colour``).

The conversion to the screen is ``display.shown``, the one every picture goes through. Several
images shown together (a study's cells, a side-by-side) take ONE EV100 there, so a brighter lamp
shows brighter.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence

import numpy as np

from ..photometry.bands import Bands
from ..photometry.cie import KM
from ..photometry.output import BANDS_ATTRIBUTE, CHANNEL_UNITS, UNITS_ATTRIBUTE, photometric_channels
from . import bitmap_font, display, imageio
from .imageio import image_format, write_image

EV100_ATTRIBUTE = "lamp:ev100"


def is_photometric(scene: dict) -> bool:
    return display.light_model(scene) == display.PHOTOMETRIC


def ev100_for(XYZ: np.ndarray | Sequence[np.ndarray], scene: dict, override: float | str | None = None) -> float:
    """The camera EV100 of one XYZ image or of several shown together: ``override`` (a number, or
    "auto" for the project's automatic exposure as an EV100), else the scene's camera
    (``camera.exposure`` "ev100" with ``camera.ev100``, or "auto"); ``display.exposure_for``."""
    images = [np.asarray(a) for a in XYZ] if isinstance(XYZ, (list, tuple)) else [np.asarray(XYZ)]
    return display.exposure_for(images, [scene] * len(images), ev100=override).ev100


def write_render(path: str | os.PathLike, XYZ: np.ndarray, scene: dict, *, ev100: float,
                 view: display.ViewTransform | None = None, stops: float = 0.0, bands: Bands | None = None,
                 false_colour: tuple[float | None, float | None] | None = None) -> None:
    """Write a photometric image: .exr as XYZ, L... in cd/m² (units in the header), .png through
    ``view`` at camera ``ev100`` and ``stops`` more, or, with ``false_colour`` = (lo, hi) cd/m²
    (either None: from the image), as the luminance false-colour map with its legend."""
    attributes = {EV100_ATTRIBUTE: f"{ev100:g}"}
    if image_format(path) == "exr":
        write_photometric_exr(path, XYZ, bands=bands, scene=scene, attributes=attributes)
        return
    if false_colour is not None:
        write_false_colour_png(path, np.asarray(XYZ)[..., 1], *false_colour, scene=scene)
        return
    # ``stops`` go to the view as Blender's exposure slider does (lamp:exposure records them)
    linear = display.shown(XYZ, scene, view=None, fixed=display.Exposure(ev100)).pixels[0]
    write_image(path, linear, scene, view=view, exposure=stops, attributes=attributes)


def write_pass(path: str | os.PathLike, XYZ: np.ndarray, scene: dict, bands: Bands | None = None) -> None:
    """One contribution pass of a photometric render (XYZ, Y in cd/m²) as an .exr with units."""
    write_photometric_exr(path, XYZ, channels=("X", "Y", "Z"), bands=bands, scene=scene)


# ---------------------------------------------------------------------------------------------
# Files of photometric images


def write_photometric_exr(path: str | os.PathLike, XYZ: np.ndarray, *,
                          channels: Sequence[str] = ("X", "Y", "Z", "x", "y"), bands: Bands | None = None,
                          scene: dict | None = None, attributes: Mapping[str, str] | None = None) -> None:
    """Write XYZ (H, W, 3; Y in cd/m², top row first) as a float EXR with named channels, their
    units in ``lamp:units`` (one ``name: unit`` per line), the bands in ``lamp:bands`` and the scene
    JSON in ``lamp:scene``. Channels X, Y, Z first (the default) carry OpenEXR's ``chromaticities``
    and ``whiteLuminance`` for CIE XYZ (``imageio.XYZ_CHROMATICITIES``), so Blender and other
    readers take them for XYZ, not Rec.709. Written atomically (never a partial file)."""
    name = os.fspath(path)
    if image_format(name) != "exr":
        raise imageio.SceneError(name, "photometric images are written as .exr")
    XYZ = np.asarray(XYZ)
    if XYZ.ndim != 3 or XYZ.shape[2] != 3 or XYZ.shape[0] < 1 or XYZ.shape[1] < 1:
        raise ValueError(f"XYZ image: expected (height, width, 3), got {XYZ.shape}")
    planes = photometric_channels(XYZ, channels)
    pixels = np.ascontiguousarray(np.stack(list(planes.values()), axis=-1), dtype=np.float32)
    units = "\n".join(f"{c}: {CHANNEL_UNITS[c]}" for c in planes)
    extra = {UNITS_ATTRIBUTE: units, "lamp:km": f"{KM:g}", **(attributes or {})}
    if bands is not None:
        extra[BANDS_ATTRIBUTE] = " ".join(f"{e:g}" for e in bands.edges_nm)
    xyz = tuple(planes)[:3] == ("X", "Y", "Z")  # a luminance-only or xy file is no colour image
    imageio.write_channels(name, pixels, tuple(planes), scene=scene, attributes=extra, xyz=xyz)


def read_photometric_exr(path: str | os.PathLike) -> tuple[dict[str, np.ndarray], dict[str, str]]:
    """(channel name → (H, W) float32, the ``lamp:*`` string attributes) of an EXR written above."""
    name = os.fspath(path)
    oiio = imageio.oiio_module()
    inp = oiio.ImageInput.open(name)
    if inp is None:
        raise imageio.SceneError(name, f"cannot read the image ({oiio.geterror()})")
    try:
        spec = inp.spec()
        pixels = inp.read_image(0, 0, 0, spec.nchannels, oiio.FLOAT)
        if pixels is None:
            raise imageio.SceneError(name, f"cannot read the image ({inp.geterror()})")
        pixels = np.asarray(pixels, dtype=np.float32).reshape(spec.height, spec.width, spec.nchannels)
        attrs = {a.name: a.value for a in spec.extra_attribs if a.name.startswith("lamp:") and isinstance(a.value, str)}
        return {c: pixels[:, :, i] for i, c in enumerate(spec.channelnames)}, attrs
    finally:
        inp.close()


# ---------------------------------------------------------------------------------------------
# False colour

# A blue → green → yellow → red → white ramp (dark = dim), as luminance false-colour views go.
_RAMP = np.array([
    (0.00, 0.05, 0.05, 0.30), (0.14, 0.10, 0.15, 0.85), (0.28, 0.00, 0.60, 0.95), (0.42, 0.05, 0.75, 0.35),
    (0.57, 0.65, 0.85, 0.05), (0.71, 1.00, 0.75, 0.00), (0.85, 0.95, 0.20, 0.05), (1.00, 1.00, 1.00, 1.00),
])
LEGEND_WIDTH = 96  # at label scale 1 (images under 360 rows); twice that above


def false_colour_ramp(t: np.ndarray) -> np.ndarray:
    """(..., 3) display colour of positions t in [0, 1] on the ramp."""
    t = np.clip(np.asarray(t, dtype=np.float64), 0.0, 1.0)
    return np.stack([np.interp(t, _RAMP[:, 0], _RAMP[:, c]) for c in (1, 2, 3)], axis=-1)


def luminance_range(lum: np.ndarray, decades: int = 4) -> tuple[float, float]:
    """(lo, hi) cd/m² spanning ``decades`` decades below the decade above the image's maximum."""
    finite = np.asarray(lum)[np.isfinite(lum) & (np.asarray(lum) > 0)]
    if finite.size == 0:
        return 0.1, 10.0 ** (decades - 1)
    hi = 10.0 ** math.ceil(math.log10(float(finite.max())))
    return hi / 10.0 ** decades, hi


def false_colour(lum: np.ndarray, lo: float | None = None, hi: float | None = None, *,
                 legend: bool = True) -> np.ndarray:
    """(H, W [+ legend], 3) display image in [0, 1]: log10 luminance mapped on the ramp from ``lo``
    to ``hi`` cd/m² (defaults: ``luminance_range``; give both to compare images), with a legend of
    the decades in cd/m² on the right. Black where the luminance is 0 or not finite."""
    lum = np.asarray(lum, dtype=np.float64)
    if lum.ndim != 2 or lum.shape[0] < 1 or lum.shape[1] < 1:
        raise ValueError(f"luminance image: expected (height, width), got {lum.shape}")
    if lo is None or hi is None:
        auto_lo, auto_hi = luminance_range(lum)
        lo = auto_lo if lo is None else lo
        hi = auto_hi if hi is None else hi
    if not (math.isfinite(lo) and math.isfinite(hi) and 0 < lo < hi):
        raise ValueError(f"false colour range: {lo!r} to {hi!r} cd/m² is not 0 < lo < hi")
    span = math.log10(hi) - math.log10(lo)
    lit = np.isfinite(lum) & (lum > 0)
    t = (np.log10(np.where(lit, lum, lo)) - math.log10(lo)) / span
    image = np.where(lit[..., None], false_colour_ramp(t), 0.0)
    if not legend:
        return image
    return np.concatenate([image, _legend(lum.shape[0], lo, hi)], axis=1)


def _label(value: float) -> str:
    return f"{value:g}".upper()


def _legend(height: int, lo: float, hi: float) -> np.ndarray:
    """A strip beside the image: the ramp top (hi) to bottom (lo), decade ticks labelled, the unit."""
    scale = 2 if height >= 360 else 1
    strip = np.full((height, LEGEND_WIDTH * scale, 3), 0.12)
    line = bitmap_font.LINE_H * scale
    top, bottom = 2 * line, max(2 * line + 1, height - line // 2)
    bar_x0, bar_x1 = 4 * scale, 16 * scale
    rows = np.arange(top, bottom)
    t = 1.0 - (rows - top) / max(1, bottom - 1 - top)
    strip[top:bottom, bar_x0:bar_x1] = false_colour_ramp(t)[:, None, :]
    _draw(strip, "CD/M2", line // 4, bar_x0, scale)
    span = math.log10(hi) - math.log10(lo)
    first, last = math.ceil(math.log10(lo) - 1e-9), math.floor(math.log10(hi) + 1e-9)
    for decade in range(first, last + 1):
        frac = (decade - math.log10(lo)) / span
        row = int(round(top + (1.0 - frac) * (bottom - 1 - top)))
        strip[row:row + scale, bar_x1:bar_x1 + 2 * scale] = 1.0
        label_row = max(line, min(height - line, row - 3 * scale))
        _draw(strip, _label(10.0 ** decade), label_row, bar_x1 + 5 * scale, scale)
    return strip


def _draw(image: np.ndarray, text: str, row: int, col: int, scale: int) -> None:
    mask = bitmap_font.text_mask(text, scale)
    h = min(mask.shape[0], image.shape[0] - row)
    w = min(mask.shape[1], image.shape[1] - col)
    if h <= 0 or w <= 0:
        return
    region = image[row:row + h, col:col + w]
    region[...] = region * (1.0 - mask[:h, :w, None]) + mask[:h, :w, None]


def write_false_colour_png(path: str | os.PathLike, lum: np.ndarray, lo: float | None = None,
                           hi: float | None = None, *, scene: dict | None = None) -> tuple[float, float]:
    """Write the false-colour map of luminance ``lum`` (H, W cd/m²) with its legend as an 8-bit PNG;
    returns the (lo, hi) range used. The range is in the header as ``lamp:false_colour``."""
    image = false_colour(lum, lo, hi)
    if lo is None or hi is None:
        auto = luminance_range(np.asarray(lum, dtype=np.float64))
        lo, hi = (auto[0] if lo is None else lo), (auto[1] if hi is None else hi)
    imageio.write_display(path, image, scene,
                          attributes={"lamp:false_colour": f"log10 luminance {lo:g} to {hi:g} cd/m2"})
    return float(lo), float(hi)

"""From a band image to physical outputs: XYZ, luminance in cd/m², xy; EXR with named channels;
physical exposure; a false-colour luminance map with a cd/m² legend.

Exposure (``exposure_scale``). A camera at EV100 (the exposure value at ISO 100) saturates at the
scene luminance L_max = (78 / (S q)) · N²/t = 1.2 · 2^EV100 cd/m² (S = 100, lens and vignetting
factor q = 0.65, saturation-based speed of ISO 12232): S. Lagarde, C. de Rousiers, "Moving
Frostbite to Physically Based Rendering 3.0", SIGGRAPH 2014 course notes, §5.1 (the same
derivation as colour-hdri's ``photometric_exposure_scale_factor_Lagarde2014``). Scene-linear values
are luminance / L_max, so L_max shows as display 1.0 before the view transform; one EV100 for a
whole study keeps its images comparable. ``ev100_for_average_luminance`` is the reflected-light
meter's choice, EV100 = log2(L_avg · S / K) with K = 12.5 (ISO 2720:1974), as "auto".

Colour. XYZ goes to linear Rec.709 (Blender's scene-linear space) without chromatic adaptation
and without clipping: a lamp's red outside the Rec.709 gamut keeps its negative green and blue for
the view transform (AgX, Filmic) to handle.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence

import numpy as np

from ..images import bitmap_font, imageio
from .bands import Bands
from .cie import KM, xy, xyz_matrix, xyz_to_linear_rec709

UNITS_ATTRIBUTE = "lamp:units"
BANDS_ATTRIBUTE = "lamp:bands"
CHANNEL_UNITS = {
    "X": "CIE 1931 2 deg X, same scale as Y",
    "Y": "CIE 1931 2 deg Y = luminance in cd/m2 (Km = 683.002 lm/W)",
    "Z": "CIE 1931 2 deg Z, same scale as Y",
    "L": "luminance in cd/m2",
    "x": "CIE 1931 chromaticity x",
    "y": "CIE 1931 chromaticity y",
}
SATURATION_FACTOR = 1.2  # 78 / (S q) with S = 100, q = 0.65 (Lagarde & de Rousiers 2014, §5.1)
METER_CALIBRATION_K = 12.5  # reflected-light meter constant (ISO 2720:1974)


def band_image_to_xyz(image: np.ndarray, bands: Bands) -> np.ndarray:
    """(..., 3) CIE XYZ of band-mean spectral radiance (..., K) in W/(m² sr nm); Y in cd/m²."""
    a = np.asarray(image, dtype=np.float64)
    if a.shape[-1:] != (bands.k,):
        raise ValueError(f"band image: last axis {a.shape[-1:]} is not the {bands.k} bands")
    return a @ xyz_matrix(bands)


def luminance(image: np.ndarray, bands: Bands) -> np.ndarray:
    """(...) luminance in cd/m² of a band image (..., K)."""
    return band_image_to_xyz(image, bands)[..., 1]


def chromaticity(XYZ: np.ndarray) -> np.ndarray:
    """(..., 2) CIE 1931 xy; black pixels get the D65 white point (they have no colour)."""
    return xy(XYZ)


# ---------------------------------------------------------------------------------------------
# Exposure and display


def exposure_scale(ev100: float) -> float:
    """The factor taking luminance in cd/m² to scene-linear display units: 1 / (1.2 · 2^EV100)."""
    if not (isinstance(ev100, (int, float)) and math.isfinite(ev100) and -20.0 <= ev100 <= 30.0):
        raise ValueError(f"exposure EV100: {ev100!r} is outside -20 to 30")
    return 1.0 / (SATURATION_FACTOR * 2.0 ** float(ev100))


def ev100_for_average_luminance(average_cd_m2: float) -> float:
    """The EV100 a reflected-light meter picks for a scene of average luminance L: log2(L · 100 / 12.5)."""
    if not (math.isfinite(average_cd_m2) and average_cd_m2 > 0):
        raise ValueError(f"average luminance: {average_cd_m2!r} cd/m² is not above 0")
    return math.log2(average_cd_m2 * 100.0 / METER_CALIBRATION_K)


def scene_linear_rec709(XYZ: np.ndarray, ev100: float) -> np.ndarray:
    """Linear Rec.709 (Blender's scene-linear) of XYZ in cd/m² at camera EV100, unclipped."""
    return xyz_to_linear_rec709(XYZ) * exposure_scale(ev100)


# ---------------------------------------------------------------------------------------------
# EXR with named channels and units


def photometric_channels(XYZ: np.ndarray, names: Sequence[str] = ("X", "Y", "Z", "x", "y")) -> dict[str, np.ndarray]:
    """The named channels (H, W) of an XYZ image: any of X, Y, Z, L (= Y), x, y."""
    XYZ = np.asarray(XYZ, dtype=np.float64)
    chroma = xy(XYZ) if {"x", "y"} & set(names) else None
    planes = {"X": lambda: XYZ[..., 0], "Y": lambda: XYZ[..., 1], "Z": lambda: XYZ[..., 2],
              "L": lambda: XYZ[..., 1], "x": lambda: chroma[..., 0], "y": lambda: chroma[..., 1]}
    out = {}
    for name in names:
        if name not in planes:
            raise ValueError(f"channel: {name!r} is not one of {', '.join(planes)}")
        out[name] = planes[name]()
    return out


def write_photometric_exr(path: str | os.PathLike, XYZ: np.ndarray, *,
                          channels: Sequence[str] = ("X", "Y", "Z", "x", "y"), bands: Bands | None = None,
                          scene: dict | None = None, attributes: Mapping[str, str] | None = None) -> None:
    """Write XYZ (H, W, 3; Y in cd/m², top row first) as a float EXR with named channels, their
    units in ``lamp:units`` (one ``name: unit`` per line), the bands in ``lamp:bands`` and the scene
    JSON in ``lamp:scene``. Channels X, Y, Z first (the default) carry OpenEXR's ``chromaticities``
    and ``whiteLuminance`` for CIE XYZ (``imageio.XYZ_CHROMATICITIES``), so Blender and other
    readers take them for XYZ, not Rec.709. Written atomically (never a partial file)."""
    name = os.fspath(path)
    if imageio.image_format(name) != "exr":
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

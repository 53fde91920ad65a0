"""The side-by-side image of a comparison and its figures (numpy; no Blender data).

Compare with Cycles shows the tracer's image and Cycles' next to each other below a strip with their
labels, and right of them the relative difference of their luminance as a signed false-colour map with
its legend (``difference_panel``); ``differences`` gives the per-channel statistics over the whole
image, ``lens_differences`` over the lens pixels (the figures the comparison reports, in % too).

The map is the one picture here made in display values (a colour scale, not light): it is drawn by
``difference_panel`` alone and turned into the linear values of a Blender image by
``difference_shown``, the one place a shared display function would take over.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ...core_tracer.images import bitmap_font, display, labels
from ...core_tracer.photometry.daylight import REC709_LUMINANCE

# The map's scale: relative luminance differences beyond ±CLIP_PERCENT % show at the ends of the scale.
CLIP_PERCENT = 20.0
# A pixel darker than this share of the image's bright end (99th percentile) in both renders is too dark
# to compare (a relative difference there is noise): shown in DARK, outside the scale.
DARK_SHARE = 0.01
DARK = (0.12, 0.12, 0.12)
# A diverging scale (Moreland's "cool to warm", display sRGB): Cycles brighter, equal, tracer brighter.
COOL, NEUTRAL, WARM = (0.230, 0.299, 0.754), (0.865, 0.865, 0.865), (0.706, 0.016, 0.150)


def differences(tracer: np.ndarray, cycles: np.ndarray) -> dict:
    """Per-channel statistics of tracer - Cycles over the whole image (linear RGB)."""
    diff = tracer.astype(np.float64) - cycles.astype(np.float64)
    return {
        "tracer_mean": tracer.astype(np.float64).mean(axis=(0, 1)).tolist(),
        "cycles_mean": cycles.astype(np.float64).mean(axis=(0, 1)).tolist(),
        "mean_difference": diff.mean(axis=(0, 1)).tolist(),
        "mean_abs_difference": np.abs(diff).mean(axis=(0, 1)).tolist(),
        "rms_difference": np.sqrt((diff * diff).mean(axis=(0, 1))).tolist(),
    }


def luminance(rgb: np.ndarray) -> np.ndarray:
    """Y of linear Rec.709 R, G, B (both halves are linear Rec.709; photometric ones at one EV100)."""
    return rgb[..., :3].astype(np.float64) @ np.asarray(REC709_LUMINANCE)


def percent(tracer: float, cycles: float) -> float | None:
    """100 (tracer - Cycles) / Cycles, None where Cycles' value is 0."""
    return 100.0 * (tracer - cycles) / cycles if cycles > 0.0 else None


def lens_differences(tracer: np.ndarray, cycles: np.ndarray, lens: np.ndarray) -> dict:
    """Per-channel statistics of tracer - Cycles over the lens pixels ``lens`` (H, W bool: the eye ray
    meets a lens), linear RGB: both means, the mean and the RMS difference, the pixel count, and the
    means' difference in % of Cycles' per channel (``percent``) and of the luminance
    (``luminance_percent``, with both mean luminances); None where there is no lens pixel."""
    count = int(lens.sum())
    if not count:
        nothing = [0.0, 0.0, 0.0]
        return {"pixels": 0, "tracer_mean": nothing, "cycles_mean": nothing, "mean_difference": nothing,
                "rms_difference": nothing, "percent": [None] * 3, "tracer_luminance": 0.0,
                "cycles_luminance": 0.0, "luminance_percent": None}
    t, c = tracer[lens].astype(np.float64), cycles[lens].astype(np.float64)
    diff = t - c
    t_mean, c_mean = t.mean(axis=0), c.mean(axis=0)
    t_y, c_y = float(luminance(t_mean)), float(luminance(c_mean))
    return {
        "pixels": count,
        "tracer_mean": t_mean.tolist(),
        "cycles_mean": c_mean.tolist(),
        "mean_difference": diff.mean(axis=0).tolist(),
        "rms_difference": np.sqrt((diff * diff).mean(axis=0)).tolist(),
        "percent": [percent(a, b) for a, b in zip(t_mean.tolist(), c_mean.tolist(), strict=True)],
        "tracer_luminance": t_y,
        "cycles_luminance": c_y,
        "luminance_percent": percent(t_y, c_y),
    }


def percent_text(value: float | None) -> str:
    """"+1.2 %", or "n/a" where Cycles' value is 0."""
    return "n/a" if value is None else f"{value:+.1f} %"


def lens_figures_text(lens: dict) -> str:
    """The lens figures in one short line: "lens mean luminance, tracer - Cycles: +1.2 % (R/G/B +1.0/...)"."""
    if not lens["pixels"]:
        return "no lens in view"
    channels = "/".join(percent_text(v).replace(" ", "") for v in lens["percent"])
    return (f"lens mean luminance, tracer - Cycles: {percent_text(lens['luminance_percent'])} "
            f"(R/G/B {channels})")


def relative_difference(tracer: np.ndarray, cycles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per pixel (H, W): 100 (Y_tracer - Y_Cycles) / Y_Cycles of the luminance, and where it is
    measured (a pixel brighter than ``DARK_SHARE`` of the image's 99th percentile in either render; the
    denominator is kept at least that level, so a pixel Cycles leaves black shows as the tracer brighter)."""
    y_t, y_c = luminance(tracer), luminance(cycles)
    brightest = np.maximum(y_t, y_c)
    floor = DARK_SHARE * float(np.percentile(brightest, 99)) if brightest.size else 0.0
    if floor <= 0.0:
        return np.zeros(brightest.shape), np.zeros(brightest.shape, bool)
    return 100.0 * (y_t - y_c) / np.maximum(y_c, floor), brightest >= floor


def diverging(value: np.ndarray, clip: float = CLIP_PERCENT) -> np.ndarray:
    """Display colours (..., 3) of ``value`` on the scale: COOL at -clip, NEUTRAL at 0, WARM at +clip."""
    x = np.clip(np.asarray(value, dtype=np.float64) / clip, -1.0, 1.0)[..., None]
    cool, neutral, warm = (np.asarray(c) for c in (COOL, NEUTRAL, WARM))
    return np.where(x < 0, neutral + (cool - neutral) * -x, neutral + (warm - neutral) * x).astype(np.float32)


def difference_panel(tracer: np.ndarray, cycles: np.ndarray, *, clip: float = CLIP_PERCENT,
                     text: str = "auto") -> np.ndarray:
    """The third panel, display values (H, W, 3): the relative difference of luminance per pixel
    (``relative_difference``) on the diverging scale clipped at ±``clip`` %, pixels too dark to compare
    in DARK, and the legend drawn at its foot: the scale bar, its ends and middle in %, and which
    colour means which renderer is brighter."""
    height, width = tracer.shape[:2]
    rel, measured = relative_difference(tracer, cycles)
    panel = np.where(measured[..., None], diverging(rel, clip), np.asarray(DARK, np.float32)).astype(np.float32)
    _draw_legend(panel, clip, labels.use_oiio(text))
    return panel


def _draw_legend(panel: np.ndarray, clip: float, oiio_text: bool) -> None:
    """The scale bar across the panel's foot on a black band, "-clip %  0  +clip %" above it and
    "blue: Cycles brighter  red: tracer brighter" below (shorter where the panel is narrow)."""
    height, width = panel.shape[:2]
    scale = _label_scale(height)
    line = bitmap_font.GLYPH_H * scale + 2
    bar = max(3, 2 * scale)
    band = 2 * line + bar + 4
    if band > height // 2:
        return  # too small a panel for a legend
    top = height - band
    panel[top:] = 0.0
    margin = max(2, width // 16)
    ramp = np.linspace(-clip, clip, width - 2 * margin)
    panel[top + line + 1:top + line + 1 + bar, margin:width - margin] = diverging(ramp, clip)[None]

    def write(text_: str, y: int, align: str) -> None:
        mask = labels.coverage(text_, width, line, size=line - 2, oiio_text=oiio_text, align=align,
                               inset=margin if align != "center" else 0, top=1)
        area = panel[y:y + line]
        np.maximum(area, mask[..., None], out=area)

    ends = f"{clip:g} %"
    write(f"-{ends}", top, "left")
    write(f"+{ends}", top, "right")
    middle = labels.coverage("0", width, line, size=line - 2, oiio_text=oiio_text, inset=width // 2 - scale * 3,
                             top=1)
    np.maximum(panel[top:top + line], middle[..., None], out=panel[top:top + line])
    meaning = labels.fitting(("blue: Cycles brighter  red: tracer brighter", "blue Cycles  red tracer brighter",
                              "blue Cycles, red tracer"), width - 2 * margin,
                             lambda t: labels.text_width(t, line - 2, oiio_text))
    write(meaning, top + line + bar + 3, "left")


def difference_shown(comparison: dict, view: display.ViewTransform | None, text: str = "auto") -> np.ndarray:
    """The difference panel of ``comparison`` as the side-by-side image holds it: display values where
    the halves are shown through ``view``, else the linear values that the scene's view transform
    (``linear_view``, Standard by default) shows as those display values."""
    panel = difference_panel(comparison["tracer"], comparison["cycles"], text=text)
    if view is not None:
        return panel
    back = (comparison.get("linear_view") or display.view_transform("Standard")).to_linear(panel)
    return np.clip(np.nan_to_num(back, nan=0.0, posinf=0.0), 0.0, None).astype(np.float32)


def difference_labels(lens: dict) -> tuple[str, ...]:
    """The difference panel's labels, longest first."""
    if not lens["pixels"]:
        return ("Luminance (Tracer - Cycles) / Cycles  no lens", "(Tracer - Cycles) / Cycles", "Difference")
    mean = percent_text(lens["luminance_percent"])
    return (f"Luminance (Tracer - Cycles) / Cycles  lens mean {mean}", f"Luminance difference  lens {mean}",
            f"Difference  lens {mean}", "Difference")


def label_height(image_height: int) -> int:
    """Height of the label strip: the 7-pixel font at an integer scale, with a margin."""
    return bitmap_font.GLYPH_H * _label_scale(image_height) + 6


def _label_scale(image_height: int) -> int:
    return max(1, min(4, image_height // 160 + 1))


def side_by_side(left: np.ndarray, right: np.ndarray, left_labels: Sequence[str],
                 right_labels: Sequence[str], *, text: str = "auto", third: np.ndarray | None = None,
                 third_labels: Sequence[str] = ()) -> np.ndarray:
    """One (H + strip, 2W + gap, 3) image: ``left`` and ``right`` next to each other below a
    strip holding their labels, and ``third`` (the difference) right of them when given. Each label is
    the first of its alternatives (longest first) that fits above its panel, drawn by
    ``core_tracer.images.labels`` (OpenImageIO's font where it can draw text, else, or with
    ``text="bitmap"``, the bitmap font, which draws capitals)."""
    height, width = left.shape[:2]
    panels = [(left, left_labels), (right, right_labels)] + ([(third, third_labels)] if third is not None else [])
    gap = max(2, width // 128)
    strip = label_height(height)
    out = np.zeros((height + strip, len(panels) * width + (len(panels) - 1) * gap, 3), np.float32)
    oiio_text = labels.use_oiio(text)
    size, inset = strip - 2, 3 * _label_scale(height)
    for i, (image, alternatives) in enumerate(panels):
        x = i * (width + gap)
        out[strip:, x:x + width] = image
        if i:
            out[:, x - gap:x] = 0.5
        # Each label is drawn into its own panel of the strip, so a long one is clipped there.
        label = labels.fitting(alternatives, width - 2 * inset, lambda t: labels.text_width(t, size, oiio_text))
        mask = labels.coverage(label, width, strip, size=size, oiio_text=oiio_text, inset=inset, top=3)
        area = out[:strip, x:x + width]
        np.maximum(area, mask[..., None], out=area)
    return out


def shown_side_by_side(comparison: dict, view: display.ViewTransform | None, exposure: float) -> np.ndarray:
    """The side-by-side image of ``comparison`` with both halves at ``exposure`` stops: linear
    without ``view``, else display values through ``view`` (both halves through the one transform)."""
    def shown(image: np.ndarray) -> np.ndarray:
        if view is not None:
            return view.to_display(image, exposure)
        return image * np.float32(2.0 ** exposure)

    left, right = comparison["labels"]
    tracer, cycles = comparison["tracer"], comparison["cycles"]
    lens = comparison.get("lens_differences")
    if lens is None:
        return side_by_side(shown(tracer), shown(cycles), left, right)
    return side_by_side(shown(tracer), shown(cycles), left, right, third=difference_shown(comparison, view),
                        third_labels=difference_labels(lens))

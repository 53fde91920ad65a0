"""The side-by-side image of a comparison and its figures (numpy; no Blender data).

Compare with Cycles shows the tracer's image and Cycles' next to each other below a strip with their
labels, and right of them their difference; ``differences`` gives the per-channel statistics over the
whole image, ``lens_differences`` over the lens pixels (the figures the comparison reports).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ...core_tracer.images import bitmap_font, display, labels

SCENE_LINEAR = {"light_model": display.PAPER}  # what Blender's renders hand back: scene-linear RGB


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


def lens_differences(tracer: np.ndarray, cycles: np.ndarray, lens: np.ndarray) -> dict:
    """Per-channel statistics of tracer - Cycles over the lens pixels ``lens`` (H, W bool: the eye ray
    meets a lens), linear RGB: both means, the mean and the RMS difference, and the pixel count."""
    count = int(lens.sum())
    if not count:
        nothing = [0.0, 0.0, 0.0]
        return {"pixels": 0, "tracer_mean": nothing, "cycles_mean": nothing, "mean_difference": nothing,
                "rms_difference": nothing}
    t, c = tracer[lens].astype(np.float64), cycles[lens].astype(np.float64)
    diff = t - c
    return {
        "pixels": count,
        "tracer_mean": t.mean(axis=0).tolist(),
        "cycles_mean": c.mean(axis=0).tolist(),
        "mean_difference": diff.mean(axis=0).tolist(),
        "rms_difference": np.sqrt((diff * diff).mean(axis=0)).tolist(),
    }


def lens_figures_text(lens: dict) -> str:
    """The lens figures in one short line: "lens, tracer - Cycles: mean +0.01/-0.02/+0.00, RMS 0.2/0.1/0.05"."""
    if not lens["pixels"]:
        return "no lens in view"
    mean = "/".join(f"{v:+.3g}" for v in lens["mean_difference"])
    rms = "/".join(f"{v:.3g}" for v in lens["rms_difference"])
    return f"lens, tracer - Cycles: mean {mean}, RMS {rms}"


def difference(tracer: np.ndarray, cycles: np.ndarray) -> np.ndarray:
    """The difference panel: |tracer - Cycles| per channel, linear, in the halves' own units (so it is
    shown at their exposure: a bright pixel there is a difference as large as that brightness)."""
    return np.abs(tracer.astype(np.float32) - cycles.astype(np.float32))


def difference_labels(lens: dict) -> tuple[str, ...]:
    """The difference panel's labels, longest first."""
    rms = "/".join(f"{v:.2g}" for v in lens["rms_difference"])
    return (f"|Tracer - Cycles|  lens RMS {rms}", "|Tracer - Cycles|", "Difference")


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
    def shown(image: np.ndarray) -> np.ndarray:  # both halves are scene-linear RGB (Blender's renders)
        return display.shown(image, SCENE_LINEAR, view=view, fixed=display.Exposure(paper_stops=exposure)).pixels[0]

    left, right = comparison["labels"]
    tracer, cycles = comparison["tracer"], comparison["cycles"]
    lens = comparison.get("lens_differences")
    if lens is None:
        return side_by_side(shown(tracer), shown(cycles), left, right)
    return side_by_side(shown(tracer), shown(cycles), left, right, third=shown(difference(tracer, cycles)),
                        third_labels=difference_labels(lens))

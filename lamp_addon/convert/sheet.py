"""The side-by-side image of a comparison and its figures (numpy; no Blender data).

Compare with Cycles shows the tracer's image and Cycles' next to each other below a strip with their
labels; ``differences`` gives the per-channel statistics the comparison reports.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ...core_tracer.images import bitmap_font, display, labels


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


def label_height(image_height: int) -> int:
    """Height of the label strip: the 7-pixel font at an integer scale, with a margin."""
    return bitmap_font.GLYPH_H * _label_scale(image_height) + 6


def _label_scale(image_height: int) -> int:
    return max(1, min(4, image_height // 160 + 1))


def side_by_side(left: np.ndarray, right: np.ndarray, left_labels: Sequence[str],
                 right_labels: Sequence[str], *, text: str = "auto") -> np.ndarray:
    """One (H + strip, 2W + gap, 3) image: ``left`` and ``right`` next to each other below a
    strip holding their labels. Each label is the first of its alternatives (longest first) that
    fits above its half, drawn by ``core_tracer.images.labels`` (OpenImageIO's font where it can
    draw text, else, or with ``text="bitmap"``, the bitmap font, which draws capitals)."""
    height, width = left.shape[:2]
    gap = max(2, width // 128)
    strip = label_height(height)
    out = np.zeros((height + strip, 2 * width + gap, 3), np.float32)
    out[strip:, :width] = left
    out[strip:, width + gap:] = right
    out[:, width:width + gap] = 0.5
    oiio_text = labels.use_oiio(text)
    size, inset = strip - 2, 3 * _label_scale(height)
    for alternatives, x in ((left_labels, 0), (right_labels, width + gap)):
        # Each label is drawn into its own half of the strip, so a long one is clipped there.
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
    return side_by_side(shown(comparison["tracer"]), shown(comparison["cycles"]), left, right)

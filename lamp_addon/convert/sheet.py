"""The side-by-side image of a comparison and its figures (numpy; no Blender data).

Compare with Cycles shows the tracer's image and Cycles' next to each other below a strip with their
labels; ``differences`` gives the per-channel statistics the comparison reports.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

try:  # inside the extension package
    from ...core_tracer.images import bitmap_font
except ImportError:  # lamp_addon imported as a top-level package (bpy-free tests)
    from core_tracer.images import bitmap_font


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
    fits above its half. Labels are drawn with OpenImageIO's ``render_text`` when it can (the
    PyPI OpenImageIO has FreeType and a font; ``text="auto"``), else (or with ``text="bitmap"``)
    with core_tracer's bitmap font, which draws capitals."""
    height, width = left.shape[:2]
    gap = max(2, width // 128)
    strip = label_height(height)
    out = np.zeros((height + strip, 2 * width + gap, 3), np.float32)
    out[strip:, :width] = left
    out[strip:, width + gap:] = right
    out[:, width:width + gap] = 0.5
    for alternatives, x in ((left_labels, 0), (right_labels, width + gap)):
        # Each label is drawn into its own half of the strip, so a long one is clipped there.
        label = _oiio_text(alternatives, width, strip) if text == "auto" else None
        if label is None:
            label = _bitmap_text(alternatives, width, strip, _label_scale(height))
        area = out[:strip, x:x + width]
        np.maximum(area, label, out=area)
    return out


def _fitting(alternatives: Sequence[str], room: int, measure: Callable[[str], int]) -> str:
    """The first label that fits in ``room`` pixels, else the shortest (clipped when drawn)."""
    return next((t for t in alternatives if measure(t) <= room), alternatives[-1])


def _bitmap_text(alternatives: Sequence[str], width: int, height: int, scale: int) -> np.ndarray:
    """A (height, width, 3) label drawn with the bitmap font, clipped to its box."""
    x = 3 * scale
    label = _fitting(alternatives, width - 2 * x, lambda t: bitmap_font.ADVANCE_W * scale * len(t))
    mask = bitmap_font.text_mask(label, scale)
    out = np.zeros((height, width, 3), np.float32)
    rows, cols = max(0, min(mask.shape[0], height - 3)), max(0, min(mask.shape[1], width - x))
    out[3:3 + rows, x:x + cols] = mask[:rows, :cols, None]
    return out


def _oiio_text(alternatives: Sequence[str], width: int, height: int) -> np.ndarray | None:
    """A (height, width, 3) label drawn by OpenImageIO, or None when it cannot draw text."""
    try:
        import OpenImageIO as oiio
    except ImportError:
        return None
    buf = oiio.ImageBuf(oiio.ImageSpec(width, height, 3, oiio.FLOAT))
    size = height - 2
    label = _fitting(alternatives, width - 8, lambda t: oiio.ImageBufAlgo.text_size(t, size, "").width)
    if not oiio.ImageBufAlgo.render_text(buf, 4, height - 4, label, size, "", (1.0, 1.0, 1.0)):
        return None  # Blender's bundled OpenImageIO has no FreeType
    return np.asarray(buf.get_pixels(oiio.FLOAT), dtype=np.float32).reshape(height, width, 3)

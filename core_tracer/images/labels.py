"""Text on images (study sheets, the Compare side by side): one way to draw a label, two fonts.

OpenImageIO's ``render_text`` with its bundled font where it works (the PyPI OpenImageIO); the
numpy ``bitmap_font`` where it does not: the OpenImageIO inside Blender has no FreeType
(BLENDER-NOTES.md), and a Blender build may have no OpenImageIO module at all. A label is a
coverage mask in [0, 1] the size of its box; the caller blends it in the colour it wants.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from . import bitmap_font
from .display import optional_oiio

TEXT_MODES = ("auto", "oiio", "bitmap", "none")

_render_text_works: bool | None = None




def render_text_available() -> bool:
    """Whether OpenImageIO can draw text here (probed once: it draws a "1" and looks for ink)."""
    global _render_text_works
    oiio = optional_oiio()
    if oiio is None:  # checked every time: a module that cannot be imported draws nothing
        return False
    if _render_text_works is None:
        ok = False
        if oiio is not None:
            probe = oiio.ImageBuf(oiio.ImageSpec(16, 16, 1, oiio.FLOAT))
            try:
                ok = bool(oiio.ImageBufAlgo.render_text(probe, 1, 8, "1", 10, "", (1.0,), "left", "center"))
            except Exception:  # noqa: BLE001 - bindings without text support raise instead of returning False
                ok = False
            ok = ok and float(np.asarray(probe.get_pixels(oiio.FLOAT)).max()) > 0.0
        _render_text_works = ok
    return _render_text_works


def use_oiio(text: str) -> bool:
    """Whether a ``text`` mode ("auto", "oiio", "bitmap", "none") draws with OpenImageIO; "oiio" where
    it cannot draw raises ``RuntimeError``."""
    if text not in TEXT_MODES:
        raise ValueError(f"text must be {', '.join(TEXT_MODES)}, not {text!r}")
    if text == "oiio" and not render_text_available():
        raise RuntimeError("OpenImageIO cannot render text here (no FreeType)")
    return text == "oiio" or (text == "auto" and render_text_available())


def text_width(text: str, size: int, oiio_text: bool) -> int:
    """Width in pixels of ``text`` on one line: ``size`` is OpenImageIO's font size in pixels, and
    for the bitmap font its scale is ``bitmap_scale(size)``."""
    if oiio_text:
        return int(optional_oiio().ImageBufAlgo.text_size(text, size, "").width)
    return bitmap_font.ADVANCE_W * bitmap_scale(size) * len(text)


def bitmap_scale(size: int) -> int:
    """The bitmap font's integer scale for a line ``size`` pixels high (a glyph is 7 px + 1 px gap)."""
    return max(1, size // bitmap_font.LINE_H)


def fitting(alternatives: Sequence[str], room: int, measure: Callable[[str], int]) -> str:
    """The first label that fits in ``room`` pixels, else the last (the shortest; clipped when drawn)."""
    return next((t for t in alternatives if measure(t) <= room), alternatives[-1])


def shorten(text: str, room: int, char_width: int) -> str:
    """``text`` cut to ``room`` pixels of ``char_width``-wide characters, ending in "..." when cut."""
    fits = max(1, room // char_width)
    return text if len(text) <= fits else text[: max(1, fits - 3)] + "..."


def coverage(text: str, width: int, height: int, *, size: int, oiio_text: bool, align: str = "left",
             inset: int = 0, top: int | None = None) -> np.ndarray:
    """Coverage in [0, 1] (float32, ``height`` x ``width``) of ``text`` on one line, starting
    ``inset`` px from the left (or ending there, ``align="right"``), its top ``top`` px down (None:
    vertically centred); whatever does not fit is clipped. ``size``: the line height in px
    (OpenImageIO's font size; the bitmap font uses the largest integer scale that fits)."""
    if oiio_text:
        oiio = optional_oiio()
        buf = oiio.ImageBuf(oiio.ImageSpec(width, height, 1, oiio.FLOAT))
        x = width - 1 - inset if align == "right" else inset
        y, valign = (height // 2, "center") if top is None else (top, "top")
        if oiio.ImageBufAlgo.render_text(buf, x, y, text, size, "", (1.0,), align, valign):
            return np.asarray(buf.get_pixels(oiio.FLOAT), dtype=np.float32).reshape(height, width)
    mask = bitmap_font.text_mask(text, bitmap_scale(size))
    out = np.zeros((height, width), dtype=np.float32)
    room = max(0, width - inset)
    y0 = (height - min(mask.shape[0], height)) // 2 if top is None else min(max(0, top), height)
    mh, mw = min(mask.shape[0], height - y0), min(mask.shape[1], room)
    x0 = width - inset - mw if align == "right" else inset
    out[y0:y0 + mh, x0:x0 + mw] = mask[:mh, :mw]
    return out

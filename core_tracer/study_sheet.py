"""The contact sheet of a study: the variants in a grid, labelled, written as EXR and PNG.

Axis 1 runs along the columns, axis 2 (if any) down the rows. Above the grid: the title and the
names of the two parameters; above each column its value of axis 1, left of each row its value
of axis 2; under each image the variant's values. ``layout(study)`` computes every rectangle
and is a pure function of the study, so the geometry is testable without rendering.

Composition uses OpenImageIO (``ImageBufAlgo.paste``; labels with ``render_text`` and its
bundled font). Where ``render_text`` is unavailable (the OpenImageIO inside Blender has no
FreeType) the labels are drawn with ``bitmap_font``; without OpenImageIO at all the sheet is
composed in numpy (same pixels) and only the file writers need it.

Files: EXR is linear float with the study JSON in the header attribute ``lamp:study``; PNG is
8-bit sRGB with the same JSON as a text chunk. ``Study.load(sheet)`` reads it back.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from . import bitmap_font
from .imageio import load_writer, oiio_module, write_image
from .study import STUDY_ATTRIBUTE, Study, format_value

BACKGROUND = (0.018, 0.018, 0.02)  # linear; a dark grey that sets off the black of each render
TEXT_COLOR = (0.75, 0.75, 0.75)
MIN_TEXT_CHARS = 28  # the sheet is at least this many characters wide, so a title fits


@dataclass(frozen=True)
class Rect:
    x: int
    y: int
    w: int
    h: int


@dataclass(frozen=True)
class TextBox:
    text: str
    rect: Rect
    kind: str  # "title", "axes", "column", "row", "cell"


@dataclass(frozen=True)
class SheetLayout:
    width: int
    height: int
    scale: int  # text scale: a line is 8*scale px high (bitmap font), a character 6*scale px wide
    cells: tuple[Rect, ...]  # where each variant's image goes, in variant order
    texts: tuple[TextBox, ...]

    @property
    def line_height(self) -> int:
        return (bitmap_font.LINE_H + 2) * self.scale

    @property
    def char_width(self) -> int:
        return bitmap_font.ADVANCE_W * self.scale


def text_scale(size: tuple[int, int]) -> int:
    """Label size follows the image size: 1 below 96 px, 2 below 384 px, 3 above."""
    side = min(size)
    return 1 if side < 96 else 2 if side < 384 else 3


def cell_lines(study: Study, index: int) -> list[str]:
    """The label under one variant: one line per axis, ``name=value``."""
    v = study.variants[index]
    return [f"{a.parameter.short}={format_value(x)}" for a, x in zip(study.axes, v.values, strict=True)]


def layout(study: Study) -> SheetLayout:
    """Every rectangle of the sheet of ``study`` (pixels, origin top-left)."""
    w, h = study.size
    s = text_scale(study.size)
    adv = bitmap_font.ADVANCE_W * s
    line = (bitmap_font.LINE_H + 2) * s
    pad = 4 * s
    gap = pad
    axes = study.axes
    n_lines = len(axes)

    widest_cell = max(len(t) for i in range(len(study)) for t in cell_lines(study, i))
    column_labels = [f"{axes[0].parameter.short}={format_value(x)}" for x in axes[0].values]
    cell_w = max(w, widest_cell * adv, max(len(t) for t in column_labels) * adv)
    cell_h = h + pad // 2 + n_lines * line
    if len(axes) > 1:
        row_labels = [f"{axes[1].parameter.short}={format_value(x)}" for x in axes[1].values]
        row_header = max(len(t) for t in row_labels) * adv + pad
    else:
        row_labels = []
        row_header = 0

    grid_x = pad + row_header
    grid_w = study.columns * cell_w + (study.columns - 1) * gap
    width = max(grid_x + grid_w + pad, 2 * pad + MIN_TEXT_CHARS * adv)
    top = pad + 2 * line + pad  # title line and axes line
    grid_y = top + line  # the column header strip
    height = grid_y + study.rows * cell_h + (study.rows - 1) * gap + pad

    texts = [TextBox(study.heading(), Rect(pad, pad, width - 2 * pad, line), "title")]
    axes_text = f"columns: {axes[0].parameter.text}"
    if len(axes) > 1:
        axes_text += f"   rows: {axes[1].parameter.text}"
    texts.append(TextBox(axes_text, Rect(pad, pad + line, width - 2 * pad, line), "axes"))
    for c, label in enumerate(column_labels):
        texts.append(TextBox(label, Rect(grid_x + c * (cell_w + gap), top, cell_w, line), "column"))
    for r, label in enumerate(row_labels):
        y = grid_y + r * (cell_h + gap) + (h - line) // 2
        texts.append(TextBox(label, Rect(pad, max(y, grid_y), row_header - pad, line), "row"))

    cells = []
    for v in study.variants:
        x0 = grid_x + v.column * (cell_w + gap)
        y0 = grid_y + v.row * (cell_h + gap)
        cells.append(Rect(x0 + (cell_w - w) // 2, y0, w, h))
        for k, text in enumerate(cell_lines(study, v.index)):
            texts.append(TextBox(text, Rect(x0, y0 + h + pad // 2 + k * line, cell_w, line), "cell"))
    return SheetLayout(width, height, s, tuple(cells), tuple(texts))


# ---------------------------------------------------------------------------------------------
# Composition


def _oiio():
    try:
        return oiio_module()
    except ImportError:
        return None


_render_text_works: bool | None = None


def render_text_available() -> bool:
    """Whether this OpenImageIO can draw text (it cannot without FreeType, as inside Blender)."""
    global _render_text_works
    if _render_text_works is None:
        oiio = _oiio()
        ok = False
        if oiio is not None:
            probe = oiio.ImageBuf(oiio.ImageSpec(16, 16, 1, oiio.FLOAT))
            try:
                ok = bool(oiio.ImageBufAlgo.render_text(probe, 1, 8, "1", 10, "", (1.0,), "left", "center"))
            except Exception:  # bindings without text support raise instead of returning False
                ok = False
            ok = ok and float(np.asarray(probe.get_pixels(oiio.FLOAT)).max()) > 0.0
        _render_text_works = ok
    return _render_text_works


def preload_writers() -> None:
    """Load what composing and writing a sheet need, before a study renders (``imageio.load_writer``)."""
    load_writer()
    render_text_available()


def _fit(text: str, width: int, char_width: int) -> str:
    room = max(1, width // char_width)
    return text if len(text) <= room else text[: max(1, room - 3)] + "..."


def _text_coverage(box: TextBox, scale: int, char_width: int, use_oiio: bool) -> np.ndarray:
    """Coverage in [0, 1] of ``box.text`` drawn in a (h, w) array the size of its rectangle."""
    r = box.rect
    text = _fit(box.text, r.w, char_width)
    if use_oiio:
        oiio = _oiio()
        buf = oiio.ImageBuf(oiio.ImageSpec(r.w, r.h, 1, oiio.FLOAT))
        align = "right" if box.kind == "row" else "left"
        x = r.w - 1 if box.kind == "row" else 0
        if oiio.ImageBufAlgo.render_text(buf, x, r.h // 2, text, 10 * scale, "", (1.0,), align, "center"):
            return np.asarray(buf.get_pixels(oiio.FLOAT), dtype=np.float32).reshape(r.h, r.w)
    mask = bitmap_font.text_mask(text, scale)
    out = np.zeros((r.h, r.w), dtype=np.float32)
    mh, mw = min(mask.shape[0], r.h), min(mask.shape[1], r.w)
    y0 = (r.h - mh) // 2
    x0 = r.w - mw if box.kind == "row" else 0
    out[y0:y0 + mh, x0:x0 + mw] = mask[:mh, :mw]
    return out


def compose(study: Study, images: Sequence[np.ndarray], *, text: str = "auto") -> np.ndarray:
    """The contact sheet (H, W, 3 float32 linear, top row first) of the rendered variants.

    ``text``: ``"auto"`` (OpenImageIO's ``render_text`` where it works, else the bitmap font),
    ``"oiio"``, ``"bitmap"`` or ``"none"``.
    """
    if len(images) != len(study):
        raise ValueError(f"expected {len(study)} images, got {len(images)}")
    lay = layout(study)
    w, h = study.size
    for i, img in enumerate(images):
        if np.shape(img) != (h, w, 3):
            raise ValueError(f"image {i}: expected shape {(h, w, 3)}, got {np.shape(img)}")
    if text not in ("auto", "oiio", "bitmap", "none"):
        raise ValueError(f"text must be auto, oiio, bitmap or none, not {text!r}")
    oiio = _oiio()
    use_oiio_text = text == "oiio" or (text == "auto" and render_text_available())
    if use_oiio_text and not render_text_available():
        raise RuntimeError("OpenImageIO cannot render text here (no FreeType)")

    if oiio is not None:
        sheet = oiio.ImageBuf(oiio.ImageSpec(lay.width, lay.height, 3, oiio.FLOAT))
        oiio.ImageBufAlgo.fill(sheet, BACKGROUND)
        for rect, img in zip(lay.cells, images, strict=True):
            cell = oiio.ImageBuf(oiio.ImageSpec(rect.w, rect.h, 3, oiio.FLOAT))
            cell.set_pixels(oiio.ROI(0, rect.w, 0, rect.h, 0, 1, 0, 3), np.ascontiguousarray(img, dtype=np.float32))
            if not oiio.ImageBufAlgo.paste(sheet, rect.x, rect.y, 0, 0, cell):
                raise RuntimeError(f"cannot paste a variant into the sheet ({oiio.geterror()})")
        canvas = np.asarray(sheet.get_pixels(oiio.FLOAT), dtype=np.float32).reshape(lay.height, lay.width, 3)
        canvas = np.array(canvas)  # writable
    else:
        canvas = np.empty((lay.height, lay.width, 3), dtype=np.float32)
        canvas[:] = BACKGROUND
        for rect, img in zip(lay.cells, images, strict=True):
            canvas[rect.y:rect.y + rect.h, rect.x:rect.x + rect.w] = img

    if text != "none":
        color = np.asarray(TEXT_COLOR, dtype=np.float32)
        for box in lay.texts:
            r = box.rect
            if r.w <= 0 or r.h <= 0:
                continue
            m = _text_coverage(box, lay.scale, lay.char_width, use_oiio_text)[..., None]
            region = canvas[r.y:r.y + r.h, r.x:r.x + r.w]
            region[:] = region * (1.0 - m) + color * m
    return canvas


# ---------------------------------------------------------------------------------------------
# Files


def write_sheet(path: str | os.PathLike, study: Study, sheet: np.ndarray, *, exposure: float = 0.0) -> None:
    """Write a composed sheet as EXR (linear float) or PNG (8-bit sRGB, ``exposure`` stops
    applied), chosen by the suffix, with the study JSON in the ``lamp:study`` attribute.
    Atomic: never a partial file."""
    write_image(path, sheet, attributes={STUDY_ATTRIBUTE: study.to_json(), "ImageDescription": study.heading()},
                exposure=exposure)

"""The contact sheet of a study: the variants in a grid, labelled, written as EXR and PNG.

Axis 1 runs along the columns, axis 2 (if any) down the rows. Above the grid: the title and the
names of the two parameters; above each column its value of axis 1, left of each row its value
of axis 2, each with its unit (``spec``: "height=0.5 mm"), each said once; under each image its
measures, if any. A sorted or filtered sheet, whose places no longer say the values, gives each
cell its values under it instead. ``layout(study)`` computes every rectangle
and is a pure function of the study, so the geometry is testable without rendering.

Composition is numpy; labels come from ``images.labels`` (OpenImageIO's font where it can draw
text, else the bitmap font), so a sheet is made without OpenImageIO and only the files need it.
Every cell goes to the screen through ``display.shown`` (as its variant's light model says: RGB, or
XYZ in cd/m²), all at one exposure, so the cells compare: a brighter bulb shows as a brighter cell.

Files: EXR is linear float with the study JSON in the header attribute ``lamp:study``; PNG shows
the variants through a view transform (``images.display``) with the labels drawn on the display
side, so they read whatever the exposure; the same JSON rides as a text chunk. ``Study.load(sheet)``
reads it back.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..images import bitmap_font, display, labels
from ..images.imageio import EXPOSURE_ATTRIBUTE, image_format, load_writer, write_display, write_image
from .definition import STUDY_ATTRIBUTE, Study, format_value
from .measured import arrange, format_measure

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
    cells: tuple[Rect | None, ...]  # where each variant's image goes, in variant order (None: filtered out)
    texts: tuple[TextBox, ...]

    @property
    def char_width(self) -> int:
        return bitmap_font.ADVANCE_W * self.scale


def text_scale(size: tuple[int, int]) -> int:
    """Label size follows the image size (the side of a square of as many pixels, so a cell framed on
    a wide lamp keeps readable labels): 1 below 96 px, 2 below 384 px, 3 above."""
    side = math.sqrt(size[0] * size[1])
    return 1 if side < 96 else 2 if side < 384 else 3


def value_label(parameter, value) -> str:
    """``name=value unit``: "height=0.5 mm", "ior=1.5", "cuts.type=fisheye" (the field's unit, ``spec``)."""
    unit = getattr(parameter.spec, "unit", "")
    return f"{parameter.short}={format_value(value)}" + (f" {unit}" if unit else "")


def measure_lines(study: Study, index: int, measured: Sequence[dict] | None) -> list[str]:
    """One line per measure of one variant (none without ``measured``)."""
    if measured is None:
        return []
    return [format_measure(name, measured[index][name]) for name in study.measured.names]


def cell_lines(study: Study, index: int, measured: Sequence[dict] | None = None) -> list[str]:
    """A variant's full label: one line per axis, ``name=value unit``, then one per measure (under the
    cells of a sorted or filtered sheet, in its footer; a grid says the values in its headers)."""
    v = study.variants[index]
    lines = [value_label(a.parameter, x) for a, x in zip(study.axes, v.values, strict=True)]
    return lines + measure_lines(study, index, measured)


def layout(study: Study, measured: Sequence[dict] | None = None) -> SheetLayout:
    """Every rectangle of the sheet of ``study`` (pixels, origin top-left); with ``measured`` (each
    variant's values of ``study.measured.names``) the values go under the cells, and a sorted or
    filtered study places the kept cells in its order, row by row, and lists the others in a footer."""
    if measured is not None and len(measured) != len(study):
        raise ValueError(f"expected {len(study)} measured variants, got {len(measured)}")
    if measured is not None and study.measured.reorders:
        return _ordered_layout(study, measured)
    w, h = study.size
    s = text_scale(study.size)
    adv = bitmap_font.ADVANCE_W * s
    line = (bitmap_font.LINE_H + 2) * s
    pad = 4 * s
    gap = pad
    axes = study.axes
    n_lines = len(study.measured.names) if measured is not None else 0  # the axis values are in the headers

    widest_cell = max((len(t) for i in range(len(study)) for t in measure_lines(study, i, measured)), default=0)
    column_labels = [value_label(axes[0].parameter, x) for x in axes[0].values]
    cell_w = max(w, widest_cell * adv, max(len(t) for t in column_labels) * adv)
    cell_h = h + (pad // 2 + n_lines * line if n_lines else 0)
    if len(axes) > 1:
        row_labels = [value_label(axes[1].parameter, x) for x in axes[1].values]
        row_header = max(len(t) for t in row_labels) * adv + pad
    else:
        row_labels = []
        row_header = 0

    grid_x = pad + row_header
    grid_w = study.columns * cell_w + (study.columns - 1) * gap
    axes_text = f"columns: {axes[0].parameter.text}"
    if len(axes) > 1:
        axes_text += f"   rows: {axes[1].parameter.text}"
    # wide enough for the axes line (what the sheet shows is named in full) and a short title
    width = max(grid_x + grid_w + pad, 2 * pad + max(MIN_TEXT_CHARS, len(axes_text)) * adv)
    top = pad + 2 * line + pad  # title line and axes line
    grid_y = top + line  # the column header strip
    height = grid_y + study.rows * cell_h + (study.rows - 1) * gap + pad

    texts = [TextBox(study.heading(), Rect(pad, pad, width - 2 * pad, line), "title")]
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
        for k, text in enumerate(measure_lines(study, v.index, measured)):
            texts.append(TextBox(text, Rect(x0, y0 + h + pad // 2 + k * line, cell_w, line), "cell"))
    return SheetLayout(width, height, s, tuple(cells), tuple(texts))


def _ordered_layout(study: Study, measured: Sequence[dict]) -> SheetLayout:
    """The sheet of a sorted or filtered study: the kept cells in order, ``study.columns`` a row (the
    position no longer says the axis values: each cell's label does), the rest in the footer."""
    w, h = study.size
    s = text_scale(study.size)
    adv = bitmap_font.ADVANCE_W * s
    line = (bitmap_font.LINE_H + 2) * s
    pad = gap = 4 * s
    order, dropped = arrange(study.measured, measured)
    labels_of = {i: cell_lines(study, i, measured) for i in range(len(study))}
    columns = max(1, min(study.columns, len(order)))
    rows = math.ceil(len(order) / columns)
    cell_w = max(w, max(len(t) for lines in labels_of.values() for t in lines) * adv)
    cell_h = h + pad // 2 + len(labels_of[0]) * line
    choice = study.measured
    how = "   ".join(([f"sorted by {choice.sort}"] if choice.sort else [])
                     + ([f"filter {' and '.join(str(f) for f in choice.filters)}"] if choice.filters else []))
    axes_text = "varied: " + ", ".join(a.parameter.text for a in study.axes)
    grid_w = columns * cell_w + (columns - 1) * gap
    footer = [f"left out by the filter ({len(dropped)}):" if dropped else "left out by the filter: none"]
    footer += [f"  #{i + 1} " + "  ".join(labels_of[i]) for i in dropped] if choice.filters else []
    if not choice.filters:
        footer = []
    width = max(pad + grid_w + pad, 2 * pad + max(MIN_TEXT_CHARS, len(axes_text), len(how),
                                                  *(len(t) for t in footer)) * adv)
    top = pad + 3 * line + pad  # title, axes and order lines
    grid_y = top
    grid_h = rows * cell_h + max(0, rows - 1) * gap
    height = grid_y + grid_h + pad + len(footer) * line + pad
    texts = [TextBox(study.heading(), Rect(pad, pad, width - 2 * pad, line), "title"),
             TextBox(axes_text, Rect(pad, pad + line, width - 2 * pad, line), "axes"),
             TextBox(how, Rect(pad, pad + 2 * line, width - 2 * pad, line), "axes")]
    cells: list[Rect | None] = [None] * len(study)
    for k, index in enumerate(order):
        x0 = pad + (k % columns) * (cell_w + gap)
        y0 = grid_y + (k // columns) * (cell_h + gap)
        cells[index] = Rect(x0 + (cell_w - w) // 2, y0, w, h)
        for j, text in enumerate(labels_of[index]):
            texts.append(TextBox(text, Rect(x0, y0 + h + pad // 2 + j * line, cell_w, line), "cell"))
    y = grid_y + grid_h + pad
    for k, text in enumerate(footer):
        texts.append(TextBox(text, Rect(pad, y + k * line, width - 2 * pad, line), "footer"))
    return SheetLayout(width, height, s, tuple(cells), tuple(texts))


# ---------------------------------------------------------------------------------------------
# Composition


def preload_writers() -> None:
    """Load what composing and writing a sheet need before a study renders (``imageio.load_writer``):
    an interrupt that lands while OpenImageIO is half imported then ends the program cleanly."""
    load_writer()
    labels.render_text_available()


def compose(study: Study, images: Sequence[np.ndarray], *, text: str = "auto", exposure: float | str = 0.0,
            view: display.ViewTransform | None = None, measured: Sequence[dict] | None = None,
            ev100: float | str | None = None, stops: float = 0.0, as_values: bool = False) -> np.ndarray:
    """The contact sheet (H, W, 3 float32, top row first) of the rendered variants; ``composed``
    without the exposure it chose."""
    return composed(study, images, text=text, exposure=exposure, view=view, measured=measured, ev100=ev100,
                    stops=stops, as_values=as_values)[0]


def composed(study: Study, images: Sequence[np.ndarray], *, text: str = "auto", exposure: float | str = 0.0,
             view: display.ViewTransform | None = None, measured: Sequence[dict] | None = None,
             ev100: float | str | None = None, stops: float = 0.0,
             as_values: bool = False) -> tuple[np.ndarray, display.Exposure]:
    """(the contact sheet, H, W, 3 float32, top row first; the exposure of its cells).

    The cells are the variants' renders shown through ``display.shown`` (each as its variant's light
    model says: XYZ in cd/m² or RGB), all at ONE exposure: paper-mode cells at ``exposure`` stops
    ("auto": measured over all of them), photometric cells at ONE EV100 (``ev100``; None: the first
    photometric variant's camera; "auto": measured over all) and ``stops`` more. Without ``view`` the
    sheet is scene-linear (for an EXR, or for Blender to show through its view); with it the sheet
    holds display values in [0, 1] (background and labels too). ``as_values``: the cells as they
    are (the XYZ of a photometric sheet's .exr), no exposure.

    ``measured``: each variant's measure values (``layout``).

    ``text``: ``"auto"`` (OpenImageIO's ``render_text`` where it works, else the bitmap font),
    ``"oiio"``, ``"bitmap"`` or ``"none"``.
    """
    if len(images) != len(study):
        raise ValueError(f"expected {len(study)} images, got {len(images)}")
    lay = layout(study, measured)
    w, h = study.size
    for i, img in enumerate(images):
        if np.shape(img) != (h, w, 3):
            raise ValueError(f"image {i}: expected shape {(h, w, 3)}, got {np.shape(img)}")
    oiio_text = labels.use_oiio(text)
    if as_values:
        cells, used = [np.asarray(img, np.float32) for img in images], display.Exposure()
    else:
        shown = display.shown(list(images), [v.scene for v in study.variants], view=view, ev100=ev100, stops=stops,
                              exposure=exposure)
        cells, used = shown.pixels, shown.exposure

    background, color = np.asarray(BACKGROUND, np.float32), np.asarray(TEXT_COLOR, np.float32)
    if view is not None:  # the same greys as a linear sheet shows under Standard
        background, color = (display.srgb_encode(c).astype(np.float32) for c in (background, color))
    canvas = np.empty((lay.height, lay.width, 3), dtype=np.float32)
    canvas[:] = background
    for rect, cell in zip(lay.cells, cells, strict=True):
        if rect is None:  # left out by the filter: named in the footer
            continue
        canvas[rect.y:rect.y + rect.h, rect.x:rect.x + rect.w] = cell

    if text != "none":
        size = (bitmap_font.LINE_H + 2) * lay.scale
        for box in lay.texts:
            r = box.rect
            if r.w <= 0 or r.h <= 0:
                continue
            line = labels.shorten(box.text, r.w, lay.char_width)
            m = labels.coverage(line, r.w, r.h, size=size, oiio_text=oiio_text,
                                align="right" if box.kind == "row" else "left")[..., None]
            region = canvas[r.y:r.y + r.h, r.x:r.x + r.w]
            region[:] = region * (1.0 - m) + color * m
    return canvas, used


# ---------------------------------------------------------------------------------------------
# Files


def write_sheet(path: str | os.PathLike, study: Study, images: Sequence[np.ndarray], *,
                view: display.ViewTransform | None = None, exposure: float | str | None = "auto",
                text: str = "auto", measured: Sequence[dict] | None = None, ev100: float | str | None = None,
                stops: float = 0.0) -> display.Exposure:
    """Compose the sheet of the rendered variants and write it, with the study JSON in the
    ``lamp:study`` attribute: EXR scene-linear (paper cells as rendered), PNG through ``view``
    (default the lamp view, ``display.LAMP_VIEW``) at one exposure for every cell (``composed``). Returns
    the exposure applied. Atomic: never a partial file."""
    attributes = {STUDY_ATTRIBUTE: study.to_json(), "ImageDescription": study.heading()}
    if image_format(path) == "exr":
        sheet, used = composed(study, images, text=text, measured=measured, ev100=ev100, stops=stops)
        write_image(path, sheet, attributes={**attributes, **_exposure_attributes(used)})
        return used
    view = view or display.view_transform(display.LAMP_VIEW)
    shown, used = composed(study, images, text=text, exposure="auto" if exposure is None else exposure, view=view,
                           measured=measured, ev100=ev100, stops=stops)
    write_display(path, shown, attributes={**attributes, **_exposure_attributes(used)}, view=view.view,
                  exposure=used.paper_stops if used.paper_stops is not None else used.stops)
    return used


def _exposure_attributes(used: display.Exposure) -> dict[str, str]:
    """The photometric cells' EV100 in the header (``images.photometric.EV100_ATTRIBUTE``)."""
    return {"lamp:ev100": f"{used.ev100:g}"} if used.ev100 is not None else {}


def write_composed(path: str | os.PathLike, study: Study, sheet: np.ndarray, *,
                   view: display.ViewTransform | None = None, exposure: float = 0.0,
                   view_exposure: float = 0.0, ev100: float | None = None) -> None:
    """Write a sheet composed already (linear, its variants scaled by ``exposure`` stops, as Blender
    shows it): EXR as it is, with ``lamp:exposure`` saying how the variants were scaled (and
``lamp:ev100`` the EV100 of its photometric cells); PNG
    through ``view`` at ``view_exposure`` more stops (Blender's own exposure slider). Atomic: never
    a partial file."""
    attributes = {STUDY_ATTRIBUTE: study.to_json(), "ImageDescription": study.heading(),
                  **_exposure_attributes(display.Exposure(ev100))}
    if image_format(path) == "exr":
        write_image(path, sheet, attributes={**attributes, EXPOSURE_ATTRIBUTE: f"{exposure:g}"})
        return
    view = view or display.view_transform()
    write_display(path, view.to_display(sheet, view_exposure), attributes=attributes, view=view.view,
                  exposure=exposure + view_exposure)

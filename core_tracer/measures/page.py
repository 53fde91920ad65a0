"""The one-page report of the measures, drawn with numpy alone: a real Blender's Python has numpy and
nothing else (no matplotlib; the worker it starts does not see the OpenImageIO Blender bundles, whose
copy has no FreeType anyway), so the page is a raster drawn here: rectangles, lines, a colour map and
the project's 5 × 7 bitmap font (``images.bitmap_font``, capitals), written by ``images.png``.

Why not bundle matplotlib: its cp311 wheels and those it needs (contourpy, kiwisolver, pillow,
fonttools, cycler, pyparsing, python-dateutil, six, packaging; matplotlib 3.11.2, measured with ``pip
download --no-deps`` on 2026-12-07) weigh 25 MB for linux-x64, 19 MB for windows-x64 and 18 MB for
macos-arm64, each zip growing by that for one page; and a bundled packaging or pillow would be shared
with, and could break, other add-ons.

The page (1800 × 1300 px): the verdict on top (red when a function fails); the rendered lamp; the
front luminance (log scale, the inferno colour map) with the dark areas outlined in cyan and each
function's homogeneity figures; each function's UN R148 grid as cells at (H, V), green where a point
passes and red where it fails (a red border where a maximum is exceeded there), the simulated cd over
the required; the chromaticity diagram (the spectral locus, R48's regions solid, J578's dashed, each
function's light as a dot, black-rimmed inside, red-rimmed outside); the FMVSS 108 and ratio verdicts,
the failed points and the times.
"""

from __future__ import annotations

import os

import numpy as np

from ..images.bitmap_font import ADVANCE_W, LINE_H, text_mask
from ..images.png import write_png
from .functions import FUNCTIONS, NOTE

WIDTH, HEIGHT = 1800, 1300
INK = (0.1, 0.1, 0.1)
GREY = (0.45, 0.45, 0.45)
FAIL = (0.69, 0.13, 0.10)
PASS_FILL = (0.23, 0.60, 0.29)
FAIL_FILL = (0.82, 0.20, 0.17)
TINTS = {"red": (0.75, 0.22, 0.17), "amber": (0.88, 0.56, 0.04), "white": (0.50, 0.55, 0.55)}
# matplotlib's "inferno" (van der Walt and Smith, BIDS colormaps, CC0) at 0, 1/8, ..., 1: perceptually
# ordered, dark to bright, so a brighter lens reads as brighter in print and for colour-blind readers
INFERNO = np.array([(0, 0, 4), (31, 12, 72), (85, 15, 109), (136, 34, 106), (186, 54, 85), (227, 89, 51),
                    (249, 140, 10), (249, 201, 50), (252, 255, 164)], float) / 255.0
# Characters the bitmap font lacks, spelled in those it has.
_SPELLED = {"≥": ">=", "≤": "<=", "°": " DEG", "²": "2", "γ": "G", "×": "X", "“": '"', "”": '"', "—": "-",
            "–": "-", "§": "S", "±": "+-", "·": ".", "|": "/", "\u00a0": " "}


def ascii_text(text: str) -> str:
    return "".join(_SPELLED.get(ch, ch) for ch in str(text))


class Canvas:
    """An RGB float image, top row first, with the few shapes the page needs (pixel coordinates)."""

    def __init__(self, width: int, height: int):
        self.rgb = np.ones((height, width, 3), np.float32)

    @property
    def height(self) -> int:
        return self.rgb.shape[0]

    @property
    def width(self) -> int:
        return self.rgb.shape[1]

    def rect(self, x0: float, y0: float, x1: float, y1: float, colour, edge=None, edge_px: int = 1) -> None:
        x0, x1 = sorted((int(round(x0)), int(round(x1))))
        y0, y1 = sorted((int(round(y0)), int(round(y1))))
        x0, y0, x1, y1 = max(x0, 0), max(y0, 0), min(x1, self.width), min(y1, self.height)
        if x1 <= x0 or y1 <= y0:
            return
        if colour is not None:
            self.rgb[y0:y1, x0:x1] = colour
        if edge is not None:
            e = edge_px
            for part in ((y0, y0 + e, x0, x1), (y1 - e, y1, x0, x1), (y0, y1, x0, x0 + e), (y0, y1, x1 - e, x1)):
                self.rgb[part[0]:part[1], part[2]:part[3]] = edge

    def text(self, x: float, y: float, text: str, scale: int = 2, colour=INK, align: str = "left") -> int:
        """Draw ``text`` with its top-left (or top-centre, top-right) at (x, y); returns its width."""
        mask = text_mask(ascii_text(text), scale)
        h, w = mask.shape
        x = int(round(x - (w / 2 if align == "center" else w if align == "right" else 0)))
        y = int(round(y))
        xs, ys = max(x, 0), max(y, 0)
        xe, ye = min(x + w, self.width), min(y + h, self.height)
        if xe > xs and ye > ys:
            m = mask[ys - y:ye - y, xs - x:xe - x, None]
            region = self.rgb[ys:ye, xs:xe]
            region[:] = region * (1 - m) + np.asarray(colour, np.float32) * m
        return w

    def line(self, points, colour, width: int = 1, dash: float = 0.0) -> None:
        """A polyline through ``points`` (N, 2) in pixels; ``dash`` > 0: dashes and gaps that long."""
        p = np.asarray(points, float)
        travelled = 0.0
        for a, b in zip(p[:-1], p[1:], strict=True):
            length = float(np.hypot(*(b - a)))
            n = max(2, int(length * 2) + 1)
            t = np.linspace(0.0, 1.0, n)
            pts = a + (b - a) * t[:, None]
            if dash > 0:
                keep = ((travelled + t * length) // dash) % 2 == 0
                pts = pts[keep]
            travelled += length
            r = width // 2
            for dy in range(-r, width - r):
                for dx in range(-r, width - r):
                    x = np.rint(pts[:, 0]).astype(int) + dx
                    y = np.rint(pts[:, 1]).astype(int) + dy
                    ok = (x >= 0) & (x < self.width) & (y >= 0) & (y < self.height)
                    self.rgb[y[ok], x[ok]] = colour

    def disc(self, x: float, y: float, radius: float, colour, rim=None, rim_px: int = 2) -> None:
        yy, xx = np.mgrid[0:self.height, 0:self.width]
        y0, y1 = int(max(0, y - radius - 1)), int(min(self.height, y + radius + 2))
        x0, x1 = int(max(0, x - radius - 1)), int(min(self.width, x + radius + 2))
        d = np.hypot(xx[y0:y1, x0:x1] - x, yy[y0:y1, x0:x1] - y)
        region = self.rgb[y0:y1, x0:x1]
        region[d <= radius] = rim if rim is not None else colour
        region[d <= radius - rim_px] = colour

    def image(self, x: int, y: int, width: int, height: int, picture: np.ndarray) -> tuple[int, int, int, int]:
        """``picture`` (H, W, 3 in [0, 1]) fitted into the box, aspect kept (area-averaged when shrunk,
        nearest when enlarged), centred; returns the box it took."""
        ph, pw = picture.shape[:2]
        s = min(width / pw, height / ph)
        w, h = max(1, int(pw * s)), max(1, int(ph * s))
        rows = np.minimum((np.arange(h) + 0.5) / s, ph - 1e-6).astype(int)
        cols = np.minimum((np.arange(w) + 0.5) / s, pw - 1e-6).astype(int)
        if s < 1:  # each output pixel the mean of the input pixels it covers
            edges_r = np.linspace(0, ph, h + 1).astype(int)
            edges_c = np.linspace(0, pw, w + 1).astype(int)
            summed = np.add.reduceat(np.add.reduceat(picture, edges_r[:-1], axis=0), edges_c[:-1], axis=1)
            counts = np.outer(np.diff(edges_r), np.diff(edges_c))[..., None]
            shown = summed / np.maximum(counts, 1)
        else:
            shown = picture[rows][:, cols]
        x0, y0 = x + (width - w) // 2, y + (height - h) // 2
        self.rgb[y0:y0 + h, x0:x0 + w] = shown[..., :3]
        return x0, y0, w, h


def colour_map(values: np.ndarray) -> np.ndarray:
    """``values`` in [0, 1] (NaN: white) as inferno RGB."""
    v = np.clip(np.nan_to_num(values, nan=0.0), 0.0, 1.0) * (len(INFERNO) - 1)
    i = np.minimum(v.astype(int), len(INFERNO) - 2)
    t = (v - i)[..., None]
    out = INFERNO[i] * (1 - t) + INFERNO[i + 1] * t
    out[np.isnan(values)] = 1.0
    return out


def outline(mask: np.ndarray) -> np.ndarray:
    """The pixels of ``mask`` with a 4-neighbour outside it: its edge, for drawing the dark areas."""
    inner = mask.copy()
    inner[1:] &= mask[:-1]
    inner[:-1] &= mask[1:]
    inner[:, 1:] &= mask[:, :-1]
    inner[:, :-1] &= mask[:, 1:]
    return mask & ~inner


def draw(result, lamp_image: np.ndarray | None = None) -> np.ndarray:
    """The page of ``result`` (a ``report.Measures``) as RGB in [0, 1] (module docstring)."""

    page = Canvas(WIDTH, HEIGHT)
    verdicts = result.verdicts()
    failing = [k for k, ok in verdicts.items() if not ok]
    passing = [k for k, ok in verdicts.items() if ok]
    page.text(30, 24, f"Measures of “{result.scene_name}”", 3)
    summary = [(f"FAILS {', '.join(failing)}", FAIL)] if failing else [("passes every check", INK)]
    if failing and passing:
        summary.append((f"passes {', '.join(passing)}", INK))
    for k, (line, colour) in enumerate(summary):
        page.text(30, 60 + 20 * k, line[:(WIDTH - 60) // (2 * ADVANCE_W)], 2, colour)

    # Row 1: the design, and its front luminance with the homogeneity figures.
    page.text(30, 110, "the design (photometric render)", 2, GREY)
    if lamp_image is not None:
        page.image(30, 134, 840, 330, np.clip(np.asarray(lamp_image, np.float32), 0.0, 1.0))
    _front(page, result, 920, 110)

    # Row 2: each function's UN R148 grid.
    names = list(result.functions)
    for k, name in enumerate(names[:4]):
        key = FUNCTIONS[name][0]
        _grid(page, [r for r in result.rows if r.function == key], f"{name}: {key}", 30 + k * 440, 530, 410, 260)

    # Row 3: the colours, and the FMVSS 108 and ratio verdicts with the failed points.
    _chromaticity(page, result, 60, 920, 680, 300)
    _verdicts(page, result, names, 800, 880)
    page.text(30, HEIGHT - 22, NOTE + " Sources: UN R148 01 series (ECE/TRANS/WP.29/2022/92), FMVSS 108 "
              "(49 CFR 571.108), UN R48 S2.29, SAE J578 - docs/measures.md.", 1, GREY)
    return page.rgb


def _front(page: Canvas, result, x: int, y: int) -> None:
    front = result.front_view
    lum = np.asarray(front["luminance"], float)
    shown = np.log10(np.maximum(lum, 1.0))
    top = max(1.0, float(np.nanmax(shown)))
    picture = colour_map(shown / top)
    if front["dark"].any():
        picture[outline(np.asarray(front["dark"], bool))] = (0.0, 0.9, 0.9)
    some = next(iter(result.homogeneity.values()), None)
    where = (f"at {some['viewing_distance_m']:g} m (eye resolves {some['eye_resolution_mm']:.1f} mm); cyan: below "
             f"{some['dark_below_fraction_of_mean']:g} x mean") if some else ""
    page.text(x, y, "front view from H-V: luminance, log scale", 2, GREY)
    page.text(x, y + 20, f"homogeneity {where}", 1, GREY)
    x0, y0, w, h = page.image(x, y + 34, 760, 300, picture)
    # the colour bar: log10 luminance from 0 (1 cd/m2) to the brightest
    bar = colour_map(np.linspace(1.0, 0.0, 200))[:, None, :].repeat(14, axis=1)
    page.image(x + 780, y + 34, 14, 300, bar)
    page.text(x + 800, y + 34, f"{10 ** top:.3g}", 1)
    page.text(x + 800, y + 326, "1 cd/m2", 1)
    page.text(x + 800, y + 180, "log", 1, GREY)
    row = y + 346
    for name, hg in result.homogeneity.items():
        page.text(x, row, f"{name}: Lmin/Lmax {hg['lmin_over_lmax']:.2f}  Lmin/Lmean {hg['lmin_over_lmean']:.2f}  "
                          f"CV {hg['cv']:.2f}  dark {100 * hg['dark_fraction']:.0f} %", 1)
        row += LINE_H + 4


def _grid(page: Canvas, rows, title: str, x: int, y: int, width: int, height: int) -> None:
    """A regulation grid's points at (H, V) in a box: green where they pass, red where they fail (a
    red border where a maximum fails there); the simulated cd over the required minimum."""
    points = [r for r in rows if r.kind == "min" and r.h is not None]
    maxima = [r for r in rows if r.kind == "max"]
    over = {(r.h, r.v) for r in maxima if not r.passed}
    ok = all(r.passed for r in rows)
    worst = min(maxima, key=lambda r: r.margin, default=None)
    page.text(x, y, f"{title}: {'pass' if ok else 'FAIL'}", 2, INK if ok else FAIL)
    if worst is not None:
        page.text(x, y + 20, f"max {worst.simulated:.3g} cd at {worst.point}, limit {worst.required:g} cd", 1,
                  INK if worst.passed else FAIL)
    top = y + 40
    page.rect(x, top, x + width, top + height, (0.97, 0.97, 0.97), (0.85, 0.85, 0.85))
    if not points:
        return
    hs, vs = [r.h for r in points], [r.v for r in points]
    h_lo, h_hi, v_lo, v_hi = min(hs), max(hs), min(vs), max(vs)
    h_span, v_span = max(h_hi - h_lo, 1.0), max(v_hi - v_lo, 1.0)
    margin_x, margin_y = 46, 28
    sx = (width - 2 * margin_x) / h_span
    sy = (height - 2 * margin_y) / v_span
    cell_w = min(70, 0.9 * sx * _closest(hs, h_span))
    cell_h = min(40, 0.85 * sy * _closest(vs, v_span))
    for r in points:
        cx = x + margin_x + (r.h - h_lo) * sx
        cy = top + height - margin_y - (r.v - v_lo) * sy
        edge = (1.0, 0.13, 0.13) if (r.h, r.v) in over else (1.0, 1.0, 1.0)
        page.rect(cx - cell_w / 2, cy - cell_h / 2, cx + cell_w / 2, cy + cell_h / 2,
                  PASS_FILL if r.passed else FAIL_FILL, edge, 2)
        page.text(cx, cy - 9, f"{r.simulated:.3g}", 1, (1, 1, 1), "center")
        page.text(cx, cy + 2, f">={r.required:.3g}", 1, (1, 1, 1), "center")
    for h in sorted(set(hs)):
        page.text(x + margin_x + (h - h_lo) * sx, top + height + 4, f"{h:g}", 1, GREY, "center")
    for v in sorted(set(vs)):
        page.text(x + 4, top + height - margin_y - (v - v_lo) * sy - 3, f"{v:g}", 1, GREY)
    page.text(x + width, top + height + 4, "H, DEG", 1, GREY, "right")
    page.text(x + 4, top + 4, "V, DEG", 1, GREY)


def _closest(values, default: float) -> float:
    """The smallest gap between distinct ``values`` (the cells' room)."""
    gaps = np.diff(sorted(set(values)))
    return float(gaps.min()) if len(gaps) else default


def _chromaticity(page: Canvas, result, x: int, y: int, width: int, height: int) -> None:
    from ..photometry.cie import cmfs
    from . import colour

    page.text(x - 30, y - 40, "colour at H-V (CIE 1931 xy)", 2, GREY)
    page.text(x - 30, y - 18, "UN R48 S2.29 regions solid, SAE J578 dashed", 1, GREY)
    page.rect(x, y, x + width, y + height, (0.99, 0.99, 0.99), (0.85, 0.85, 0.85))
    x_lo, x_hi, y_lo, y_hi = 0.25, 0.75, 0.20, 0.50

    def at(points) -> np.ndarray:
        p = np.asarray(points, float)
        return np.stack([x + (p[:, 0] - x_lo) / (x_hi - x_lo) * width,
                         y + height - (p[:, 1] - y_lo) / (y_hi - y_lo) * height], axis=1)

    for gx in np.arange(0.3, 0.75, 0.1):
        page.line(at([(gx, y_lo), (gx, y_hi)]), (0.92, 0.92, 0.92))
        page.text(at([(gx, y_lo)])[0, 0], y + height + 4, f"{gx:.1f}", 1, GREY, "center")
    for gy in np.arange(0.25, 0.5, 0.05):
        page.line(at([(x_lo, gy), (x_hi, gy)]), (0.92, 0.92, 0.92))
        page.text(x - 4, at([(x_lo, gy)])[0, 1] - 3, f"{gy:.2f}", 1, GREY, "right")
    wavelengths, bars = cmfs()
    keep = (wavelengths >= 380) & (wavelengths <= 700)
    locus = bars[keep] / bars[keep].sum(axis=1, keepdims=True)
    inside = (locus[:, 0] >= x_lo) & (locus[:, 1] >= y_lo) & (locus[:, 1] <= y_hi)
    page.line(at(locus[inside][:, :2]), GREY)
    for regulation, dash in (("UN R48 §2.29", 0.0), ("SAE J578", 6.0)):
        for col, corners in colour.REGIONS[regulation].items():
            poly = np.asarray(corners + (corners[0],))
            page.line(at(poly), TINTS[col], 2 if dash == 0 else 1, dash)
    for k, (name, c) in enumerate(result.colours.items()):
        px, py = at([c["xy"]])[0]
        ok = all(c["inside"].values())
        page.disc(px, py, 7, TINTS[c["required"]], INK if ok else (1.0, 0.0, 0.0))
        page.text(px + 12, py - 16 + 14 * k, f"{name} ({c['xy'][0]:.3f}, {c['xy'][1]:.3f}) {'in' if ok else 'OUT'}",
                  1, INK if ok else FAIL)


def _verdicts(page: Canvas, result, names, x: int, y: int) -> None:

    lines: list[tuple[str, tuple]] = [("FMVSS 108 and ratios:", INK)]
    for name in names:
        key = FUNCTIONS[name][1]
        rows = [r for r in result.rows if r.function == key]
        bad = [r for r in rows if not r.passed]
        lines.append((f"  {name} ({key}): {'pass' if not bad else 'FAIL'}, {len(rows)} checks"
                      + (f"; fails {', '.join(f'{r.point} {r.kind}' for r in bad[:3])}" if bad else ""),
                      INK if not bad else FAIL))
    for key in ("R148 stop/position 5:1", "FMVSS stop/taillamp"):
        rows = [r for r in result.rows if r.function == key]
        if rows:
            worst = min(rows, key=lambda r: r.margin)
            ok = all(r.passed for r in rows)
            lines.append((f"  {key}: {'pass' if ok else 'FAIL'}, lowest {worst.simulated:.1f} at {worst.point} "
                          f"(needs {worst.required:g})", INK if ok else FAIL))
    row = y
    for text, colour in lines:
        for part in wrap(text, (WIDTH - x - 20) // (2 * ADVANCE_W)):
            page.text(x, row, part, 2, colour)
            row += 2 * LINE_H + 6
    failed = [r for r in result.rows if not r.passed]
    row += 10
    page.text(x, row, f"failed points ({len(failed)}):", 2, FAIL if failed else INK)
    row += 2 * LINE_H + 6
    room = max(0, (HEIGHT - 60 - row) // (LINE_H + 6))
    shown = failed[:room]
    for k, r in enumerate(shown):
        more = f" (+{len(failed) - room} more in measures.json)" if k == len(shown) - 1 < len(failed) - 1 else ""
        page.text(x + 24, row, f"{r.function} {r.point} {r.kind}: {r.simulated:.3g} vs {r.required:.3g} "
                               f"({100 * r.margin:+.0f} %){more}", 1, FAIL)
        row += LINE_H + 6
    page.text(x, HEIGHT - 50, "times: " + ", ".join(f"{k} {v:.1f} s" for k, v in result.seconds.items()), 1, GREY)


def wrap(text: str, width: int) -> list[str]:
    """``text`` in lines of at most ``width`` characters, broken at spaces."""
    lines, line = [], ""
    for word in text.split(" "):
        if line and len(line) + 1 + len(word) > width:
            lines.append(line)
            line = "  " + word if text.startswith("  ") else word
        else:
            line = f"{line} {word}" if line else word
    return lines + [line] if line or not lines else lines


def write(result, path: str | os.PathLike, lamp_image: np.ndarray | None = None) -> None:
    """The page of ``result`` as an 8-bit PNG."""
    rgb = np.rint(np.clip(draw(result, lamp_image), 0.0, 1.0) * 255.0).astype(np.uint8)
    write_png(path, rgb, {"Title": f"Measures of {result.scene_name}", "Software": "core_tracer.measures"})

"""Make ``docs/lamp-view-agx-filmic.png``: one lit four-lamp combination (tail, stop, amber turn,
reversing) shown through Blender's views side by side, and print the colour of each lit lens.

    .venv/bin/python tools/make_lamp_view_image.py [--out docs/lamp-view-agx-filmic.png] [--size 360]
        [--stops 1]

The design is ``presets/four-lamp-night-lit-photometric.json`` (photometric, camera EV100 12), rendered
once and shown through ``images.display.shown`` at its EV100 and ``--stops`` more (a designer
brightening to read the cuts), then through each view of Blender's configuration: AgX (Blender's
default), Khronos PBR Neutral, Standard and Filmic (the project's lamp view, ``display.LAMP_VIEW``).
Under each: the median display colour (R, G, B codes) and its hue of the stop lens and the amber
turn lens (lit pixels: luminance above 2 % of the image's 99.5th percentile, split into the four
lamps left to right). The same figures are printed.
"""

from __future__ import annotations

import argparse
import colorsys
import os
import sys
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from core_tracer import load_scene, render  # noqa: E402
from core_tracer.images import display, labels  # noqa: E402
from core_tracer.images.imageio import write_display  # noqa: E402

PRESET = os.path.join(ROOT, "presets", "four-lamp-night-lit-photometric.json")
VIEWS = ("AgX", "Khronos PBR Neutral", "Standard", display.LAMP_VIEW)
LAMPS = ("tail", "stop", "turn (amber)", "reversing")
GAP = 8
TEXT = 14
BACKGROUND = 0.12


def lens_colours(shown: np.ndarray, XYZ: np.ndarray) -> list[np.ndarray]:
    """The median display colour of each of the four lit lenses, left to right."""
    Y = XYZ[..., 1]
    lit = Y > 0.02 * np.percentile(Y, 99.5)
    columns = np.nonzero(lit)[1]
    out = []
    for part in np.array_split(np.arange(columns.min(), columns.max() + 1), 4):
        mask = lit.copy()
        mask[:, :part[0]] = False
        mask[:, part[-1] + 1:] = False
        out.append(np.median(shown[mask], axis=0))
    return out


def crop_to_lamps(XYZ: np.ndarray, margin: float = 0.08) -> np.ndarray:
    """The part of the render around the lit lenses, ``margin`` of its width more on every side."""
    rows, columns = np.nonzero(XYZ[..., 1] > 0.02 * np.percentile(XYZ[..., 1], 99.5))
    pad = round(margin * (columns.max() - columns.min()))
    y0, y1 = max(0, rows.min() - pad), min(XYZ.shape[0], rows.max() + pad + 1)
    x0, x1 = max(0, columns.min() - pad), min(XYZ.shape[1], columns.max() + pad + 1)
    return XYZ[y0:y1, x0:x1]


def describe(rgb: np.ndarray) -> str:
    hue = colorsys.rgb_to_hsv(*rgb)[0] * 360.0
    r, g, b = (int(round(c * 255)) for c in rgb)
    return f"{r},{g},{b} hue {hue:.0f}"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=os.path.join(ROOT, "docs", "lamp-view-agx-filmic.png"))
    parser.add_argument("--size", type=int, default=360, help="the render's width is twice this, cropped to the lamps")
    parser.add_argument("--stops", type=float, default=1.0, help="stops above the preset's EV100")
    args = parser.parse_args(argv)
    start = time.perf_counter()
    scene = load_scene(PRESET)
    XYZ = crop_to_lamps(render(scene, 2 * args.size, round(2 * args.size * 0.625)))  # the preset's camera
    height, width = XYZ.shape[:2]
    linear = display.shown(XYZ, scene, view=None, stops=args.stops)
    ev100 = linear.exposure.ev100
    oiio_text = labels.render_text_available()
    rows = 3
    cap_h = rows * (TEXT + 6)
    sheet = np.full((2 * (height + cap_h) + 3 * GAP, 2 * width + 3 * GAP, 3), BACKGROUND, np.float32)
    for i, name in enumerate(VIEWS):
        shown = display.view_transform(name).to_display(linear.pixels[0])
        colours = lens_colours(shown, XYZ)
        lamp = " (lamp view)" if name == display.LAMP_VIEW else " (Blender's default)" if name == "AgX" else ""
        text = [f"{name}{lamp}", f"stop {describe(colours[1])}", f"amber {describe(colours[2])}"]
        print(f"{name:20s} " + "  ".join(f"{lamp_name}: {describe(c)}" for lamp_name, c in zip(LAMPS, colours,
                                                                                             strict=True)))
        x = GAP + (i % 2) * (width + GAP)
        y = GAP + (i // 2) * (height + cap_h + GAP)
        sheet[y:y + height, x:x + width] = shown
        for k, line in enumerate(text):
            mask = labels.coverage(line, width, TEXT + 6, size=TEXT, oiio_text=oiio_text, inset=4)[..., None]
            region = sheet[y + height + k * (TEXT + 6):y + height + (k + 1) * (TEXT + 6), x:x + width]
            region[:] = region * (1 - mask) + 0.9 * mask
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    write_display(args.out, sheet, view="AgX / Khronos PBR Neutral / Standard / Filmic",
                  attributes={"lamp:ev100": f"{ev100:g}", "lamp:stops": f"{args.stops:g}"})
    print(f"EV100 {ev100:g} {args.stops:+g} EV; wrote {args.out} ({sheet.shape[1]}x{sheet.shape[0]}) in "
          f"{time.perf_counter() - start:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

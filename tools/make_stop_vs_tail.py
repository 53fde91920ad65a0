"""Make ``docs/images/stop-vs-tail-photometric.png``: the P21/5W stop and tail lamps side by side
under ONE exposure, and print the colour of each red lamp against UN R48's red region.

    .venv/bin/python tools/make_stop_vs_tail.py [--out docs/images/stop-vs-tail-photometric.png] [--size 320]
        [--samples 4] [--bands K]

Top row: what a camera at the presets' common EV100 shows (XYZ in cd/m² → linear Rec.709 →
Blender's AgX), so the stop lamp shows as much brighter as it is. Bottom row: the luminance in
false colour on one shared cd/m² scale (legend on the right). Under each lamp: its lit lens's mean
luminance and its chromaticity xy, the sum of XYZ over the lit lens (pixels within 1/10 of the
image's 99th luminance percentile), i.e. the intensity-weighted mean; and whether that xy lies in
R48's red region (``photometry.regulation``, UN R48 §2.29). The same figures are printed.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from core_tracer import load_scene, render_passes  # noqa: E402
from core_tracer.images import display, labels, photometric  # noqa: E402
from core_tracer.images import photometric as photometric_images  # noqa: E402
from core_tracer.images.imageio import write_display  # noqa: E402
from core_tracer.photometry import regulation  # noqa: E402

PRESETS = (("stop", "photometric-stop-lamp.json"), ("tail", "photometric-tail-lamp.json"))
LIT_FRACTION = 0.1  # of the 99th luminance percentile: the lit lens
GAP = 8
CAPTION_LINES = 3
BACKGROUND = 0.12


def lit_lens(XYZ: np.ndarray) -> np.ndarray:
    luminance = XYZ[..., 1]
    return luminance >= LIT_FRACTION * np.percentile(luminance, 99.0)


def lens_colour(XYZ: np.ndarray) -> tuple[float, np.ndarray, int]:
    """(mean luminance cd/m², intensity-weighted xy, pixels) of the lit lens."""
    region = lit_lens(XYZ)
    total = XYZ[region].sum(axis=0)
    return float(XYZ[region][:, 1].mean()), total[:2] / total.sum(), int(region.sum())


def caption(lines: list[str], width: int, size: int) -> np.ndarray:
    oiio_text = labels.render_text_available()
    rows = []
    for line in lines:
        rows.append(labels.coverage(line, width, size + 6, size=size, oiio_text=oiio_text, inset=6))
    return np.concatenate(rows, axis=0)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=os.path.join(ROOT, "docs", "images", "stop-vs-tail-photometric.png"))
    parser.add_argument("--size", type=int, default=320, help="side of each lamp's picture in pixels")
    parser.add_argument("--samples", type=int, default=4)
    parser.add_argument("--bands", type=int, default=None, help="K (default the tracer's)")
    args = parser.parse_args(argv)
    start = time.perf_counter()
    scenes, images, stats = [], [], []
    for _, name in PRESETS:
        scene = load_scene(os.path.join(ROOT, "presets", name))
        scene["image"].update(width=args.size, height=args.size, samples=args.samples)
        result = render_passes(scene, bands=args.bands)
        scenes.append(scene)
        images.append(result.image.astype(np.float64))
        stats.append(result.stats)
    # ONE exposure: the presets' common EV100 (both say 15), else one automatic EV100 over both
    evs = {float(s["camera"]["ev100"]) for s in scenes if s["camera"].get("exposure") == "ev100"}
    common = evs.pop() if len(evs) == 1 and all(s["camera"].get("exposure") == "ev100" for s in scenes) else "auto"
    view = display.view_transform()
    together = display.shown(images, scenes, view=view, ev100=common)
    shown, ev100 = together.pixels, together.exposure.ev100
    lo, hi = photometric_images.luminance_range(np.concatenate([XYZ[..., 1].ravel() for XYZ in images]))
    false = [photometric_images.false_colour(XYZ[..., 1], lo, hi, legend=False) for XYZ in images]
    legend = photometric_images.false_colour(images[0][..., 1], lo, hi)[:, args.size:]

    size = 14 if args.size >= 256 else 10
    print(f"EV100 {ev100:g} for both ({view.view}); false colour {lo:g} to {hi:g} cd/m2; K = {stats[0]['bands']}")
    columns = []
    for (label, name), XYZ, scene in zip(PRESETS, images, scenes, strict=True):
        luminance, xy, pixels = lens_colour(XYZ)
        red = bool(regulation.in_region(xy, "red"))
        bulb = scene["lamps"][0]["bulb"]
        print(f"{label}: {name}: bulb {bulb['type']} {bulb['state']}; lit lens {pixels} px, mean luminance "
              f"{luminance:.0f} cd/m2, xy ({xy[0]:.4f}, {xy[1]:.4f}), in UN R48 red: {'yes' if red else 'NO'}")
        text = [f"{label.upper()}  {bulb['type']} {bulb['state']} filament",
                f"lens {luminance:,.0f} cd/m2",
                f"xy ({xy[0]:.3f}, {xy[1]:.3f}) {'in' if red else 'OUTSIDE'} R48 red"]
        columns.append((text, XYZ))
    w = args.size
    cap_h = CAPTION_LINES * (size + 6)
    height = 2 * w + cap_h + 3 * GAP
    width = 2 * w + 3 * GAP + legend.shape[1]
    sheet = np.full((height, width, 3), BACKGROUND, dtype=np.float32)
    for i, (text, _) in enumerate(columns):
        x = GAP + i * (w + GAP)
        sheet[GAP:GAP + w, x:x + w] = shown[i]
        cap = caption(text, w, size)[..., None]
        region = sheet[GAP + w:GAP + w + cap_h, x:x + w]
        region[:] = region * (1 - cap) + 0.9 * cap
        y = 2 * GAP + w + cap_h
        sheet[y:y + w, x:x + w] = false[i]
    y = 2 * GAP + w + cap_h
    sheet[y:y + w, 2 * w + 3 * GAP - GAP:2 * w + 3 * GAP - GAP + legend.shape[1]] = legend
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    write_display(args.out, sheet, view=view.view, attributes={photometric.EV100_ATTRIBUTE: f"{ev100:g}"})
    print(f"wrote {args.out} ({width}x{height}) in {time.perf_counter() - start:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

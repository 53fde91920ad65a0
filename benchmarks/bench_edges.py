"""How well the tracer's anti-aliased edges agree with Cycles': the body's bottom edge against the
black world, as a profile across the edge, for the tracer at 64 samples with a box filter and
with Blackman-Harris 1.5 px (its default), against Cycles at many samples with its default filter.

    .venv/bin/python benchmarks/bench_edges.py [--cycles-samples 1024] [--size 64x48]

Each profile is the mean over the columns where the edge runs straight (the lens far away), divided
by the body's own value inside, so shading differences between the renderers cancel and only the
edge's spread remains. Prints both profiles and the largest and mean differences from Cycles'.
"""

from __future__ import annotations

import argparse
import os
import sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from benchmarks.common import design_in_blender  # noqa: E402
from core_tracer.raytrace.engine import render_passes  # noqa: E402
from core_tracer.scene.validate import load_scene  # noqa: E402
from tools import dev_extension  # noqa: E402

PRESET = os.path.join(ROOT, "presets", "paper-baseline.json")


def profile(image: np.ndarray, rows: slice, cols: slice, inside_row: int) -> np.ndarray:
    luminance = image[..., :3].mean(axis=2)
    return luminance[rows, cols].mean(axis=1) / luminance[inside_row, cols].mean()


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--cycles-samples", type=int, default=1024)
    parser.add_argument("--size", default="64x48")
    args = parser.parse_args()
    width, height = (int(v) for v in args.size.split("x"))

    import bpy

    scene = load_scene(PRESET)
    scene["image"].update(width=width, height=height, samples=64)
    with dev_extension.enabled_from_source(bpy, "lamp_styling_dev") as package:
        bl_scene, compare = design_in_blender(bpy, package, scene)
        comparison = compare.compare_design(bl_scene, samples=args.cycles_samples, resolution=(width, height))
    rendered = comparison["scene"]
    cycles = comparison["cycles"]
    # The body's bottom edge: the first row from the bottom whose centre ray misses the body.
    centre = render_passes(rendered, keep_passes=False, samples=1).image.mean(axis=2)
    col = width // 2
    lit = np.nonzero(centre[:, col] > 0)[0]
    bottom = int(lit.max())
    rows = slice(bottom - 3, bottom + 4)
    cols = slice(2, width // 6)  # left of the lens, inside the body's width
    reference = profile(cycles, rows, cols, bottom - 4)
    print(f"edge rows {rows.start}..{rows.stop - 1}, columns {cols.start}..{cols.stop - 1}, "
          f"Cycles {args.cycles_samples} spp Blackman-Harris 1.5 px")
    print("Cycles         " + " ".join(f"{v:6.3f}" for v in reference))
    for name in ("box", "blackman-harris"):
        mine = profile(render_passes(rendered, keep_passes=False, samples=64, filter_name=name).image,
                       rows, cols, bottom - 4)
        diff = np.abs(mine - reference)
        print(f"{name:<15}" + " ".join(f"{v:6.3f}" for v in mine)
              + f"   max |diff| {diff.max():.4f}, mean {diff.mean():.4f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Edge samples against as many samples everywhere (issue 34, "clean bulb edges"): the lit lens's
relative error of the four-lamp night photometric preset at its 8 samples, with ``engine.edges``'s
edge samples (K x 8 more samples where a pixel's samples of the bulb pass disagree, along the main
branches or as whole trees) and without, and plainly at more samples, each with the ray segments it
traced and its time, as ratios to the plain 8 samples'.

    .venv/bin/python benchmarks/bench_bulb_edges.py [--size 256x160] [--edge-samples 4 8 16]
        [--whole-tree 4] [--samples 8 16 24 32] [--reference-samples 64] [--reach 0]

The metric is ``bench_cycles_noise``'s: the RMS over the lit lens (luminance at least 1/10 of the
99th percentile of the reference) of a render's Y minus the reference's, over the lit lens's mean
Y; the reference is the render at ``--reference-samples`` with every sample traced and no edge
samples. The lit lens's mean of each render against the reference's shows any bias. One process,
one thread (times are ratios on a loaded machine).
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
from core_tracer.raytrace.engine import edges  # noqa: E402

PRESET = os.path.join(ROOT, "presets", "four-lamp-night-lit-photometric.json")


def render_y(scene: dict, size: tuple[int, int], samples: int,
             every_sample: bool = False) -> tuple[np.ndarray, int, float]:
    start = time.perf_counter()
    result = render_passes(scene, *size, samples=samples, keep_passes=False, threads=1,
                           adaptive_threshold=0.0 if every_sample else None)
    return result.image[..., 1].astype(np.float64), result.stats["segments"], time.perf_counter() - start


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", default="256x160")
    parser.add_argument("--edge-samples", type=int, nargs="+", default=[4, 8, 16])
    parser.add_argument("--whole-tree", type=int, nargs="*", default=[4],
                        help="edge samples K traced as whole trees (MAIN_SHARE 0)")
    parser.add_argument("--samples", type=int, nargs="+", default=[8, 16, 24, 32])
    parser.add_argument("--reference-samples", type=int, default=64)
    parser.add_argument("--reach", type=int, default=0, help="edges.EDGE_REACH")
    args = parser.parse_args()
    size = tuple(int(v) for v in args.size.lower().split("x"))
    scene = load_scene(PRESET)
    edges.EDGE_REACH = args.reach
    reference, _, seconds = render_y(scene, size, args.reference_samples, every_sample=True)
    mask = reference >= 0.1 * np.percentile(reference, 99)
    mean = reference[mask].mean()
    print(f"four-lamp night photometric at {size[0]}x{size[1]}; reference {args.reference_samples} samples "
          f"({seconds:.1f} s): lit lens {int(mask.sum())} px, mean Y {mean:.1f} cd/m²", flush=True)
    base = None

    main_share = edges.MAIN_SHARE

    def report(label: str, samples: int, k: int, share: float = main_share) -> None:
        nonlocal base
        edges.MAIN_SHARE = share
        y, segments, seconds = render_y({**scene, "image": {**scene["image"], "edge_samples": k}}, size, samples)
        error = float(np.sqrt(np.mean((y[mask] - reference[mask]) ** 2)) / mean)
        base = base or (segments, seconds)
        print(f"{label:<24} error {error:.4f}  segments {segments / base[0]:5.2f}x  time {seconds / base[1]:5.2f}x "
              f"({seconds:.1f} s)  lit-lens mean {y[mask].mean() / mean - 1:+.4f}", flush=True)

    for samples in args.samples:
        report(f"{samples} samples", samples, 0)
    for k in args.edge_samples:
        report(f"8 samples, K={k} main", 8, k)
    for k in args.whole_tree:
        report(f"8 samples, K={k} trees", 8, k, 0.0)
    return 0


if __name__ == "__main__":
    sys.exit(main())

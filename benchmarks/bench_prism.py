"""How fast is a prism-plate lamp? Renders the prism-plate preset and the four-lamp preset at 512x512
several times each, interleaved, and prints the minimum and median wall time (the minimum is the
steadier figure on a shared machine), the CPU time and the ray segments of each, and their ratio.
With ``--against DIR`` it also times the four-lamp preset with the tracer of another checkout (the
tree before the prism plate, say), in a subprocess, to show what the new parts cost a lamp without them.

    .venv/bin/python benchmarks/bench_prism.py [--runs 7] [--threads 1] [--classes] [--against DIR]

Target (issue 12 item 7): the four-lamp time stays within 1.5x of today's with the new lamp types;
measured here with every lamp of the four-lamp preset given a prism plate (default plate fields).
``--classes`` also counts each preset's ray segments by path class (Table 1 and the plate's ⑬-⑲,
``raytrace.paths``) and by accumulated attenuation: where a plate lamp's extra segments come from.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

import core_tracer  # noqa: E402
from core_tracer.raytrace import engine, paths  # noqa: E402

PRESETS = {"four-lamp": ROOT / "presets" / "four-lamp-rear-combination.json",
           "prism-plate": ROOT / "presets" / "prism-plate-stop-lamp.json"}

TIME_CODE = """
import sys, time
sys.path.insert(0, sys.argv[1])
import core_tracer
scene = core_tracer.load_scene(sys.argv[2])
core_tracer.render(scene, 64, 64)
for _ in range(int(sys.argv[4])):
    t = time.perf_counter()
    core_tracer.render_passes(scene, int(sys.argv[3]), int(sys.argv[3]), keep_passes=False)
    print(time.perf_counter() - t)
"""


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=7)
    parser.add_argument("--size", type=int, default=512)
    parser.add_argument("--threads", type=int, default=None, help="render threads (default: every core)")
    parser.add_argument("--classes", action="store_true", help="count the segments of each path class")
    parser.add_argument("--against", type=Path, default=None, help="another checkout to time the four-lamp preset in")
    args = parser.parse_args()

    scenes = {name: core_tracer.load_scene(path) for name, path in PRESETS.items()}
    # the measure: the four-lamp combination with every lamp's reflector replaced by a plate
    mixed = core_tracer.load_scene(PRESETS["four-lamp"])
    for lamp in mixed["lamps"]:
        lamp["collection"] = "prism_plate"
    scenes["four-lamp, all prism plates"] = core_tracer.normalize(mixed)
    for scene in scenes.values():
        core_tracer.render(scene, 64, 64)  # warm up imports and caches
    times = {name: [] for name in scenes}
    cpu = {name: [] for name in scenes}
    segments = {}
    for _ in range(args.runs):
        for name, scene in scenes.items():
            start, cpu_start = time.perf_counter(), time.process_time()
            result = core_tracer.render_passes(scene, args.size, args.size, keep_passes=False, threads=args.threads)
            times[name].append(time.perf_counter() - start)
            cpu[name].append(time.process_time() - cpu_start)
            segments[name] = result.stats["segments"]
    print(f"machine       {os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f}")
    print(f"image         {args.size}x{args.size}, {args.runs} runs each, interleaved, "
          f"{args.threads or os.cpu_count()} thread(s)")
    for name in scenes:
        print(f"{name:28} min {min(times[name]):.3f} s, median {statistics.median(times[name]):.3f} s, "
              f"CPU min {min(cpu[name]):.3f} s median {statistics.median(cpu[name]):.3f} s, "
              f"{segments[name]:,} segments, {min(cpu[name]) / segments[name] * 1e6:.3f} us CPU per segment")
    for name in ("prism-plate", "four-lamp, all prism plates"):
        print(f"ratio         {name} / four-lamp = {min(times[name]) / min(times['four-lamp']):.2f} (min over min), "
              f"{statistics.median(cpu[name]) / statistics.median(cpu['four-lamp']):.2f} (CPU medians)")
    if args.classes:
        for name, scene in scenes.items():
            print_classes(name, scene, args.size)
    if args.against is not None:
        out = subprocess.run([sys.executable, "-c", TIME_CODE, str(args.against), str(PRESETS["four-lamp"]),
                              str(args.size), str(args.runs)], capture_output=True, text=True, check=True)
        other = [float(x) for x in out.stdout.split()]
        print(f"four-lamp in {args.against}: min {min(other):.3f} s, median {statistics.median(other):.3f} s "
              f"(this tree: min {min(times['four-lamp']):.3f} s)")
    return 0


def print_classes(name: str, scene: dict, size: int) -> None:
    """One render's segments: the eye rays, then the segments inside the lamps by path class and
    by the branch's accumulated attenuation (its largest channel; the cut-off is 0.1 %)."""
    by_class: dict[int, int] = {}
    by_weight = np.zeros(3, np.int64)
    bands = np.array([0.01, 0.1])
    intersect = engine.walk.intersect

    def counting(ctx, rays):  # the tracer's own classification (paths.CLASS_OF), counted
        t, surface, normal = intersect(ctx, rays)
        classes, counts = np.unique(paths.CLASS_OF[rays.medium, rays.src, surface], return_counts=True)
        for c, count in zip(classes.tolist(), counts.tolist(), strict=True):
            by_class[c] = by_class.get(c, 0) + count
        by_weight[:] += np.bincount(np.searchsorted(bands, rays.k.max(axis=1), side="right"), minlength=3)
        return t, surface, normal

    engine.walk.intersect = counting
    try:
        result = core_tracer.render_passes(scene, size, size, keep_passes=False)
    finally:
        engine.walk.intersect = intersect
    inside = sum(by_class.values())
    print(f"{name}: {result.stats['segments']:,} segments = {result.stats['segments'] - inside:,} eye rays "
          f"+ {inside:,} inside the lamps; by attenuation k < 1 %: {by_weight[0]:,}, 1-10 %: {by_weight[1]:,}, "
          f">= 10 %: {by_weight[2]:,}")
    print("    " + ", ".join(f"{c}: {n:,}" for c, n in sorted(by_class.items())))


if __name__ == "__main__":
    raise SystemExit(main())

"""What samples per pixel cost: the four-lamp preset at 512x512 with 1, 4 and 16 samples (median
wall-clock and CPU time of a few renders, and the eye rays per second).

    .venv/bin/python benchmarks/bench_samples.py [--runs 3] [--samples 1 4 16]

Issue target (with surroundings, not built here): 16 samples at 512x512 in <= 1.5 s on 2 cores.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import core_tracer  # noqa: E402
from core_tracer.raytrace.tracer import render_passes  # noqa: E402


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--samples", type=int, nargs="+", default=[1, 4, 16])
    parser.add_argument("--preset", default=str(ROOT / "presets" / "four-lamp-rear-combination.json"))
    parser.add_argument("--size", type=int, default=512)
    args = parser.parse_args()
    scene = core_tracer.load_scene(args.preset)
    for samples in args.samples:
        walls, cpus = [], []
        for _ in range(args.runs):
            w, c = time.perf_counter(), time.process_time()
            render_passes(scene, args.size, args.size, keep_passes=False, samples=samples)
            walls.append(time.perf_counter() - w)
            cpus.append(time.process_time() - c)
        wall = statistics.median(walls)
        rays = args.size * args.size * samples
        print(f"{args.size}x{args.size} at {samples:3d} samples: {wall:6.2f} s wall, "
              f"{statistics.median(cpus):6.2f} s CPU, {rays / wall / 1e6:5.2f} M eye rays/s")
    return 0


if __name__ == "__main__":
    sys.exit(main())

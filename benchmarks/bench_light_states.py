"""Lighting states (issue 23 item 5): the cost of rendering a design's passes against one render, and
of re-weighting them (the Light Panel's redraw, target < 50 ms at 512²).

    .venv/bin/python benchmarks/bench_light_states.py [--preset NAME] [--size 512] [--pool]

"one render" is the design's render as ``render`` traces it (adaptive sampling on); "every sample" the
same without adaptive sampling (what the states trace, so that a state equals a direct render of it).
``--pool`` traces both on the band pool's worker processes (as the CLI does for a heavy render), when
this tree's ``render_states`` takes a pool.
"""

from __future__ import annotations

import argparse
import inspect
import os
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

import core_tracer  # noqa: E402
from core_tracer.measures import states as S  # noqa: E402
from core_tracer.raytrace.engine import render_passes  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--preset", default="four-lamp-night-lit-photometric.json")
    parser.add_argument("--size", type=int, default=512)
    parser.add_argument("--repeats", type=int, default=50)
    parser.add_argument("--pool", action="store_true", help="trace on the band pool's workers")
    args = parser.parse_args()
    scene = core_tracer.load_scene(str(ROOT / "presets" / args.preset))
    scene["image"]["width"] = scene["image"]["height"] = args.size
    pool, with_pool = None, {}
    if args.pool:
        from core_tracer.raytrace import band_pool

        pool = band_pool.shared()
        pool.ready(30)
        if "pool" in inspect.signature(S.render_states).parameters:
            with_pool = {"pool": pool}
    start = time.perf_counter()
    render_passes(scene, keep_passes=False, pool=pool)
    one = time.perf_counter() - start
    start = time.perf_counter()
    render_passes(scene, keep_passes=False, pool=pool, adaptive_threshold=0)
    every_sample = time.perf_counter() - start
    start = time.perf_counter()
    light = S.render_states(scene, **with_pool)
    every = time.perf_counter() - start
    out = np.empty_like(light.surroundings)
    weights = light.default_weights()
    times = []
    for k in range(args.repeats):
        weights[light.states[1 + k % (len(light.states) - 1)].key] = float(k % 3) / 2
        start = time.perf_counter()
        S.relight(light, weights, out)
        times.append(time.perf_counter() - start)
    print(f"{args.preset} at {args.size}x{args.size}, {len(light.states) - 1} states + surroundings, "
          f"load average {os.getloadavg()[0]:.2f}")
    where = " on the pool" if with_pool else ""
    print(f"  one render {one:.2f} s (every sample {every_sample:.2f} s); the states {every:.2f} s "
          f"({every / one:.2f}x one render, {every / every_sample:.2f}x every sample){where}")
    print(f"  relight: median {1000 * np.median(times):.1f} ms, max {1000 * max(times):.1f} ms "
          f"over {args.repeats} changes")


if __name__ == "__main__":
    main()

"""How much does a cylindrical lens cost? Renders, at 512x512, the four-lamp preset (today's
benchmark), the same with its right-hand lamp cylindrical (radius 110 mm, wrapping toward +x; the
body 100 mm deep to hold its deeper reflector), the same with its left-hand lamp wrapping toward
-x too, the wrap-around preset, and the wrap-around preset
with its cylindrical lens made flat (the same lamps on a flat front), and prints for each the
minimum over several runs of the wall clock and CPU time and the ray segments traced. The machine
may be shared: the minimum of the repeats is the figure to compare.

    .venv/bin/python benchmarks/bench_wrap.py [--runs 5] [--size 512]
"""

from __future__ import annotations

import argparse
import copy
import os
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import core_tracer  # noqa: E402
from core_tracer.scene.validate import normalize  # noqa: E402


def measure(scenes: dict[str, dict], size: int, runs: int, threads: int) -> dict[str, tuple[float, float, int]]:
    """Each scene rendered ``runs`` times, the scenes taken in turn (so that a busy spell of the
    machine falls on all of them): per scene the minimum wall and CPU time and the segments."""
    for scene in scenes.values():
        core_tracer.render(scene, 64, 64)  # warm up imports and caches
    walls = {name: [] for name in scenes}
    cpus = {name: [] for name in scenes}
    segments = {}
    for _ in range(runs):
        for name, scene in scenes.items():
            start, cpu_start = time.perf_counter(), time.process_time()
            result = core_tracer.render_passes(scene, size, size, keep_passes=False, threads=threads)
            walls[name].append(time.perf_counter() - start)
            cpus[name].append(time.process_time() - cpu_start)
            segments[name] = result.stats["segments"]
    return {name: (min(walls[name]), min(cpus[name]), segments[name]) for name in scenes}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--size", type=int, default=512)
    parser.add_argument("--threads", type=int, default=1, help="band threads (default 1: steadier on a busy machine)")
    args = parser.parse_args()
    four = core_tracer.load_scene(ROOT / "presets" / "four-lamp-rear-combination.json")
    wrap = core_tracer.load_scene(ROOT / "presets" / "wrap-around-combination.json")
    flat = copy.deepcopy(wrap)
    for lamp in flat["lamps"]:
        lamp["lens"]["shape"] = "flat"
    flat = normalize(flat)
    four_wrapped = copy.deepcopy(four)
    four_wrapped["body"]["depth"] = 100.0
    four_wrapped["lamps"][3]["lens"].update(shape="cylindrical", wrap_radius=110.0, wrap_toward="+x")
    both_ends = copy.deepcopy(four_wrapped)
    both_ends["lamps"][0]["lens"].update(shape="cylindrical", wrap_radius=110.0, wrap_toward="-x")
    four_wrapped, both_ends = normalize(four_wrapped), normalize(both_ends)
    print(f"machine       {os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f}")
    print(f"image         {args.size}x{args.size}, min of {args.runs} runs, {args.threads} thread(s)")
    cases = {"four-lamp": four, "four, one wraps": four_wrapped, "four, both wrap": both_ends, "wrap-around": wrap,
             "wrap, lens flat": flat}
    figures = measure(cases, args.size, args.runs, args.threads)
    base_wall, base_cpu, _ = figures["four-lamp"]
    for name, (wall, cpu, segments) in figures.items():
        print(f"{name:16s} wall {wall:.3f} s  CPU {cpu:.3f} s  {segments} segments  "
              f"{wall / base_wall:.2f}x wall, {cpu / base_cpu:.2f}x CPU of the four-lamp")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

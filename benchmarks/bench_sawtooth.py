"""Saw-tooth cuts against fish-eye cuts: the four-lamp preset at 512x512 as shipped (fish-eye), with
every lamp's cuts turned saw-tooth (its own pitch, tooth angle 20 deg, horizontal ridges), and with
the two types mixed (lamps 1 and 3 saw-tooth), and with cylindrical flutes of each lamp's own pitch
and height. Renders are interleaved and the minimum of the
repeats is reported (wall clock and CPU time; on a shared machine the CPU time on one thread is
the figure to compare), the steadiest figure on a shared machine; also the ray segments, since the
saw-tooth optics send the rays on other paths (more total internal reflection), and the CPU time
per segment, which is what the strip walk itself costs.

    .venv/bin/python benchmarks/bench_sawtooth.py [--runs 5] [--size 512] [--angle 20] [--threads 1]
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


def with_sawtooth(scene: dict, lamps: list[int], angle: float) -> dict:
    out = copy.deepcopy(scene)
    for i in lamps:
        out["lamps"][i]["cuts"].update(type="sawtooth", tooth_angle=angle, orientation=0.0)
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--preset", default=str(ROOT / "presets" / "four-lamp-rear-combination.json"))
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--size", type=int, default=512)
    parser.add_argument("--angle", type=float, default=20.0)
    parser.add_argument("--threads", type=int, default=1, help="band threads (default 1: steadier on a busy machine)")
    args = parser.parse_args()

    fish = core_tracer.load_scene(args.preset)
    n = len(fish["lamps"])
    fluted = copy.deepcopy(fish)
    for lamp in fluted["lamps"]:  # each lamp's own pitch and height, as cylindrical flutes
        lamp["cuts"].update(type="flutes", orientation=0.0)
    cases = {"fish-eye": fish, "saw-tooth": with_sawtooth(fish, list(range(n)), args.angle),
             "mixed": with_sawtooth(fish, list(range(0, n, 2)), args.angle), "flutes": fluted}
    for scene in cases.values():
        core_tracer.render(scene, 64, 64)  # warm up
    best = {name: float("inf") for name in cases}
    best_cpu = {name: float("inf") for name in cases}
    segments = {}
    for _ in range(args.runs):
        for name, scene in cases.items():
            start, cpu_start = time.perf_counter(), time.process_time()
            result = core_tracer.render_passes(scene, args.size, args.size, keep_passes=False, threads=args.threads)
            best[name] = min(best[name], time.perf_counter() - start)
            best_cpu[name] = min(best_cpu[name], time.process_time() - cpu_start)
            segments[name] = result.stats["segments"]
    print(f"preset   {Path(args.preset).name}, {args.size}x{args.size}, min of {args.runs} runs, {args.threads} "
          f"thread(s), {os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f}")
    for name in cases:
        print(f"{name:10s} wall {best[name]:.3f} s ({best[name] / best['fish-eye']:.2f}x)  CPU {best_cpu[name]:.3f} s "
              f"({best_cpu[name] / best_cpu['fish-eye']:.2f}x fish-eye)  {segments[name]:>9d} segments  "
              f"{1e9 * best_cpu[name] / segments[name]:.0f} ns/segment")
    return 0


if __name__ == "__main__":
    sys.exit(main())

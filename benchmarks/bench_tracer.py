"""How fast is the tracer? Prints, for the four-lamp preset, the median time of several 512x512
renders (wall clock, and the CPU time of all threads: on a busy machine the CPU time is the
steadier figure), the ray segments traced per second, and the peak memory of a 2048x2048 render.

    .venv/bin/python benchmarks/bench_tracer.py [--runs 5] [--preset presets/four-lamp-rear-combination.json]
        [--rectangular]

Targets of the tracer's speed and memory: <= 1.0 s at 512x512 on a 2-core machine; <= 1 GB peak memory at 2048x2048.
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

import core_tracer  # noqa: E402

PEAK_CODE = """
import resource, sys, time
import core_tracer
scene = core_tracer.load_scene(sys.argv[1])
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
t = time.perf_counter()
core_tracer.render(scene, 2048, 2048)
print(time.perf_counter() - t, before, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)
"""


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--preset", default=str(ROOT / "presets" / "four-lamp-rear-combination.json"))
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--size", type=int, default=512)
    parser.add_argument("--threads", type=int, default=None, help="band threads (default: one per core)")
    parser.add_argument("--skip-memory", action="store_true", help="skip the 2048x2048 peak-memory run")
    parser.add_argument("--rectangular", action="store_true",
                        help="make every lens a square of the round lens's diameter with 10 mm corners")
    args = parser.parse_args()

    scene = core_tracer.load_scene(args.preset)
    if args.rectangular:
        for lamp in scene["lamps"]:
            side = 2 * lamp["lens"]["radius"]
            lamp["lens"].update(outline="rectangular", width=side, height=side, corner_radius=10.0)
        scene = core_tracer.normalize(scene)
    core_tracer.render(scene, 64, 64)  # warm up imports and caches
    times, cpu_times, segments = [], [], 0
    for _ in range(args.runs):
        start, cpu_start = time.perf_counter(), time.process_time()
        result = core_tracer.render_passes(scene, args.size, args.size, threads=args.threads, keep_passes=False)
        times.append(time.perf_counter() - start)
        cpu_times.append(time.process_time() - cpu_start)
        segments = result.stats["segments"]
    median = statistics.median(times)
    print(f"preset        {Path(args.preset).name}")
    print(f"machine       {os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f}")
    print(f"image         {args.size}x{args.size}, {args.runs} runs")
    print(f"median time   {median:.3f} s   (min {min(times):.3f} s, max {max(times):.3f} s)")
    threads = args.threads or os.cpu_count()
    print(f"median CPU    {statistics.median(cpu_times):.3f} s   (all {threads} threads)")
    print(f"segments      {segments:,} per image, {segments / median / 1e6:.2f} M segments/s")
    if not args.skip_memory:
        out = subprocess.run([sys.executable, "-c", PEAK_CODE, args.preset], cwd=ROOT, capture_output=True,
                             text=True, check=True)
        seconds, before, peak = out.stdout.split()
        print(f"2048x2048     {float(seconds):.2f} s, peak memory {int(peak) / 1024:.0f} MB "
              f"(after imports {int(before) / 1024:.0f} MB)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""What samples per pixel cost: the four-lamp day preset (surroundings: Blender's city world, a
three-quarter view) and the four-lamp preset at 512x512 with 1, 4 and 16 samples, every sample of
every pixel against adaptive sampling (the default: all samples only where a pixel's neighbourhood
disagrees), with the adaptive image's difference from the full one; optionally the same scene
rendered by Cycles, for the ratio of the two times in one run.

    .venv/bin/python benchmarks/bench_samples.py [--runs 3] [--samples 1 4 16] [--threads 2]
        [--preset presets/four-lamp-day-lit.json ...] [--cycles 256]

Target: the day preset, 16 samples at 512x512, in <= 1.5 s on 2 cores. Bands are traced in the band
pool's worker processes, started before timing (as in Blender after a first render, and in the
CLI's heavy renders); ``--no-pool`` traces them on threads instead. Times are the minimum and
median of the runs (wall clock; CPU over the threads and worker processes in brackets). The day preset's peak is the sun
seen in a lens, thousands of times the rest of the image, so the adaptive image's difference is
also given against the 99.9th percentile of the pixels.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402
from bench_viewport import cpu_seconds  # noqa: E402

import core_tracer  # noqa: E402
from core_tracer.raytrace import band_pool  # noqa: E402
from core_tracer.raytrace.engine import render_passes  # noqa: E402


def _timed(scene: dict, size: int, samples: int, runs: int, threshold: float | None, threads: int | None, pool):
    walls, cpus, result = [], [], None
    for _ in range(runs):
        w, c = time.perf_counter(), cpu_seconds(pool)
        result = render_passes(scene, size, size, keep_passes=False, samples=samples, adaptive_threshold=threshold,
                               threads=threads, pool=pool)
        walls.append(time.perf_counter() - w)
        cpus.append(cpu_seconds(pool) - c)
    return min(walls), statistics.median(walls), min(cpus), result


def _cycles(preset: Path, size: int, samples: int, cycles_samples: int) -> str:
    """Both renderers on one scene in one run (tools/compare_preset.py): the tracer at ``samples``
    (the preset's image.samples), Cycles at ``cycles_samples``; returns the timing lines."""
    doc = json.loads(preset.read_text())
    doc.setdefault("image", {})["samples"] = samples
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / preset.name
        path.write_text(json.dumps(doc))
        out = subprocess.run([sys.executable, str(ROOT / "tools" / "compare_preset.py"), str(path), "-o",
                              str(Path(tmp) / "compare.exr"), "--samples", str(cycles_samples),
                              "--size", f"{size}x{size}"], capture_output=True, text=True, check=True).stdout
    tracer = float(re.search(r"Lamp Tracer:.* in ([0-9.]+) s", out).group(1))
    cycles = float(re.search(r"Cycles:.* in ([0-9.]+) s", out).group(1))
    return (f"one run of tools/compare_preset.py: Lamp Tracer {samples} samples {tracer:.2f} s, Cycles "
            f"{cycles_samples} samples {cycles:.2f} s: Cycles takes {cycles / tracer:.0f} times as long")


def _bench(preset: Path, args: argparse.Namespace, pool) -> None:
    scene = core_tracer.load_scene(preset)
    render_passes(scene, 64, 64, keep_passes=False)  # warm up (and read the world image)
    render_passes(scene, args.size, args.size, samples=4, keep_passes=False, pool=pool)  # the same in the workers
    where = f"{pool.size} worker processes" if pool is not None else f"{args.threads or os.cpu_count()} threads"
    print(f"{preset.name}, {args.size}x{args.size}, bands in {where} on {os.cpu_count()} "
          f"cores, load average {os.getloadavg()[0]:.2f}, min / median of {args.runs} runs")
    for samples in args.samples:
        w_full, m_full, c_full, full = _timed(scene, args.size, samples, args.runs, 0.0, args.threads, pool)
        line = (f"{samples:3d} samples: every sample {w_full:5.2f} / {m_full:5.2f} s ({c_full:5.2f} s CPU, "
                f"{full.stats['segments'] / 1e6:.2f} M segments)")
        if samples > 4:
            w, m, c, adaptive = _timed(scene, args.size, samples, args.runs, None, args.threads, pool)
            reference = full.image.astype(np.float64)
            error = np.abs(adaptive.image - reference)
            busy = adaptive.stats["busy_pixels"] / args.size**2
            p999 = np.percentile(reference.max(axis=2), 99.9)
            line += (f"; adaptive {w:5.2f} / {m:5.2f} s ({c:5.2f} s CPU, {adaptive.stats['segments'] / 1e6:.2f} M "
                     f"segments, {busy:.0%} of pixels took every sample), differs by at most "
                     f"{error.max() / reference.max():.1e} of the peak ({error.max() / p999:.1e} of the 99.9th "
                     f"percentile), {error.mean() / reference.mean():.1e} of the mean")
        print(line, flush=True)
    print(f"load average after: {os.getloadavg()[0]:.2f}", flush=True)


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--samples", type=int, nargs="+", default=[1, 4, 16])
    parser.add_argument("--preset", nargs="+", default=[str(ROOT / "presets" / "four-lamp-day-lit.json"),
                                                         str(ROOT / "presets" / "four-lamp-rear-combination.json")])
    parser.add_argument("--size", type=int, default=512)
    parser.add_argument("--threads", type=int, default=None, help="threads of a render (default: all cores)")
    parser.add_argument("--cycles", type=int, default=0, metavar="N",
                        help="also render each scene at 16 samples with both renderers (Cycles at N samples)")
    parser.add_argument("--no-pool", action="store_true",
                        help="bands on threads of this process instead of the band pool's worker processes")
    args = parser.parse_args()
    pool = None if args.no_pool or args.threads == 1 else band_pool.shared()
    if pool is not None and not pool.ready(30):
        raise SystemExit(f"the band pool did not start: {pool.broken}")
    for preset in args.preset:
        _bench(Path(preset), args, pool)
        if args.cycles:
            print(_cycles(Path(preset), args.size, 16, args.cycles), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())

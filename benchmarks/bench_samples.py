"""What samples per pixel cost: the four-lamp preset at 512x512 with 1, 4 and 16 samples, every
sample of every pixel against adaptive sampling (the default: all samples only where a pixel's
neighbourhood disagrees), with the adaptive image's difference from the full one; optionally the
same scene rendered by Cycles, for the ratio of the two times in one run.

    .venv/bin/python benchmarks/bench_samples.py [--runs 3] [--samples 1 4 16] [--cycles 256]

Issue target (with surroundings, not built here): 16 samples at 512x512 in <= 1.5 s on 2 cores.
Times are the minimum and median of the runs (wall clock; CPU over both threads in brackets).
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

import core_tracer  # noqa: E402
from core_tracer.raytrace.tracer import render_passes  # noqa: E402


def _timed(scene: dict, size: int, samples: int, runs: int, threshold: float | None):
    walls, cpus, result = [], [], None
    for _ in range(runs):
        w, c = time.perf_counter(), time.process_time()
        result = render_passes(scene, size, size, keep_passes=False, samples=samples, adaptive_threshold=threshold)
        walls.append(time.perf_counter() - w)
        cpus.append(time.process_time() - c)
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


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--samples", type=int, nargs="+", default=[1, 4, 16])
    parser.add_argument("--preset", default=str(ROOT / "presets" / "four-lamp-rear-combination.json"))
    parser.add_argument("--size", type=int, default=512)
    parser.add_argument("--cycles", type=int, default=0, metavar="N",
                        help="also render the scene at 16 samples with both renderers (Cycles at N samples)")
    args = parser.parse_args()
    scene = core_tracer.load_scene(args.preset)
    render_passes(scene, 64, 64, keep_passes=False)  # warm up
    print(f"{args.size}x{args.size}, {os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f}, "
          f"min / median of {args.runs} runs")
    for samples in args.samples:
        w_full, m_full, c_full, full = _timed(scene, args.size, samples, args.runs, 0.0)
        line = (f"{samples:3d} samples: every sample {w_full:5.2f} / {m_full:5.2f} s ({c_full:5.2f} s CPU, "
                f"{full.stats['segments'] / 1e6:.2f} M segments)")
        if samples > 4:
            w, m, c, adaptive = _timed(scene, args.size, samples, args.runs, None)
            error = np.abs(adaptive.image.astype(np.float64) - full.image)
            busy = adaptive.stats["busy_pixels"] / args.size**2
            line += (f"; adaptive {w:5.2f} / {m:5.2f} s ({c:5.2f} s CPU, {adaptive.stats['segments'] / 1e6:.2f} M "
                     f"segments, {busy:.0%} of pixels took every sample), differs by at most "
                     f"{error.max() / full.image.max():.1e} of the peak, {error.mean() / full.image.mean():.1e} "
                     "of the mean")
        print(line, flush=True)
    if args.cycles:
        print(_cycles(Path(args.preset), args.size, 16, args.cycles))
    return 0


if __name__ == "__main__":
    sys.exit(main())

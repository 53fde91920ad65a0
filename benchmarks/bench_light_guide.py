"""How costly is a light guide's path? Renders the LED light-guide tail lamp and the photometric stop
lamp at 512x512 and 8 samples, interleaved in one process, and prints each render's wall and CPU
time, its ray segments, segments per eye ray, deepest path and the branches ended at the depth
limit, and the ratio of the cost per segment (guide / stop lamp).

    .venv/bin/python benchmarks/bench_light_guide.py [--runs 1] [--size 512] [--samples 8] [--guide SCENE.json]

``--guide`` renders another guide lamp in the preset's place (an older version of it, to time a change of
the code on the same design).

Target (issue 32): a guide's paths are long (tens of total internal reflections), so it is judged per
segment: the guide lamp's CPU time per segment within 1.3x the stop lamp's. The ratio is taken in one
run, the two renders one after the other, so that a shared machine's load weighs on both alike.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # no BLAS thread beside each render thread (bench_photometric)

import core_tracer  # noqa: E402

PRESETS = {"guide": ROOT / "presets" / "led-light-guide-tail-lamp.json",
           "stop": ROOT / "presets" / "photometric-stop-lamp.json"}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=1)
    parser.add_argument("--size", type=int, default=512)
    parser.add_argument("--samples", type=int, default=8)
    parser.add_argument("--guide", type=Path, default=PRESETS["guide"], help="the guide lamp's scene file")
    args = parser.parse_args()
    scenes = {name: core_tracer.load_scene(path) for name, path in {**PRESETS, "guide": args.guide}.items()}
    for scene in scenes.values():
        scene["image"]["samples"] = args.samples
    per_segment: dict[str, list[float]] = {name: [] for name in scenes}
    for run in range(args.runs):
        for name, scene in scenes.items():
            wall, cpu = time.perf_counter(), time.process_time()
            result = core_tracer.render_passes(scene, args.size, args.size, keep_passes=False)
            wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
            stats = result.stats
            rays = args.size * args.size * args.samples
            per_segment[name].append(cpu / stats["segments"])
            print(f"run {run} {name:5s}: wall {wall:7.2f} s, cpu {cpu:7.2f} s, {stats['segments']} segments, "
                  f"{stats['segments'] / rays:.2f} a ray, deepest {stats['max_depth']}, "
                  f"{stats['cut_at_depth']} ended at the depth limit, {1e9 * cpu / stats['segments']:.0f} ns CPU a "
                  "segment", flush=True)
        ratio = per_segment["guide"][-1] / per_segment["stop"][-1]
        print(f"run {run}: CPU per segment, guide / stop lamp = {ratio:.2f} (target <= 1.3), load average "
              f"{os.getloadavg()[0]:.1f}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""What the photometric mode costs: a photometric preset rendered in its own mode (K bands) and the
same document with ``"light_model": "paper"`` (the same geometry, cuts, lamps and camera; R, G, B),
alternately in one run, at 512x512. Prints the median wall-clock and CPU time of each, the ray
segments, and the ratio photometric / paper (issue 22: at most 2x). A free-form preset is traced on
its meshes (the .glb beside it), both modes on the same geometry.

    .venv/bin/python benchmarks/bench_photometric.py [--preset presets/four-lamp-night-lit-photometric.json]
        [--runs 5] [--size 512] [--bands K] [--threads N]

Both renders run in this process on the same threads (``--threads``, default every core), so the
ratio compares the models, not the machine's load at two moments. numpy's BLAS runs single-threaded
here, as in the band pool's worker processes that the CLI renders with (``processes.worker_environment``):
the render's threads are the parallelism; a BLAS thread spinning beside each of them for the
photometric mode's small matrix products (K bands to X, Y, Z) burned CPU and gained no time.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # before numpy is imported (docstring)
ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from core_tracer import load_scene, render_passes  # noqa: E402
from core_tracer.raytrace import spectral  # noqa: E402


def timed(scene: dict, size: int, bands: int | None, threads: int | None, meshes=None) -> tuple[float, float, int]:
    """(wall s, CPU s, ray segments) of one render (a free-form design's on its ``meshes``)."""
    wall, cpu = time.perf_counter(), time.process_time()
    render = render_passes if meshes is None else meshes.render_passes
    result = render(scene, size, size, bands=bands, threads=threads)
    return time.perf_counter() - wall, time.process_time() - cpu, int(result.stats.get("segments", 0))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--preset", default=str(ROOT / "presets" / "four-lamp-night-lit-photometric.json"))
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--size", type=int, default=512)
    parser.add_argument("--bands", type=int, default=None, help=f"K (default {spectral.DEFAULT_BANDS})")
    parser.add_argument("--threads", type=int, default=None)
    args = parser.parse_args()
    photometric = load_scene(args.preset)
    if photometric.get("light_model") != "photometric":
        raise SystemExit(f"{args.preset}: not a photometric preset")
    paper = {**photometric, "light_model": "paper"}
    meshes = None
    if "freeform" in photometric:
        from core_tracer.freeform.design import DesignMeshes
        from core_tracer.freeform.loading import load_meshes

        meshes = DesignMeshes(load_meshes(args.preset, photometric))
    k = args.bands or spectral.DEFAULT_BANDS
    timed(paper, 64, None, args.threads, meshes)  # imports, caches, world image, Embree: out of the figures
    timed(photometric, 64, k, args.threads, meshes)
    runs: dict[str, list[tuple[float, float, int]]] = {"paper": [], "photometric": []}
    for _ in range(args.runs):
        runs["paper"].append(timed(paper, args.size, None, args.threads, meshes))
        runs["photometric"].append(timed(photometric, args.size, k, args.threads, meshes))
    median = {mode: (statistics.median(r[0] for r in rs), statistics.median(r[1] for r in rs), rs[0][2])
              for mode, rs in runs.items()}
    print(f"{Path(args.preset).name} at {args.size}x{args.size}, {photometric['image'].get('samples', 1)} "
          f"sample(s), median of {args.runs}:")
    for mode, (wall, cpu, segments) in median.items():
        what = f"K = {k}" if mode == "photometric" else "R, G, B"
        print(f"  {mode:12s} ({what:8s}) wall {wall:6.2f} s   cpu {cpu:6.2f} s   {segments} ray segments")
    print(f"  load average {os.getloadavg()[0]:.2f}, BLAS threads {os.environ['OPENBLAS_NUM_THREADS']}")
    print(f"  ratio photometric / paper: wall {median['photometric'][0] / median['paper'][0]:.2f}x, "
          f"cpu {median['photometric'][1] / median['paper'][1]:.2f}x")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

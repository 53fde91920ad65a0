"""Old tree against new for edge samples (issue 34 item 4), run once per tree in one command: the
four-lamp night photometric preset at its 512x320 and 8 samples in the band pool, its lit lens's
relative error, time, ray segments and mean against a 64-sample reference (every sample) that
``ref`` renders (in the old tree) to the third argument's file. Run from the new tree's folder:

    OLD=/tmp/edges-old   # git worktree add --detach /tmp/edges-old main; ln -s <venv> $OLD/.venv
    $OLD/.venv/bin/python benchmarks/bench_bulb_edges_trees.py $OLD ref
    $OLD/.venv/bin/python benchmarks/bench_bulb_edges_trees.py $OLD old
    .venv/bin/python benchmarks/bench_bulb_edges_trees.py . new
"""

from __future__ import annotations

import os
import sys
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # before numpy is imported, as the band pool's workers
import numpy as np  # noqa: E402


def main() -> int:
    tree, what = os.path.abspath(sys.argv[1]), sys.argv[2]
    reference_file = sys.argv[3] if len(sys.argv) > 3 else "/tmp/bulb-edges-reference.npy"
    sys.path.insert(0, tree)
    # Imported here: which tree's tracer is the argument (this script lives in the new tree only).
    from core_tracer import load_scene, render_passes
    from core_tracer.raytrace import band_pool

    scene = load_scene(os.path.join(tree, "presets", "four-lamp-night-lit-photometric.json"))
    pool = band_pool.shared()
    if not pool.ready(120):
        raise SystemExit(f"the band pool did not start: {pool.broken}")
    if what == "new":
        scene["image"]["edge_samples"] = 8  # the scene's own setting (off by default)
    render_passes(scene, 64, 40, keep_passes=False, pool=pool)  # warm up
    if what == "ref":
        start = time.perf_counter()
        result = render_passes(scene, samples=64, keep_passes=False, pool=pool, adaptive_threshold=0.0)
        np.save(reference_file, result.image[..., 1])
        print(f"reference: 64 samples, {time.perf_counter() - start:.1f} s")
        return 0
    reference = np.load(reference_file).astype(np.float64)
    lit = reference >= 0.1 * np.percentile(reference, 99)
    for _ in range(2):
        start = time.perf_counter()
        result = render_passes(scene, samples=8, keep_passes=False, pool=pool)
        seconds = time.perf_counter() - start
        y = result.image[..., 1].astype(np.float64)
        error = np.sqrt(np.mean((y[lit] - reference[lit]) ** 2)) / reference[lit].mean()
        print(f"{what}: 8 samples error {error:.4f} time {seconds:.2f} s segments {result.stats['segments']} "
              f"lit mean {y[lit].mean() / reference[lit].mean() - 1:+.4f} load {os.getloadavg()[0]:.1f}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""A study on the local Dask cluster against the project's own worker pool, and what a study costs
on a real cluster.

    .venv/bin/python benchmarks/bench_cluster.py [--grid 8x8] [--size 256] [--samples 16] [--workers N]

Renders the same study (refractive index against cut height on the paper's baseline) on the worker
pool (``study.run``) and on the local Dask cluster, alternately for ``--rounds`` rounds (a shared
machine's other work then weighs on both alike), and the local cluster's start-up apart. No cell
cache: every cell renders. Prints the wall times, the ratio Dask / pool, the images' equality, the
bytes of one task and of one result, the scheduler's overhead per task (no-op tasks), the memory
each worker holds, and an estimate of a 400-variant print-size study (1920 px, 64 samples) on 16
nodes like this machine, from the measured cost per eye ray.
"""

from __future__ import annotations

import argparse
import os
import pickle
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from core_tracer.cluster import engine  # noqa: E402
from core_tracer.cluster.cells import BAND_TASK_RAYS  # noqa: E402
from core_tracer.scene.reading import read_json  # noqa: E402
from core_tracer.study import definition as st  # noqa: E402
from core_tracer.study import on_cluster as dask_study  # noqa: E402
from core_tracer.study import run as study_run  # noqa: E402

BASE = ROOT / "presets" / "paper-baseline.json"
PRINT_SIZE, PRINT_SAMPLES, PRINT_VARIANTS, NODES = 1920, 64, 400, 16


def _rss() -> int:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def _nothing(x: int) -> int:
    return x


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--grid", default="8x8")
    parser.add_argument("--size", type=int, default=256)
    parser.add_argument("--samples", type=int, default=16)
    parser.add_argument("--workers", type=int, default=engine.default_workers())
    parser.add_argument("--rounds", type=int, default=2)
    args = parser.parse_args()
    cols, rows = (int(x) for x in args.grid.split("x"))
    base = read_json(BASE)
    base["image"] = {**base.get("image", {}), "samples": args.samples}
    study = st.Study.build(base, [st.parse_vary(f"lens.ior=1.45:1.6:{cols}"),
                                  st.parse_vary(f"cuts.height=0.5:2:{rows}")], (args.size, args.size))
    n = len(study)
    print(f"{cols}x{rows} study at {args.size} px, {args.samples} samples, {args.workers} workers x 1 thread; "
          f"load average {', '.join(f'{x:.2f}' for x in os.getloadavg())}")

    cells, inputs = dask_study.study_cells(study)
    pool_times, dask_times = [], []
    start = time.perf_counter()
    with engine.connect(workers=args.workers, memory_limit=engine.worker_memory(cells)) as client:
        up = time.perf_counter() - start
        # Alternated, so that the other work of a shared machine weighs on both alike.
        for _ in range(args.rounds):
            t0 = time.perf_counter()
            pool_images = study_run.run_study(study, args.workers, threads=1)
            pool_times.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            dask_images, count = engine.run_cells(client, cells, inputs, None)
            dask_times.append(time.perf_counter() - t0)
            print(f"worker pool {pool_times[-1]:7.2f} s, local Dask {dask_times[-1]:7.2f} s "
                  f"(load {os.getloadavg()[0]:.2f})")
        # The scheduler's own cost per task: no-op tasks, submitted and gathered.
        t0 = time.perf_counter()
        futures = client.map(_nothing, range(400), pure=False)
        client.gather(futures)
        overhead = (time.perf_counter() - t0) / 400
        rss = client.run(_rss)
    pool, tasks = min(pool_times), min(dask_times)
    print(f"local Dask cluster up in {up:.2f} s (a CLI run pays it once)")
    print(f"ratio Dask / pool: {tasks / pool:.2f} (best of {args.rounds} each), {(tasks + up) / pool:.2f} with the "
          f"start-up; per round {', '.join(f'{d / p:.2f}' for p, d in zip(pool_times, dask_times, strict=True))}")
    equal = all(np.array_equal(a, b) for a, b in zip(pool_images, dask_images, strict=True))
    print(f"images equal bit for bit: {equal}; {count.rendered} tasks")
    task_bytes = len(pickle.dumps(cells[0], protocol=pickle.HIGHEST_PROTOCOL))
    print(f"one task {task_bytes} bytes pickled; one result {dask_images[0].nbytes} bytes; scheduler overhead "
          f"{overhead * 1e3:.2f} ms per task; worker memory {', '.join(f'{v / 2**20:.0f}' for v in rss.values())} MB "
          f"(limit {engine.worker_memory(cells) / 2**20:.0f} MB)")
    rays = args.size * args.size * args.samples
    per_ray = pool / (n * rays) * args.workers  # core-seconds per eye ray
    print_cell = per_ray * PRINT_SIZE * PRINT_SIZE * PRINT_SAMPLES
    cores = NODES * args.workers
    tasks_per_cell = -(-PRINT_SIZE * PRINT_SIZE * PRINT_SAMPLES // BAND_TASK_RAYS)
    estimate = PRINT_VARIANTS * print_cell / cores + PRINT_VARIANTS * tasks_per_cell * overhead
    print(f"{per_ray * 1e9:.0f} ns per eye ray per core; a {PRINT_SIZE} px, "
          f"{PRINT_SAMPLES}-sample cell about {print_cell / 60:.1f} core-minutes; {PRINT_VARIANTS} of them on {NODES} "
          f"nodes of {args.workers} cores: about {estimate / 60:.0f} minutes (each cell some 30 band tasks)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

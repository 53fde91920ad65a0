"""Studies and optimisations without start-up (issue 34 item 3): the default local run against the
same work in one process, measured in one run.

    .venv/bin/python benchmarks/bench_startup.py [--rounds 2] [--trials 4] [--dask]

1. A 16-variant study at 128x128 (paper baseline, lens.ior x cuts.height, 4 x 4), ``--no-cache``:
   the command with its default settings (the local worker pool), and with ``--workers 0`` (one
   process). Target: default <= 1.5x one process.
2. ``optimise`` on the even-stop-lamp example (docs/examples/even-stop-lamp.optimise.json) for
   ``--trials`` trials in a fresh storage, ``--no-cache``: default settings, and ``--workers 0``
   (the trials' own work, one after the other in the command's process). Target: default <= 1.5x.

Each figure is the command's own "in X s" (from its start of work to its end: a local Dask cluster's
start-up included, Python's own start and the imports not) and the whole command's wall time; the
runs alternate, ``--rounds`` times, and the best of each is kept, with the largest proportional set
size of the command's process tree seen (sampled every 0.2 s). ``--dask`` adds the same runs on
a local Dask cluster (``--engine dask`` / ``--scheduler local``) for reference. The load average is
printed before and after: on a shared machine only the ratios mean anything.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PYTHON = sys.executable
STUDY = ["study", str(ROOT / "presets" / "paper-baseline.json"), "--vary", "lens.ior=1.45:1.6:4", "--vary",
         "cuts.height=0.5:2:4", "--size", "128x128", "--no-cache"]
EXAMPLE = ROOT / "docs" / "examples" / "even-stop-lamp.optimise.json"
SECONDS = re.compile(r" in ([0-9.]+) s ")


def load() -> str:
    return ", ".join(f"{x:.2f}" for x in os.getloadavg())


def tree_pss(pid: int) -> int:
    """The proportional set size of ``pid`` and every process under it (shared pages counted once
    over the processes sharing them: a forked worker's pages shared with its parent are not counted
    twice), from /proc; 0 where it cannot be read."""
    total, todo = 0, [pid]
    while todo:
        p = todo.pop()
        try:
            with open(f"/proc/{p}/smaps_rollup") as f:
                total += next(int(x.split()[1]) for x in f if x.startswith("Pss:")) * 1024
            for task in os.listdir(f"/proc/{p}/task"):
                with open(f"/proc/{p}/task/{task}/children") as f:
                    todo += [int(c) for c in f.read().split()]
        except (OSError, StopIteration):
            continue
    return total


def timed(arguments: list[str], env: dict) -> tuple[float, float, str, int]:
    """(the command's own seconds, its wall time, its last line, its process tree's peak PSS in bytes
    sampled every 0.2 s)."""
    start = time.perf_counter()
    proc = subprocess.Popen([PYTHON, "-m", "core_tracer", *arguments], cwd=ROOT, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    peak = 0
    while proc.poll() is None:
        peak = max(peak, tree_pss(proc.pid))
        time.sleep(0.2)
    stdout, stderr = proc.communicate()
    wall = time.perf_counter() - start
    if proc.returncode != 0:
        raise SystemExit(f"{' '.join(arguments)} failed:\n{stderr}")
    line = next(x for x in stdout.splitlines() if SECONDS.search(x))
    return float(SECONDS.search(line).group(1)), wall, line, peak


def optimise_file(folder: str, trials: int, run: str) -> str:
    doc = json.loads(EXAMPLE.read_text())
    base = (EXAMPLE.parent / doc["base"]).resolve()
    shutil.copy(base, os.path.join(folder, base.name))  # a spec reads its base from its own folder
    doc["base"] = base.name
    doc["trials"] = trials
    doc["storage"] = f"sqlite:///{run}.db"
    path = os.path.join(folder, f"{run}.optimise.json")
    Path(path).write_text(json.dumps(doc))
    return path


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--trials", type=int, default=4)
    parser.add_argument("--dask", action="store_true", help="also time a local Dask cluster, for reference")
    parser.add_argument("--skip-optimise", action="store_true")
    args = parser.parse_args()
    print(f"{os.cpu_count()} cores; load average before: {load()}")
    with tempfile.TemporaryDirectory() as folder:
        env = dict(os.environ, LAMP_STYLING_CACHE=os.path.join(folder, "cache"))
        sheet = os.path.join(folder, "sheet.png")
        studies = {"default (local pool)": [], "one process (--workers 0)": []}
        if args.dask:
            studies["local Dask cluster (--engine dask)"] = []
        extra = {"default (local pool)": [], "one process (--workers 0)": ["--workers", "0"],
                 "local Dask cluster (--engine dask)": ["--engine", "dask"]}
        for _ in range(args.rounds):
            for name in studies:
                studies[name].append(timed([*STUDY, *extra[name], "-o", sheet], env))
        report("16-variant study at 128x128", studies)
        if args.skip_optimise:
            return 0
        runs = {"default (local pool)": [], "one process (--workers 0)": []}
        if args.dask:
            runs["local Dask cluster (--scheduler local)"] = []
        extra = {"default (local pool)": [], "one process (--workers 0)": ["--workers", "0"],
                 "local Dask cluster (--scheduler local)": ["--scheduler", "local"]}
        n = 0
        for _ in range(args.rounds):
            for name in runs:
                n += 1
                spec = optimise_file(folder, args.trials, f"run{n}")
                runs[name].append(timed(["optimise", spec, "--no-cache", "-o", os.path.join(folder, f"out{n}"),
                                         *extra[name]], env))
        report(f"optimise, even-stop-lamp example, {args.trials} trials", runs)
    print(f"load average after: {load()}")
    return 0


def report(title: str, runs: dict[str, list[tuple[float, float, str, int]]]) -> None:
    print(title)
    best = {name: (min(r[0] for r in rs), min(r[1] for r in rs), max(r[3] for r in rs)) for name, rs in runs.items()}
    one = best["one process (--workers 0)"]
    for name, (own, wall, pss) in best.items():
        print(f"  {name:42s} {own:7.2f} s ({own / one[0]:.2f}x), whole command {wall:6.2f} s ({wall / one[1]:.2f}x),"
              f" process tree {pss / 2**20:5.0f} MB PSS at most  [{', '.join(f'{r[0]:.2f}' for r in runs[name])}]")


if __name__ == "__main__":
    raise SystemExit(main())

"""``measure`` against one render, before and after the measures went on the local pool (issue 34
item 2), in one run.

    .venv/bin/python benchmarks/bench_measure_pool.py [--before /work/main] [--rounds 1] [--no-beam-files]

The four-lamp night photometric preset: ``render -o x.exr --width 512 --height 512 --samples 8``
(the band pool, as the command renders), then ``measure -o DIR`` with this tree's code and, given
``--before``, with that checkout's (the same command there), alternated ``--rounds`` times; each
whole command's wall time, best of the rounds, and its ratio to the render; and its CPU time (the
process and every worker it started, from the children's rusage), which a loaded machine changes
less than the wall time. Target: measure <= 3x the render. The load average is printed: on a
shared machine only the ratios mean anything.
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PRESET = ROOT / "presets" / "four-lamp-night-lit-photometric.json"


def load() -> str:
    return ", ".join(f"{x:.2f}" for x in os.getloadavg())


CPU: dict[str, list[float]] = {}  # CPU seconds of each run, by its name


def children_cpu() -> float:
    used = resource.getrusage(resource.RUSAGE_CHILDREN)
    return used.ru_utime + used.ru_stime


def timed(tree: Path, arguments: list[str], name: str) -> float:
    cpu, start = children_cpu(), time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "core_tracer", *arguments], cwd=tree, capture_output=True,
                          text=True, timeout=7200)
    if done.returncode != 0:
        raise SystemExit(f"{tree}: {' '.join(arguments)} failed:\n{done.stderr}")
    CPU.setdefault(name, []).append(children_cpu() - cpu)
    print(f"    {name}: {time.perf_counter() - start:.1f} s, CPU {CPU[name][-1]:.1f} s", flush=True)
    return time.perf_counter() - start


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--before", type=Path, help="a checkout of the code before (e.g. /work/main)")
    parser.add_argument("--rounds", type=int, default=1)
    parser.add_argument("--no-beam-files", action="store_true", help="measure the report alone (measure's option)")
    args = parser.parse_args()
    print(f"{os.cpu_count()} cores; load average before: {load()}", flush=True)
    runs: dict[str, list[float]] = {"render 512x512, 8 samples": [], "measure (this tree)": []}
    if args.before:
        runs["measure (before)"] = []
    extra = ["--exit-zero"] + (["--no-beam-files"] if args.no_beam_files else [])  # a failed regulation is a figure
    with tempfile.TemporaryDirectory() as folder:
        for r in range(args.rounds):
            runs["render 512x512, 8 samples"].append(timed(ROOT, ["render", str(PRESET), "-o", f"{folder}/r.exr",
                                                                  "--width", "512", "--height", "512",
                                                                  "--samples", "8"],
                                                            "render 512x512, 8 samples"))
            runs["measure (this tree)"].append(timed(ROOT, ["measure", str(PRESET), "-o", f"{folder}/m{r}", *extra],
                                                     "measure (this tree)"))
            if args.before:
                before = ["measure", str(PRESET), "-o", f"{folder}/b{r}", *extra]
                runs["measure (before)"].append(timed(args.before, before, "measure (before)"))
    render = min(runs["render 512x512, 8 samples"])
    render_cpu = min(CPU["render 512x512, 8 samples"])
    for name, times in runs.items():
        cpu = min(CPU[name])
        print(f"  {name:28s} {min(times):8.1f} s  {min(times) / render:5.2f}x the render  "
              f"[{', '.join(f'{t:.1f}' for t in times)}]; CPU {cpu:.1f} s, {cpu / render_cpu:5.2f}x the render's")
    print(f"load average after: {load()}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""The fixed costs of a small CLI render: a whole ``render`` of the day preset at 32x32, where tracing
is negligible (imports, the environment's world, the file), this tree against another.

    .venv/bin/python benchmarks/bench_fixed_costs.py [--base /work/base] [--runs 15] [--format exr]

Runs ``python -m core_tracer render presets/four-lamp-day-lit.json -o OUT --width 32 --height 32``
in each tree, interleaved (this tree, the other, this tree, ...) so that both see the same load, and
prints min / median wall and CPU seconds (user + system of the child) of each and their ratio, with
``python -c "import numpy"`` as the floor (``--no-bytecode-cache``: every module compiled in every
run, as under ``PYTHONDONTWRITEBYTECODE=1``). The first run of each tree is a warm-up (Python's
bytecode cache, the world cache): ``PYTHONPYCACHEPREFIX`` points at a temporary folder so neither
tree is written to, and each tree's world cache is its own temporary folder. On a loaded machine
compare the ratios of one run, and the CPU times rather than the wall times.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PRESET = "presets/four-lamp-day-lit.json"


def timed(command: list[str], cwd: Path, env: dict) -> tuple[float, float]:
    """(wall, CPU) seconds of one run of ``command``."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run(command, cwd=cwd, env=env, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--base", default="/work/base", help="the tree to compare with (its own .venv)")
    parser.add_argument("--runs", type=int, default=15)
    parser.add_argument("--format", default="exr", choices=("exr", "png"))
    parser.add_argument("--no-bytecode-cache", action="store_true",
                        help="compile every module in every run (PYTHONDONTWRITEBYTECODE=1, as some sandboxes set)")
    args = parser.parse_args()
    trees = {"this": ROOT, "base": Path(args.base)}
    times: dict[str, list[tuple[float, float]]] = {name: [] for name in (*trees, "numpy")}
    with tempfile.TemporaryDirectory() as tmp:
        env = {k: v for k, v in os.environ.items() if k not in ("PYTHONDONTWRITEBYTECODE", "PYTHONPYCACHEPREFIX")}
        if args.no_bytecode_cache:
            env["PYTHONDONTWRITEBYTECODE"] = "1"
        else:
            env["PYTHONPYCACHEPREFIX"] = os.path.join(tmp, "pycache")
        commands = {}
        envs = {}
        for name, tree in trees.items():
            out = os.path.join(tmp, f"{name}.{args.format}")
            python = str(tree / ".venv" / "bin" / "python")
            commands[name] = [python, "-m", "core_tracer", "render", PRESET, "-o", out, "--width", "32", "--height",
                              "32"]
            envs[name] = dict(env, LAMP_STYLING_CACHE=os.path.join(tmp, f"cache-{name}"))
        commands["numpy"] = [str(ROOT / ".venv" / "bin" / "python"), "-c", "import numpy"]
        envs["numpy"] = env
        cwd = {"this": ROOT, "base": trees["base"], "numpy": ROOT}
        for name in commands:  # warm-up
            timed(commands[name], cwd[name], envs[name])
        for _ in range(args.runs):
            for name in commands:
                times[name].append(timed(commands[name], cwd[name], envs[name]))
    cached = "no bytecode cache" if args.no_bytecode_cache else "bytecode cached"
    print(f"whole CLI render of {PRESET} at 32x32 to .{args.format}, {args.runs} interleaved runs, {cached}")
    print(f"{'':>6} {'wall min':>9} {'wall med':>9} {'cpu min':>8} {'cpu med':>8}")
    summary = {}
    for name, runs in times.items():
        walls, cpus = [w for w, _ in runs], [c for _, c in runs]
        summary[name] = (min(walls), statistics.median(walls), min(cpus), statistics.median(cpus))
        print(f"{name:>6} " + " ".join(f"{v:8.3f}s" for v in summary[name]))
    ratio = [t / b for t, b in zip(summary["this"], summary["base"], strict=True)]
    print(f"{'ratio':>6} " + " ".join(f"{v:8.2f}x" for v in ratio) + "   (this / base)")


if __name__ == "__main__":
    sys.exit(main())

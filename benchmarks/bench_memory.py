"""Peak memory of `render` against the estimate the command checks before rendering (core_tracer.budget).

    .venv/bin/python benchmarks/bench_memory.py [--sizes 512,1024,2048]

Renders the paper's baseline at each size to EXR and PNG, with and without --passes, each in a
fresh process, and prints the process's peak resident memory next to ``budget.render_bytes``.
The estimate should be at or above the measurement (it is what the budget is checked with).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from core_tracer import budget  # noqa: E402

BASELINE = ROOT / "presets" / "paper-baseline.json"
_MEASURE = ("import resource, sys; from core_tracer.cli import main; rc = main(sys.argv[1:]); "
            "print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024, file=sys.stderr); raise SystemExit(rc)")


def peak_bytes(args: list[str]) -> int:
    proc = subprocess.run([sys.executable, "-c", _MEASURE, *args], cwd=ROOT, capture_output=True, text=True)
    if proc.returncode != 0:
        raise SystemExit(proc.stderr)
    return int(proc.stderr.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="512,1024,2048")
    sizes = [int(s) for s in parser.parse_args().sizes.split(",")]
    print(f"{'size':>6} {'format':>6} {'passes':>6} {'measured MB':>12} {'estimate MB':>12}")
    with tempfile.TemporaryDirectory() as tmp:
        for size in sizes:
            for fmt in ("exr", "png"):
                for passes in (False, True):
                    if passes and fmt == "png":
                        continue
                    args = ["render", str(BASELINE), "-o", f"{tmp}/out.{fmt}", "--width", str(size),
                            "--height", str(size)]
                    if passes:
                        args += ["--passes", f"{tmp}/passes"]
                    measured = peak_bytes(args)
                    estimate = budget.render_bytes(size, size, passes, fmt)
                    print(f"{size:>6} {fmt:>6} {'yes' if passes else 'no':>6} {measured / 2**20:>12.0f} "
                          f"{estimate / 2**20:>12.0f}")


if __name__ == "__main__":
    main()

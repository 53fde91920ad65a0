"""The quick test run (``-m "not slow"``) by CPU time: each test's seconds of CPU (its process and the
subprocesses it waited for, set-up and teardown included), the total, and the tests over the slow
marker's 0.3 s. CPU time, not wall time: on a shared machine the wall clock of a test grows with the
other programs' load while its CPU time stays within a few per cent, and on a quiet machine a test on
one thread takes about its CPU time. Target: the quick run's CPU under 90 s, every test under 0.3 s.

    xvfb-run -a .venv/bin/python benchmarks/bench_quick_tests.py [--tsv FILE] [pytest arguments]

Without pytest arguments it runs ``tests``; give folders or files to measure a part (shards of the
run can be measured side by side and their TSV files joined). ``--tsv`` writes node id, wall
seconds and CPU seconds a line, as each test ends.
"""

from __future__ import annotations

import argparse
import resource
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
SLOW_CPU_S = 0.3  # tests/pytest.ini: "slow: over ~0.3 s"
TARGET_CPU_S = 90.0


def _cpu() -> float:
    own = resource.getrusage(resource.RUSAGE_SELF)
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


class CpuClock:
    """A pytest plugin: (node id, wall s, CPU s) of every test, appended to ``tsv`` as it ends."""

    def __init__(self, tsv: Path | None):
        self.rows: list[tuple[str, float, float]] = []
        self.tsv = tsv

    @pytest.hookimpl(hookwrapper=True)
    def pytest_runtest_protocol(self, item, nextitem):
        wall, cpu = time.perf_counter(), _cpu()
        yield
        row = (item.nodeid, time.perf_counter() - wall, _cpu() - cpu)
        self.rows.append(row)
        if self.tsv is not None:
            with self.tsv.open("a", encoding="utf-8") as f:
                f.write(f"{row[0]}\t{row[1]:.3f}\t{row[2]:.3f}\n")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--tsv", type=Path, help="write node id, wall s, CPU s a line")
    args, pytest_args = parser.parse_known_args(argv)
    clock = CpuClock(args.tsv)
    started = _cpu()
    code = pytest.main(["-c", str(ROOT / "tests" / "pytest.ini"), "-m", "not slow", "-q", "-p", "no:cacheprovider",
                        *(pytest_args or [str(ROOT / "tests")])], plugins=[clock])
    total = _cpu() - started
    in_tests = sum(cpu for _, _, cpu in clock.rows)
    over = sorted((row for row in clock.rows if row[2] >= SLOW_CPU_S), key=lambda row: -row[2])
    print(f"\n{len(clock.rows)} tests: {total:.1f} s of CPU in all ({in_tests:.1f} s in the tests, the rest "
          f"collection and session set-up); target under {TARGET_CPU_S:.0f} s")
    print(f"{len(over)} tests over {SLOW_CPU_S} s of CPU (mark them slow):")
    for nodeid, _, cpu in over:
        print(f"  {cpu:6.2f} s  {nodeid}")
    return int(code)


if __name__ == "__main__":
    sys.exit(main())

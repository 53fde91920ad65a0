"""The walk's throughput, old tree against new, in one run (issue 34 item 5): CPU seconds and ray
segments of three presets on one thread (numpy's BLAS on one thread too), each tree in its own
process, the two alternating, the least CPU time of the rounds kept.

    .venv/bin/python benchmarks/bench_throughput_trees.py OLD_TREE NEW_TREE [--rounds 3]

OLD_TREE is a worktree of the commit to compare with (``git worktree add --detach /tmp/old <commit>``,
its ``.venv`` a symlink to this one's).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

CASES = [("four-lamp-rear-combination", 512, None), ("four-lamp-day-lit", 512, 16),
         ("four-lamp-night-lit-photometric", 512, 8)]
CHILD = r"""
import json, sys, time
sys.path.insert(0, sys.argv[1])
import core_tracer
from core_tracer.raytrace.engine import render_passes
out = {}
for name, size, samples in json.loads(sys.argv[2]):
    scene = core_tracer.load_scene(sys.argv[1] + "/presets/" + name + ".json")
    options = {} if samples is None else {"samples": samples}
    render_passes(scene, 64, 64, threads=1, keep_passes=False, **options)  # warm up
    start = time.process_time()
    result = render_passes(scene, size, size, threads=1, keep_passes=False, **options)
    out[name] = (time.process_time() - start, result.stats["segments"])
print(json.dumps(out))
"""


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("old")
    parser.add_argument("new")
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    trees = [("old", args.old), ("new", args.new)]
    runs: dict[str, dict[str, list]] = {"old": {}, "new": {}}
    for r in range(args.rounds):
        for label, tree in (trees if r % 2 == 0 else trees[::-1]):
            done = subprocess.run([sys.executable, "-c", CHILD, os.path.abspath(tree), json.dumps(CASES)],
                                  capture_output=True, text=True, env=env)
            if done.returncode:
                raise SystemExit(done.stderr[-2000:])
            for name, measured in json.loads(done.stdout.strip().splitlines()[-1]).items():
                runs[label].setdefault(name, []).append(measured)
    print(f"one thread, least CPU of {args.rounds} rounds; load average {os.getloadavg()[0]:.1f}")
    for name, _, _ in CASES:
        print(_compared(name, min(runs["old"][name]), min(runs["new"][name])))
    return 0


def _compared(name: str, old: tuple[float, int], new: tuple[float, int]) -> str:
    """One preset's line: each tree's (CPU seconds, segments), the time and throughput ratios."""
    (old_s, old_segments), (new_s, new_segments) = old, new
    old_rate, new_rate = old_segments / old_s, new_segments / new_s
    return (f"{name}: old {old_s:.2f} s ({old_rate / 1e6:.2f} M segments/s), new {new_s:.2f} s "
            f"({new_rate / 1e6:.2f} M segments/s): time new/old {new_s / old_s:.3f}, throughput "
            f"{new_rate / old_rate:.3f}x")


if __name__ == "__main__":
    raise SystemExit(main())

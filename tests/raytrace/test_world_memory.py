"""The memory budget counts a render's whole footprint: the parent and every band worker (issue 20,
item 7), measured as the sum of their resident memory read from /proc while the render runs."""

from __future__ import annotations

import os
import subprocess
import sys
import time

import pytest
from helpers import PRESETS, ROOT, cli_command

from core_tracer import budget
from core_tracer.cli.common import load_scene_file
from core_tracer.raytrace import environment

pytestmark = [pytest.mark.slow, pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")]


def resident(pid: int) -> int:
    """Resident bytes of process ``pid`` (0 once it is gone)."""
    try:
        with open(f"/proc/{pid}/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return 0


def children(pid: int) -> list[int]:
    try:
        with open(f"/proc/{pid}/task/{pid}/children") as f:
            return [int(p) for p in f.read().split()]
    except OSError:
        return []


def test_the_budget_counts_the_parent_and_every_band_worker(tmp_path):
    preset = PRESETS / "four-lamp-day-lit.json"
    width = height = 512
    samples = 8  # 2.1 million eye rays: the band pool's worker processes trace the bands
    assert budget.uses_pool(width, height, samples)
    env = dict(os.environ, LAMP_STYLING_CACHE=str(tmp_path / "cache"))
    proc = subprocess.Popen(cli_command("render", preset, "-o", tmp_path / "out.exr", "--width", width, "--height",
                                        height, "--samples", samples), cwd=ROOT, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    peak_sum = peak_one = processes = 0
    while proc.poll() is None:
        pids = [proc.pid, *children(proc.pid)]
        sizes = [resident(pid) for pid in pids]
        peak_sum, peak_one = max(peak_sum, sum(sizes)), max(peak_one, *sizes)
        processes = max(processes, len(pids))
        time.sleep(0.02)
    assert proc.returncode == 0, proc.stderr.read()
    workers = os.cpu_count() or 1
    assert processes == 1 + workers  # the parent and the pool's workers
    assert peak_sum > peak_one  # a per-process view misses most of the footprint
    scene = load_scene_file(preset, width, height, samples)
    estimate = budget.render_bytes(width, height, False, "exr", environment=environment.world_bytes(scene),
                                   workers=workers)
    assert peak_sum <= estimate, (peak_sum / 2**20, estimate / 2**20)

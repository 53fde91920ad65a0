"""Measures on the local worker pool (issue 34 item 2): the directions' renders shared among worker
processes give the values of one process bit for bit, and the workers are counted against the
memory budget before any starts."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from core_tracer import budget
from core_tracer.measures import intensity
from core_tracer.raytrace import band_pool
from core_tracer.scene import load_scene

DIRECTIONS = [(0.0, 0.0), (10.0, 5.0), (-20.0, 0.0), (5.0, -10.0), (0.0, 10.0)]


@pytest.mark.slow
def test_directions_on_the_pool_equal_one_process_bit_for_bit(repo_root):
    scene = load_scene(repo_root / "presets" / "photometric-stop-lamp.json")
    options = {"pixel_mm": 4.0, "replicates": 2}
    seen = []
    pooled = intensity.intensities_at(scene, DIRECTIONS, seeds=range(5), workers=2,
                                      progress=lambda done, total: seen.append((done, total)), **options)
    here = intensity.intensities_at(scene, DIRECTIONS, seeds=range(5), workers=1, **options)
    assert seen == [(k, 5) for k in range(1, 6)]
    for a, b in zip(pooled, here, strict=True):
        assert [(x.cd, x.stderr) for x in a] == [(y.cd, y.stderr) for y in b]
        assert all(np.array_equal(x.xyz, y.xyz) for x, y in zip(a, b, strict=True))
    # and each is rendered_intensities' own figure at its seed
    direct = intensity.rendered_intensity(scene, *DIRECTIONS[3], seed=3, **options)
    assert (direct.cd, direct.stderr) == (here[3][0].cd, here[3][0].stderr)
    assert here[0][0].cd > 0


def test_the_pool_is_sized_by_the_memory_budget_before_it_starts(repo_root, monkeypatch):
    scene = load_scene(repo_root / "presets" / "photometric-stop-lamp.json")
    monkeypatch.delitem(sys.modules, "bpy", raising=False)  # as the command line: the Blender tests import bpy
    monkeypatch.setattr(band_pool, "running_workers", lambda: 0)  # no band pool left by an earlier test
    monkeypatch.setattr("os.cpu_count", lambda: 8)
    assert intensity.pool_workers(scene, 45, 2.0) == 6  # (4 GB - 160 MB) over 640 MB and a view a worker
    assert intensity.pool_workers(scene, 3, 2.0) == 1  # too few directions to share
    monkeypatch.setattr(band_pool, "running_workers", lambda: 2)  # its idle workers' memory is counted too
    assert intensity.pool_workers(scene, 45, 2.0) == 4
    monkeypatch.setattr(band_pool, "running_workers", lambda: 0)
    monkeypatch.setattr(budget, "MEMORY_BUDGET", budget.BASE_BYTES + budget.WORKER_BYTES + 2**20)
    assert intensity.pool_workers(scene, 45, 2.0) == 1  # one worker's figure does not fit beside this process


@pytest.mark.slow
def test_a_worker_measures_its_directions_itself(repo_root, monkeypatch):
    """A study's or a trial's task already runs in a worker beside others: it starts no pool of its own."""
    from core_tracer.cluster.local_pool import LocalPool

    monkeypatch.delitem(sys.modules, "bpy", raising=False)  # as the command line: the Blender tests import bpy

    scene = load_scene(repo_root / "presets" / "photometric-stop-lamp.json")
    with LocalPool(1) as pool:
        assert pool.submit(intensity.pool_workers, scene, 45, 2.0).result() == 1
    assert intensity.pool_workers(scene, 45, 2.0) > 1 or (__import__("os").cpu_count() or 1) == 1


@pytest.mark.slow
def test_the_lamp_picture_on_the_band_pool_is_the_threads_picture(repo_root, monkeypatch):
    from core_tracer.measures import report

    scene = load_scene(repo_root / "presets" / "photometric-stop-lamp.json")
    pool = band_pool.shared()
    assert pool is not None and pool.ready(timeout=60)  # measure() starts it early for the picture
    before = pool.renders
    pooled = report.lamp_picture(scene, width=160)
    assert pool.renders == before + 1  # its bands went to the pool's workers
    monkeypatch.setattr(band_pool, "enabled", False)
    assert np.array_equal(pooled, report.lamp_picture(scene, width=160))

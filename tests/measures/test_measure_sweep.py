"""``measure`` in one sweep on the local pool (issue 34 item 2): the regulation grids' directions and
the beam files' measured together, with the flux out's light tracing and the front view as tasks
beside them, give every figure the parts give alone, bit for bit."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from core_tracer.measures import export, intensity, report
from core_tracer.scene import load_scene

DIRECTIONS = [(0.0, 0.0), (10.0, 5.0), (-20.0, 0.0), (5.0, -10.0), (0.0, 10.0)]


@pytest.mark.slow
def test_tasks_beside_the_directions_give_what_they_give_alone(repo_root, monkeypatch):
    monkeypatch.delitem(sys.modules, "bpy", raising=False)  # as the command line: the Blender tests import bpy
    scene = load_scene(repo_root / "presets" / "photometric-stop-lamp.json")
    tasks = [(export.traced_flux, (scene, [[0]], 2000))]
    options = {"pixel_mm": 4.0, "replicates": 2, "seeds": range(5)}
    pooled, done = intensity.measured_together(scene, DIRECTIONS, tasks=tasks, workers=2, **options)
    here, alone = intensity.measured_together(scene, DIRECTIONS, tasks=tasks, workers=1, **options)
    assert done == alone == [export.traced_flux(scene, [[0]], 2000)] and done[0][0][0] > 0
    assert [[(x.cd, x.stderr) for x in a] for a in pooled] == [[(x.cd, x.stderr) for x in a] for a in here]


@pytest.mark.slow
def test_one_sweep_gives_the_report_and_the_beam_files_each_measured_alone(repo_root, monkeypatch):
    monkeypatch.delitem(sys.modules, "bpy", raising=False)
    scene = load_scene(repo_root / "presets" / "photometric-stop-lamp.json")
    options = {"pixel_mm": 5.0, "replicates": 2, "front_pixel_mm": 2.0}
    together = report.measure(scene, beams=export.COARSE_GRID, photons=2000, **options)
    alone = report.measure(scene, **options)
    files = export.measure_distributions(scene, together.functions, grid=export.COARSE_GRID, photons=2000,
                                         pixel_mm=5.0, replicates=2)
    assert [r.as_dict() for r in together.rows] == [r.as_dict() for r in alone.rows]
    assert together.colours == alone.colours and together.homogeneity == alone.homogeneity
    assert np.array_equal(together.front_view["luminance"], alone.front_view["luminance"])
    assert together.beams.keys() == files.keys() == {"stop"}
    for name, dist in files.items():
        got = together.beams[name]
        assert np.array_equal(got.cd, dist.cd) and np.array_equal(got.stderr, dist.stderr)
        assert (got.out_lm, got.out_stderr_lm, got.xy) == (dist.out_lm, dist.out_stderr_lm, dist.xy)
        assert got.out_lm > 0
    assert alone.beams == {}


def test_the_task_beside_the_directions_is_counted_before_the_pool_starts(repo_root, monkeypatch):
    """The flux out's light tracing (about 1.1 GB) goes to a worker beside the views: its excess over a
    worker's figure is counted once, before any worker starts."""
    from core_tracer import budget
    from core_tracer.raytrace import band_pool

    scene = load_scene(repo_root / "presets" / "photometric-stop-lamp.json")
    monkeypatch.delitem(sys.modules, "bpy", raising=False)
    monkeypatch.setattr(band_pool, "running_workers", lambda: 0)
    monkeypatch.setattr("os.cpu_count", lambda: 8)
    assert intensity.pool_workers(scene, 45, 2.0) == intensity.pool_workers(scene, 45, 2.0, 2**20) == 6
    assert intensity.pool_workers(scene, 45, 2.0, export.TRACED_FLUX_BYTES) == 5  # 460 MB more for one worker
    monkeypatch.setattr(budget, "MEMORY_BUDGET", budget.BASE_BYTES + 2 * budget.WORKER_BYTES + 2**23)
    assert intensity.pool_workers(scene, 45, 2.0) == 2
    assert intensity.pool_workers(scene, 45, 2.0, export.TRACED_FLUX_BYTES) == 1  # then in this process alone

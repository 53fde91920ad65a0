"""The band pool (``band_pool``): a render's bands traced in worker processes give, bit for bit,
what threads give (the image, every pass, the segment count, the deepest branch, the busy pixels
and the transitions) at one sample (tails carried), with adaptive sampling and with every sample;
a cancelled render leaves the workers ready for the next; a worker that dies or fails never loses
the render or hangs it; a busy, starting or closed pool hands the render to threads."""

from __future__ import annotations

import os
import signal
import sys

import numpy as np
import pytest
from helpers import PRESETS, scene_with

from core_tracer import load_scene, processes
from core_tracer.raytrace import band_pool, engine

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def pool():
    own = band_pool.BandPool(2)
    assert own.ready(30), own.broken
    yield own
    own.close()


def load_preset(name: str) -> dict:
    return load_scene(str(PRESETS / name))


def _day() -> dict:
    return load_preset("four-lamp-day-lit.json")


def _clear_deep_cuts() -> dict:
    # Total internal reflection in a clear lens of n = 2.4 keeps branches going for dozens of
    # generations: the workers carry long tails from band to band.
    return scene_with(**{"lamps[0].lens.ior": 2.4, "lamps[0].lens.absorption": [0, 0, 0], "lamps[0].cuts.pitch": 3.0})


CASES = {
    # scene, width, height, rows per band (TILE_RAYS / width / samples), render_passes options
    "one-sample": (lambda: load_preset("four-lamp-rear-combination.json"), 160, 120, 8, {"samples": 1}),
    "deep-tails": (_clear_deep_cuts, 96, 72, 6, {"samples": 1, "record_transitions": True}),
    "adaptive-deep-tails": (_clear_deep_cuts, 64, 48, 4, {"samples": 16, "record_transitions": True}),
    "every-sample-four-lamps": (lambda: load_preset("four-lamp-rear-combination.json"), 64, 48, 4,
                                {"samples": 8, "adaptive_threshold": 0}),
    "adaptive-surroundings": (_day, 96, 64, 4, {"samples": 16}),
    "every-sample-surroundings": (_day, 64, 48, 4, {"samples": 8, "adaptive_threshold": 0}),
    # the light states' one walk: each source's light kept (``rays.BySource``), with and without adaptive sampling
    "by-source-surroundings": (_day, 64, 48, 4, {"samples": 8, "adaptive_threshold": 0, "by_source": True}),
    "adaptive-by-source-surroundings": (_day, 96, 64, 4, {"samples": 16, "by_source": True}),
}


def _render(monkeypatch, case: str, **options) -> engine.RenderResult:
    make, width, height, rows, extra = CASES[case]
    samples = extra["samples"]
    adaptive = samples > 1 and extra.get("adaptive_threshold") != 0
    # The parent cuts the image into bands of ``rows`` rows (as ``engine.schedule.band_rows`` does); the
    # workers trace the rows they are given.
    per_row = width * (len(engine.sampling.pilot_samples(samples)) if adaptive else samples)
    monkeypatch.setattr(engine.sampling, "TILE_RAYS", per_row * (rows + 2 if adaptive else rows))
    try:
        return engine.render_passes(make(), width, height, keep_passes=True, **extra, **options)
    finally:
        monkeypatch.undo()


def _same(a: engine.RenderResult, b: engine.RenderResult, ulps: int = 0) -> None:
    """Equal bit for bit (``ulps`` 0), or within ``ulps`` float32 units in the last place."""
    def equal(x: np.ndarray, y: np.ndarray) -> None:
        if ulps:
            np.testing.assert_array_max_ulp(x, y, maxulp=ulps)
        else:
            assert np.array_equal(x, y)

    equal(a.image, b.image)
    assert a.passes.keys() == b.passes.keys()
    for name in a.passes:
        equal(a.passes[name], b.passes[name])
    for key in ("segments", "max_depth", "busy_pixels", "transitions"):
        assert a.stats[key] == b.stats[key], key


@pytest.mark.parametrize("case", CASES)
def test_the_pool_traces_what_threads_trace(monkeypatch, pool, case):
    on_threads = _render(monkeypatch, case, threads=2)
    renders = pool.renders
    in_pool = _render(monkeypatch, case, threads=2, pool=pool)
    assert pool.renders == renders + 1
    assert on_threads.stats["worker_processes"] == 0
    assert in_pool.stats["worker_processes"] == 2  # both workers took bands
    # With surroundings, the last bits of the float64 world lookups vary with how numpy's AVX-512
    # code paths meet the arrays (up to 6e-14 relative between two identical traces of a band; none
    # with NPY_DISABLE_CPU_FEATURES turning AVX-512 off), so a float32 value may move by one unit in
    # the last place; without surroundings every value is the same bit for bit.
    _same(on_threads, in_pool, ulps=1 if "surroundings" in case else 0)
    if case == "deep-tails":
        assert in_pool.stats["transitions"]  # recorded in the workers, brought back


def test_bands_arrive_in_order_with_progress(monkeypatch, pool):
    # ... and the interpreter's switch interval is short while the workers trace (they wait for this
    # process's answers), the caller's afterwards
    rows, fractions, intervals = [], [], []
    before = sys.getswitchinterval()

    def on_rows(y0, y1, _):
        rows.append((y0, y1))
        intervals.append(sys.getswitchinterval())

    _render(monkeypatch, "one-sample", threads=2, pool=pool, on_rows=on_rows, progress=fractions.append)
    assert rows == [(y, min(120, y + 8)) for y in range(0, 120, 8)]
    assert fractions == [k / len(rows) for k in range(1, len(rows) + 1)]
    assert intervals == pytest.approx([engine.schedule.SWITCH_INTERVAL] * len(rows))
    assert sys.getswitchinterval() == before


def test_a_cancelled_render_leaves_the_workers_ready_for_the_next(monkeypatch, pool):
    bands = []
    with pytest.raises(engine.RenderCancelled):
        _render(monkeypatch, "deep-tails", threads=2, pool=pool, should_stop=lambda: len(bands) >= 2,
                on_rows=lambda y0, y1, _: bands.append(y0))
    assert len(bands) == 2
    assert pool.ready() and pool.broken is None
    renders = pool.renders
    _same(_render(monkeypatch, "deep-tails", threads=2), _render(monkeypatch, "deep-tails", threads=2, pool=pool))
    assert pool.renders == renders + 1


def test_a_render_that_finds_the_pool_busy_runs_on_threads(monkeypatch, pool):
    monkeypatch.setattr(band_pool, "LEASE_WAIT", 0.01)
    inner: list[engine.RenderResult] = []

    def render_meanwhile(y0, y1, rows):
        if not inner:  # while the first render holds the pool
            inner.append(engine.render_passes(load_preset("four-lamp-rear-combination.json"), 160, 120,
                                              keep_passes=False, threads=2, pool=pool))

    outer = engine.render_passes(load_preset("four-lamp-rear-combination.json"), 640, 480, keep_passes=False,
                                 threads=2, pool=pool, on_rows=render_meanwhile)
    assert outer.stats["worker_processes"] == 2
    assert inner[0].stats["worker_processes"] == 0
    alone = engine.render_passes(load_preset("four-lamp-rear-combination.json"), 160, 120, keep_passes=False,
                                 threads=2)
    assert np.array_equal(inner[0].image, alone.image)


def test_a_failing_worker_raises_its_error_and_the_pool_serves_on(pool):
    scene = load_preset("four-lamp-rear-combination.json")
    options = {"record_transitions": False, "samples": 1, "filter_name": "no-such-filter",
               "adaptive_threshold": 0.0, "world_seen": True, "keep_passes": False}
    with pytest.raises(band_pool.BandWorkerError, match="no-such-filter"):
        list(pool.traced_bands(scene, 64, 48, options, [(0, 24), (24, 48)], 2, lambda: False, lambda rest: iter(())))
    assert pool.ready() and pool.broken is None
    result = engine.render_passes(scene, 640, 480, threads=2, pool=pool, keep_passes=False)
    assert result.stats["worker_processes"] == 2


def test_a_worker_killed_mid_render_loses_nothing(monkeypatch):
    doomed = band_pool.BandPool(2)
    assert doomed.ready(30)
    killed = []

    def kill_once() -> bool:
        if not killed:
            killed.append(doomed.process_ids()[0])
            os.kill(killed[0], signal.SIGKILL)
        return False

    try:
        survived = _render(monkeypatch, "deep-tails", threads=2, pool=doomed, should_stop=kill_once)
        assert killed
        assert doomed.broken is not None and "ended unexpectedly" in doomed.broken
        _same(_render(monkeypatch, "deep-tails", threads=2), survived)
    finally:
        doomed.close()
    assert [p.poll() is not None for p in doomed._processes] == [True, True]


def test_closing_ends_the_workers_and_removes_the_flag_file():
    closing = band_pool.BandPool(2)
    assert closing.ready(30)
    flag = closing._flag_path
    assert not os.path.exists(flag)  # removed once every worker has mapped it (POSIX)
    closing.close()
    closing.close()  # idempotent
    assert [p.poll() is not None for p in closing._processes] == [True, True]
    assert not closing.ready()
    scene = load_preset("four-lamp-rear-combination.json")
    result = engine.render_passes(scene, 640, 480, threads=2, pool=closing, keep_passes=False)
    assert result.stats["worker_processes"] == 0  # on threads


def test_the_shared_pool_is_one_until_shut_down():
    band_pool.shutdown()
    first = band_pool.shared()
    assert first is not None and band_pool.shared() is first
    band_pool.shutdown()
    assert first.broken == "closed"
    second = band_pool.shared()
    assert second is not first and second.broken is None
    band_pool.shutdown()


def test_only_a_python_interpreter_is_started_as_a_worker(tmp_path):
    for name, runs in (("python3.11", True), ("python", True), ("blender", False), ("Blender.exe", False)):
        path = tmp_path / name
        path.write_text("")
        assert processes.python_runs_workers(str(path)) is runs, name
    assert not processes.python_runs_workers(str(tmp_path / "python-missing"))

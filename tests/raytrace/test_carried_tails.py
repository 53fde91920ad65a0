"""Carried tails (``carried.carrying_tails``): a band's last few rays traced in the wavefront of the
worker's next band give, bit for bit, what tracing each band apart gives (``schedule.trace_band``):
the image, every pass, the segment count, the deepest branch and the transitions; callbacks still
come in band order, and a cancelled render stops with no thread left running."""

from __future__ import annotations

import threading

import numpy as np
import pytest
from helpers import scene_with

from core_tracer.raytrace import engine

pytestmark = pytest.mark.slow

WIDTH, HEIGHT = 96, 72


def _long_tails_scene() -> dict:
    # A clear lens of n = 2.4 with 3 mm cuts: total internal reflection keeps branches going for
    # dozens of generations after most of a band's rays have ended.
    return scene_with(**{"lamps[0].lens.ior": 2.4, "lamps[0].lens.absorption": [0, 0, 0],
                         "lamps[0].cuts.pitch": 3.0, "image": {"width": WIDTH, "height": HEIGHT}})


def _render(monkeypatch, carry: int | None, threads: int, **options) -> engine.RenderResult:
    """The render in bands of 6 rows (12 bands); ``carry`` None: each band traced apart, by
    ``schedule.trace_band``, as before tails were carried."""
    monkeypatch.setattr(engine.sampling, "TILE_RAYS", WIDTH * 6)
    if carry is None:
        monkeypatch.setattr(engine.schedule, "_carried_bands", engine.schedule.bands_on_threads)
    else:
        monkeypatch.setattr(engine.carried, "CARRY_RAYS", carry)
    try:
        return engine.render_passes(_long_tails_scene(), threads=threads, record_transitions=True, **options)
    finally:
        monkeypatch.undo()


def _carried_counts(monkeypatch) -> list[int]:
    """Per wavefront started, how many earlier bands' rays it carries."""
    carried = []
    start = engine.carried._next_wavefront

    def counting(ctx, tails, wave, rays, *job):
        carried.append(len(tails))
        return start(ctx, tails, wave, rays, *job)

    monkeypatch.setattr(engine.carried, "_next_wavefront", counting)
    return carried


@pytest.mark.parametrize("threads", [1, 2])
@pytest.mark.parametrize("max_depth", [1000, 64, 7])
@pytest.mark.parametrize("carry", [200, 10**9], ids=["carry-200", "carry-all"])
def test_carried_tails_give_what_bands_traced_apart_give(monkeypatch, threads, max_depth, carry):
    # With MAX_DEPTH at 64 or 7 branches are cut in many bands: each carried band must count its own
    # depth; at 1000 every branch ends by the cut-off.
    # carry-all carries every band's rays from its first hits on (several bands at once).
    monkeypatch.setattr(engine.context, "MAX_DEPTH", max_depth)
    apart = _render(monkeypatch, None, threads)
    monkeypatch.setattr(engine.context, "MAX_DEPTH", max_depth)
    carried_counts = _carried_counts(monkeypatch)
    carried = _render(monkeypatch, carry, threads)
    assert max(carried_counts) >= (3 if carry > 10**6 else 1)  # tails were carried, several at once
    assert (apart.stats["max_depth"] == max_depth) == (max_depth < 1000)
    np.testing.assert_array_equal(carried.image, apart.image)
    assert carried.passes.keys() == apart.passes.keys()
    for name in apart.passes:
        np.testing.assert_array_equal(carried.passes[name], apart.passes[name])
    for key in ("segments", "max_depth", "transitions"):
        assert carried.stats[key] == apart.stats[key], key


def test_each_band_keeps_its_own_statistics(monkeypatch):
    # The bands handed to the caller carry their own segment count and deepest branch.
    def per_band(carry):
        seen = []
        traced = engine.schedule.traced_bands
        monkeypatch.setattr(engine.schedule, "traced_bands", lambda *args: (
            (y0, y1, seen.append((y0, band.segments, band.max_depth, frozenset(band.transitions))) or band)
            for y0, y1, band in traced(*args)))
        _render(monkeypatch, carry, 2)
        return seen

    apart, carried = per_band(None), per_band(10**9)
    assert len(apart) == 12 and len({depth for _, _, depth, _ in apart}) > 3
    assert carried == apart


@pytest.mark.parametrize("threads", [1, 2])
def test_callbacks_come_in_band_order_with_the_final_rows(monkeypatch, threads):
    calls = []

    def on_band(y0, y1, rows, passes):
        calls.append((y0, y1, rows.copy(), sum(passes.values())))

    progress = []
    result = _render(monkeypatch, 200, threads, on_band=on_band, progress=progress.append)
    assert [(y0, y1) for y0, y1, *_ in calls] == [(y, y + 6) for y in range(0, HEIGHT, 6)]
    assert progress == pytest.approx([(i + 1) / 12 for i in range(12)])
    np.testing.assert_array_equal(np.concatenate([rows for _, _, rows, _ in calls]), result.image)
    np.testing.assert_allclose(np.concatenate([p for *_, p in calls]), result.image, rtol=1e-6)


@pytest.mark.parametrize("threads", [1, 2])
def test_cancelling_while_tails_are_carried_stops_every_worker(monkeypatch, threads):
    # Stop once the second band is out: by then later bands are being traced, some of their rays
    # carried by another band's wavefront. The render raises, nothing more is handed out, and no
    # thread of the render is left running.
    before = set(threading.enumerate())
    bands = []
    polls_after_stop = []

    def should_stop():
        if len(bands) >= 2:
            polls_after_stop.append(True)
        return len(bands) >= 2

    with pytest.raises(engine.RenderCancelled):
        _render(monkeypatch, 10**9, threads, should_stop=should_stop,
                on_rows=lambda a, b, rows: bands.append((a, b)))
    assert bands == [(0, 6), (6, 12)]
    assert len(polls_after_stop) == 1
    assert set(threading.enumerate()) == before


def test_an_error_in_a_worker_reaches_the_caller_and_stops_the_other(monkeypatch):
    steps = []
    step = engine.walk.step

    def failing(ctx, band, rays):
        steps.append(len(rays))
        if len(steps) == 30:
            raise FloatingPointError("from a worker")
        return step(ctx, band, rays)

    monkeypatch.setattr(engine.walk, "step", failing)
    monkeypatch.setattr(engine.sampling, "TILE_RAYS", WIDTH * 6)
    before = set(threading.enumerate())
    with pytest.raises(FloatingPointError, match="from a worker"):
        engine.render_passes(_long_tails_scene(), threads=2)
    assert set(threading.enumerate()) == before

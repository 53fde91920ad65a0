"""Carried samples (``carried.carrying_samples``): with more than one sample per pixel, each group of
eye rays a band's sampling asks for starts in the wavefront of the deep branches still being traced
for earlier groups; every band is, bit for bit, what tracing it apart gives (``schedule.trace_band``):
every pass, the segment count, the deepest branch, the busy pixels and the transitions."""

from __future__ import annotations

from collections import deque

import numpy as np
import pytest
from helpers import scene_with

from core_tracer.raytrace import engine
from core_tracer.raytrace.camera import make_camera

pytestmark = pytest.mark.slow

WIDTH, HEIGHT, SAMPLES = 48, 36, 8


def _context(adaptive_threshold: float) -> engine.context.Context:
    # A clear lens of n = 2.4 with 3 mm cuts keeps branches going for dozens of generations after most
    # rays have ended (total internal reflection); a grey background and a wide view give pixels that
    # see only it, whose samples adaptive sampling looks up without tracing (``_world_samples``).
    scene = scene_with(**{"lamps[0].lens.ior": 2.4, "lamps[0].lens.absorption": [0, 0, 0],
                          "lamps[0].cuts.pitch": 3.0, "background": [0.2, 0.3, 0.4]})
    scene["camera"]["fov_deg"] = 2.0 * scene["camera"]["fov_deg"]
    return engine.context.Context(scene, make_camera(scene["camera"], WIDTH, HEIGHT), True, SAMPLES, "blackman-harris",
                           adaptive_threshold)


def _bands(rows: int) -> list[tuple[int, int]]:
    return [(y, min(HEIGHT, y + rows)) for y in range(0, HEIGHT, rows)]


def _carried(ctx: engine.context.Context, bands: list[tuple[int, int]],
             stopped=lambda: False) -> dict[int, engine.rays.Band]:
    queued = deque(enumerate(bands))

    def take():
        if not queued:
            return None
        index, (y0, y1) = queued.popleft()
        return index, y0, y1

    return dict(engine.carried.carrying_samples(ctx, take, stopped))


@pytest.mark.parametrize("adaptive_threshold", [0.01, 0.0], ids=["adaptive", "every-sample"])
@pytest.mark.parametrize("max_depth", [1000, 64, 7])
@pytest.mark.parametrize("carry", [200, 10**9], ids=["carry-200", "carry-all"])
def test_carried_samples_give_what_bands_traced_apart_give(monkeypatch, adaptive_threshold, max_depth, carry):
    # Groups of at most 4 rows of pilot samples: bands of 2 rows ask for several groups each, the
    # rest of their busy pixels' samples in groups of their own. carry-all starts every group in the
    # wavefront of all the rays still live (several groups at once).
    monkeypatch.setattr(engine.context, "MAX_DEPTH", max_depth)
    monkeypatch.setattr(engine.sampling, "TILE_RAYS", WIDTH * 4 * 3)
    monkeypatch.setattr(engine.carried, "CARRY_RAYS", carry)
    ctx = _context(adaptive_threshold)
    bands = _bands(2)
    apart = [engine.schedule.trace_band(ctx, y0, y1) for y0, y1 in bands]
    started = []
    carrying = engine.carried._carried_wavefront

    def counting(ctx, tails, *args):
        started.append(len(tails))
        return carrying(ctx, tails, *args)

    monkeypatch.setattr(engine.carried, "_carried_wavefront", counting)
    carried = _carried(ctx, bands)
    assert sorted(carried) == list(range(len(bands)))
    assert max(started) >= (3 if carry > 10**6 else 1)  # groups were carried, several at once
    assert (max(band.max_depth for band in apart) == max_depth) == (max_depth < 1000)
    if max_depth == 7:  # branches alive at the depth limit end there and are counted
        assert sum(band.cut_at_depth for band in apart) > 0
    if adaptive_threshold:
        assert 0 < sum(band.busy for band in apart) < WIDTH * HEIGHT
    for index, band in enumerate(apart):
        np.testing.assert_array_equal(carried[index].acc, band.acc)
        for key in ("segments", "max_depth", "cut_at_depth", "busy", "transitions"):
            assert getattr(carried[index], key) == getattr(band, key), (index, key)


def test_a_stopped_worker_hands_out_no_more_bands():
    ctx = _context(0.01)
    polls = []

    def stopped():
        polls.append(True)
        return len(polls) > 5

    carried = _carried(ctx, _bands(4), stopped)
    assert len(carried) < len(_bands(4)) and len(polls) == 6

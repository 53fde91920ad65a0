"""Memory counted before ``measure`` and ``states`` as before ``render`` (issue 33 item 5): the whole
footprint from ``budget``, refused in one line before anything is rendered; the estimates hold
what tracemalloc sees at a small size."""

from __future__ import annotations

import time
import tracemalloc

import pytest
from helpers import PRESETS, assert_bad_input, run_cli

from core_tracer import budget
from core_tracer.cli.common import load_scene_file
from core_tracer.measures import report
from core_tracer.measures import states as S

STOP = PRESETS / "photometric-stop-lamp.json"
NIGHT = PRESETS / "four-lamp-night-lit-photometric.json"


@pytest.mark.slow
def test_measure_with_tiny_pixels_is_refused_before_rendering(tmp_path):
    start = time.monotonic()
    line = assert_bad_input(run_cli("measure", STOP, "-o", tmp_path / "m", "--pixel-mm", "0.05"), "--pixel-mm",
                            "GB of memory", "allowed at most 4.0 GB")
    assert time.monotonic() - start < 60 and "4658x5001" in line
    assert not (tmp_path / "m").exists()


@pytest.mark.slow
@pytest.mark.parametrize("scene, size, words", [(STOP, "8192", "2 states"), (NIGHT, "4096", "8 states")])
def test_states_past_the_budget_is_refused_before_rendering(tmp_path, scene, size, words):
    done = run_cli("states", scene, "-o", tmp_path / "s.npz", "--width", size, "--height", size, "--samples", "1")
    assert_bad_input(done, "image", words, "allowed at most 4.0 GB")
    assert "state 1 of" not in done.stdout and not (tmp_path / "s.npz").exists()


@pytest.mark.slow
def test_the_states_estimate_holds_what_it_allocates():
    scene = load_scene_file(NIGHT, 64, 48, 1)
    count = len(S.states_of(scene)) - 1
    tracemalloc.start()
    try:
        S.to_bytes(S.render_states(scene))
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    estimate = budget.states_bytes(64, 48, count, sources=1 + len(scene["lamps"])) - budget.BASE_BYTES
    arrays = (count + 1) * 64 * 48 * 12
    assert estimate >= 2 * arrays and peak <= estimate + budget.BASE_BYTES, (peak, estimate)


def test_the_largest_view_is_the_front_view_or_a_side_view():
    scene = load_scene_file(STOP)
    front = report.largest_view(scene, pixel_mm=100.0, front_pixel_mm=0.5)
    assert front == (462, 262)  # the front view at 0.5 mm, as measure renders it
    w, h = report.largest_view(scene, pixel_mm=0.25, front_pixel_mm=0.5)
    assert w * h > 462 * 262 * 3  # views at 0.25 mm from every direction of the beam sweep


@pytest.mark.slow
def test_the_measure_estimate_holds_what_it_allocates():
    scene = load_scene_file(STOP)
    w, h = report.largest_view(scene, pixel_mm=4.0, front_pixel_mm=1.0)
    tracemalloc.start()
    try:
        report.measure(scene, pixel_mm=4.0, replicates=1, front_pixel_mm=1.0)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak <= budget.measure_bytes(w * h) - budget.BASE_BYTES, (peak, w, h)

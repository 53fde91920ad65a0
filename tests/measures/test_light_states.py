"""Lighting states without re-rendering (``core_tracer.measures.states``; issue 23 item 5).

Radiance is linear in each source, so the surroundings plus each state's pass, weighted, equal a
render with those sources lit. Tolerances: the sum is the same rays' light added in another order, so
the difference is float32 rounding (≤ 1e-5 of the image's peak here; measured 9e-8 paper, 6e-12 of
the peak photometric)."""

from __future__ import annotations

import copy
import time
from pathlib import Path

import numpy as np
import pytest

import core_tracer
from core_tracer.measures import states as S
from core_tracer.raytrace.engine import render_passes

PRESETS = Path(__file__).resolve().parents[2] / "presets"
TOLERANCE = 1e-5  # of the peak


def _scene(name: str, w: int = 64, h: int = 48) -> dict:
    scene = core_tracer.load_scene(str(PRESETS / name))
    scene["image"]["width"], scene["image"]["height"] = w, h
    return scene


def _render(scene: dict) -> np.ndarray:
    scene = copy.deepcopy(scene)
    scene["glare"]["on"] = False
    return render_passes(scene, keep_passes=False, adaptive_threshold=S.ADAPTIVE_OFF).image


def _close(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.abs(a - b).max() / max(float(np.abs(b).max()), 1e-30))


@pytest.fixture(scope="module")
def night():
    return S.render_states(_scene("four-lamp-night-lit-photometric.json"))


@pytest.fixture(scope="module")
def baseline():
    return S.render_states(_scene("paper-baseline.json"))


@pytest.mark.slow
def test_the_states_of_a_two_filament_bulb_are_its_filaments(night):
    keys = [s.key for s in night.states]
    assert keys[0] == S.SURROUNDINGS
    lamp0 = [s for s in night.states if s.lamp == 0]
    assert {s.filament for s in lamp0} == {"stop", "tail"}
    assert {s.rendered for s in lamp0} == {440.0, 35.0}  # UN R37 P21/5W (photometry.sources)


@pytest.mark.parametrize("which", ["night", "baseline"])
def test_the_design_own_weights_give_its_render(which, night, baseline):
    light = night if which == "night" else baseline
    assert _close(S.relight(light, light.default_weights()), _render(light.scene)) < TOLERANCE


def test_switching_a_lamp_and_a_filament_equals_a_fresh_render(night):
    scene = copy.deepcopy(night.scene)
    on = {}
    for s in night.states:
        if s.lamp == 0:
            on[s.key] = s.filament == "tail"  # lamp 1 from stop to tail
        elif s.lamp == 1:
            on[s.key] = False  # lamp 2 off
    scene["lamps"][0]["bulb"]["state"] = "tail"
    scene["lamps"][1]["bulb"]["on"] = False
    relit = S.relight(night, S.weights_for(night, on=on))
    fresh = _render(scene)
    assert _close(relit, fresh) < TOLERANCE
    assert _close(relit, _render(night.scene)) > 1e-3  # the switch shows


def test_a_paper_bulb_twice_as_bright_equals_a_render_with_twice_the_intensity(baseline):
    scene = copy.deepcopy(baseline.scene)
    scene["lamps"][0]["bulb"]["intensity"] = [2 * v for v in scene["lamps"][0]["bulb"]["intensity"]]
    relit = S.relight(baseline, S.weights_for(baseline, level={"tail": 2.0}))
    assert _close(relit, _render(scene)) < TOLERANCE


@pytest.mark.slow
def test_a_custom_bulb_flux_in_lm_equals_a_render_with_that_flux():
    scene = _scene("photometric-stop-lamp.json")
    bulb = scene["lamps"][0]["bulb"]
    bulb["type"] = "custom"
    bulb["flux_lm"] = 300.0
    light = S.render_states(scene)
    relit = S.relight(light, S.weights_for(light, level={"stop": 450.0}))
    bulb["flux_lm"] = 450.0
    assert _close(relit, _render(scene)) < TOLERANCE


def test_both_filaments_lit_is_their_sum(night):
    stop, tail = night.passes["tail.stop_filament"], night.passes["tail"]  # lamp 1, a tail lamp
    weights = {**night.default_weights(), "tail.stop_filament": 1.0, "tail": 1.0}
    only_stop = {**weights, "tail": 0.0}
    assert np.allclose(S.relight(night, weights) - S.relight(night, only_stop), tail, atol=1e-6 * stop.max())
    # tail over stop filament, lit lens pixels: the ratio of their fluxes, 35/440
    lit = stop[..., 1] > 0.05 * stop[..., 1].max()
    assert np.median(tail[..., 1][lit] / stop[..., 1][lit]) == pytest.approx(35.0 / 440.0, rel=1e-4)


def test_unknown_states_and_levels_are_refused_in_one_line(night):
    with pytest.raises(core_tracer.SceneError) as e:
        S.weights_for(night, on={"lamps[9].stop": True})
    assert "not a state of this design; allowed surroundings, tail, tail.stop_filament, stop" in str(e.value)
    assert "\n" not in str(e.value)
    out_of_range = r"turn: -1.0 is out of range; allowed \[0, 100000\] lm"
    with pytest.raises(core_tracer.SceneError, match=out_of_range):
        S.weights_for(night, level={"turn": -1.0})


def test_states_are_named_by_the_lamps_function(night, baseline):
    """Issue 31: "Lamp 3 · P21/5W stop" was the turn lamp. The four-lamp preset's lamps are "custom":
    their functions come from the lens and filament (photometric, the measures' rule) or the lens
    colour and bulb (paper)."""
    named = {s.key: s.label for s in night.states}
    assert list(named) == ["surroundings", "tail", "tail.stop_filament", "stop", "stop.tail_filament", "turn",
                           "turn.tail_filament", "reversing", "reversing.tail_filament"]
    assert named["turn"] == "Turn (lamp 3, P21/5W)"
    assert named["tail.stop_filament"] == "Tail (lamp 1, P21/5W) · stop filament"
    turn = night.state("turn")
    assert (turn.lamp, turn.filament, turn.rendered, turn.lit_in_design) == (2, "stop", 440.0, True)
    paper = S.states_of(_scene("four-lamp-rear-combination.json"))
    assert [(s.key, s.label) for s in paper[1:]] == [
        ("tail", "Tail (lamp 1)"), ("stop", "Stop (lamp 2)"), ("turn", "Turn (lamp 3)"),
        ("reversing", "Reversing (lamp 4)")]
    two_stops = _scene("four-lamp-rear-combination.json")
    for lamp in two_stops["lamps"]:
        lamp["function"] = "stop"
    assert [s.key for s in S.states_of(two_stops)[1:]] == ["stop1", "stop2", "stop3", "stop4"]
    assert S.states_of(two_stops)[2].label == "Stop 2 (lamp 2)"
    assert [s.key for s in baseline.states] == ["surroundings", "tail"]


def test_the_keys_of_earlier_versions_still_work(night):
    """``lamps[2].stop`` (the turn lamp's stop filament) as before; a file written before, whose states
    carry those keys and no alias, still loads and relights by them."""
    assert S.weights_for(night, on={"lamps[2].stop": False}) == S.weights_for(night, on={"turn": False})
    assert S.weights_for(night, level={"lamps[0].stop": 500.0}) == S.weights_for(
        night, level={"tail.stop_filament": 500.0})
    import dataclasses

    old_states = [dataclasses.replace(s, key=s.alias or s.key, alias="") for s in night.states]
    old = S.LightStates(night.scene, old_states, night.surroundings,
                        {old_states[k].key: night.passes[s.key] for k, s in enumerate(night.states[1:], start=1)},
                        night.stats)
    again = S.from_bytes(_without_aliases(S.to_bytes(old)))
    assert [s.key for s in again.states][:3] == ["surroundings", "lamps[0].tail", "lamps[0].stop"]
    assert np.array_equal(S.relight(again, S.weights_for(again, on={"lamps[2].stop": False})),
                          S.relight(night, S.weights_for(night, on={"turn": False})))


def test_the_file_round_trip_and_a_foreign_file(night, tmp_path):
    again = S.from_bytes(S.to_bytes(night))
    assert [s.key for s in again.states] == [s.key for s in night.states]
    w = night.default_weights()
    assert np.array_equal(S.relight(again, w), S.relight(night, w))
    with pytest.raises(core_tracer.SceneError, match="is not a light-states file"):
        S.from_bytes(b"PK\x03\x04 not really", "states.npz")


def test_relighting_512_pixels_square_is_a_few_milliseconds():
    """Not a speed assertion (benchmarks/bench_light_states.py measures it): a 512² relight with nine
    passes is a weighted sum, done without allocating when given ``out``."""
    h = w = 512
    rng = np.random.default_rng(0)
    keys = [f"lamps[{i}].{f}" for i in range(4) for f in ("stop", "tail")]
    states = [S.State(S.SURROUNDINGS, "", None, "", 1.0, "", True)] + \
        [S.State(k, k, int(k[6]), k.split(".")[1], 440.0, "lm", True) for k in keys]
    light = S.LightStates({"glare": {"on": False}}, states, rng.random((h, w, 3), np.float32),
                          {k: rng.random((h, w, 3), np.float32) for k in keys}, {})
    out = np.empty((h, w, 3), np.float32)
    weights = {k: 0.5 for k in keys}
    start = time.perf_counter()
    S.relight(light, weights, out)
    assert time.perf_counter() - start < 5.0  # sanity only
    expected = light.surroundings + sum(0.5 * p for p in light.passes.values())
    assert np.allclose(out, expected, rtol=1e-5)


def _without_aliases(data: bytes) -> bytes:
    """A states file as written before states had aliases: its header's states without the field."""
    import io
    import json

    with np.load(io.BytesIO(data)) as npz:
        arrays = {name: npz[name] for name in npz.files}
    header = json.loads(arrays["header"].tobytes())
    for state in header["states"]:
        del state["alias"]
    arrays["header"] = np.frombuffer(json.dumps(header).encode(), np.uint8)
    out = io.BytesIO()
    np.savez_compressed(out, **arrays)
    return out.getvalue()

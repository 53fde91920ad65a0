"""The light of each source from one walk (``rays.BySource``, ``render_passes(by_source=True)``): the
surroundings' plane is a render with every bulb off, each lamp's plane a render with only that lamp lit
minus the surroundings (the same rays, their light added in another order: float rounding, within 1e-5
of the peak), and the planes sum to the render of the design with every bulb lit; in the paper mode with
the sun's phantom light (surroundings, though it is scattered by the reflector as the bulb's glow is), in
the photometric mode (X, Y, Z per source) with LED dies and a light guide."""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest

import core_tracer
from core_tracer.measures import states as S
from core_tracer.raytrace.engine import render_passes

PRESETS = Path(__file__).resolve().parents[2] / "presets"
TOLERANCE = 1e-5  # of the peak


def _scene(name: str, w: int, h: int, samples: int | None = None) -> dict:
    scene = core_tracer.load_scene(str(PRESETS / name))
    scene["image"]["width"], scene["image"]["height"] = w, h
    if samples is not None:
        scene["image"]["samples"] = samples
    scene["glare"]["on"] = False
    return scene


def _lit(scene: dict, lamps: set[int]) -> dict:
    out = copy.deepcopy(scene)
    for i, lamp in enumerate(out["lamps"]):
        lamp["bulb"]["on"] = i in lamps
    return out


def _image(scene: dict) -> np.ndarray:
    return render_passes(scene, keep_passes=False, adaptive_threshold=0).image


def _off_by(a: np.ndarray, b: np.ndarray, peak: float) -> float:
    return float(np.abs(a - b).max() / peak)


@pytest.mark.parametrize("name, size, samples", [
    ("four-lamp-day-lit.json", (48, 32), 2),  # paper, sun, phantom light
    ("led-rear-combination-photometric.json", (48, 32), 1),  # photometric, LED dies
    ("led-light-guide-tail-lamp.json", (40, 24), 2),  # photometric, a light guide's dies
])
def test_each_source_plane_is_a_render_of_that_source_alone(name, size, samples):
    scene = _scene(name, *size, samples)
    every = set(range(len(scene["lamps"])))
    walked = render_passes(_lit(scene, every), by_source=True, adaptive_threshold=0)
    assert list(walked.passes) == ["surroundings", *(f"lamp{i}" for i in sorted(every))]
    lit = _image(_lit(scene, every))
    peak = float(np.abs(lit).max())
    assert np.allclose(sum(walked.passes.values()), walked.image, rtol=1e-6, atol=1e-7 * peak)
    assert _off_by(walked.image, lit, peak) < TOLERANCE
    surroundings = _image(_lit(scene, set()))
    assert _off_by(walked.passes["surroundings"], surroundings, peak) < TOLERANCE
    for i in sorted(every):
        alone = _image(_lit(scene, {i})) - surroundings
        assert _off_by(walked.passes[f"lamp{i}"], alone, peak) < TOLERANCE, i
    assert max(float(walked.passes[f"lamp{i}"].max()) for i in every) > 1e-3 * peak  # the lamps' light shows


def test_adaptive_sampling_gives_every_source_the_same_samples():
    """With adaptive sampling the planes still sum to the walked image (one choice of pixels for every
    source), which is the design's adaptive render within adaptive sampling's own error (its pixels
    chosen by the sources' spread instead of the passes': about as many)."""
    scene = _lit(_scene("four-lamp-night-lit-photometric.json", 64, 48, 8), {0, 1, 2, 3})
    walked = render_passes(scene, by_source=True)
    plain = render_passes(scene)
    assert np.allclose(sum(walked.passes.values()), walked.image, rtol=1e-6, atol=1e-9)
    assert walked.stats["busy_pixels"] >= plain.stats["busy_pixels"] * 0.9
    assert _off_by(walked.image, plain.image, float(plain.image.max())) < 1e-2


def test_states_come_from_one_walk(monkeypatch):
    """``render_states`` of a parametric design walks once, whatever its number of states."""
    import core_tracer.raytrace.engine as engine

    calls = []
    real = engine.render_passes

    def counting(*args, **kwargs):
        calls.append(kwargs.get("by_source"))
        return real(*args, **kwargs)

    monkeypatch.setattr(engine, "render_passes", counting)
    light = S.render_states(_scene("four-lamp-night-lit-photometric.json", 32, 24))
    assert calls == [True] and len(light.states) == 9

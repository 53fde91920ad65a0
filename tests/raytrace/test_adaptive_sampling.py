"""Adaptive sampling (engine.adaptive._trace_adaptive): samples spent where the image changes, the result
within a stated tolerance of tracing every sample, the same on every run and with any threads."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import PRESETS

from core_tracer import load_scene
from core_tracer.raytrace import engine
from core_tracer.raytrace.engine import edges, render_passes
from core_tracer.raytrace.engine.sampling import pilot_samples

# Measured at 96 x 64 and 16 samples: at most 8e-5 of the peak, 7e-5 of the mean (docs/model.md).
MAX_OF_PEAK = 5e-4
MEAN_OF_MEAN = 3e-4


def _render(case: str, threshold: float | None, size=(96, 64), **kw):
    return render_passes(load_scene(PRESETS / f"{case}.json"), *size, samples=16, keep_passes=False,
                         adaptive_threshold=threshold, **kw)


@pytest.mark.slow
@pytest.mark.parametrize("case", ["four-lamp-rear-combination", "paper-baseline"])
def test_adaptive_agrees_with_every_sample_and_traces_less(case):
    full, adaptive = _render(case, 0.0), _render(case, None)
    error = np.abs(adaptive.image.astype(np.float64) - full.image)
    assert error.max() <= MAX_OF_PEAK * full.image.max()
    assert error.mean() <= MEAN_OF_MEAN * full.image.mean()
    pixels = 96 * 64
    assert full.stats["busy_pixels"] == 0 and 0 < adaptive.stats["busy_pixels"] < pixels
    assert adaptive.stats["segments"] < 0.95 * full.stats["segments"]


@pytest.mark.slow
def test_adaptive_traces_less_than_every_sample(monkeypatch):
    """The saving of adaptive sampling itself, without the edge samples both take (``engine.edges``,
    which on this preset add about as many segments as adaptive sampling saves)."""
    monkeypatch.setattr(edges, "EDGE_SAMPLES", 0)
    full, adaptive = _render("four-lamp-rear-combination", 0.0), _render("four-lamp-rear-combination", None)
    assert adaptive.stats["segments"] < 0.9 * full.stats["segments"]


@pytest.mark.slow
def test_a_lax_threshold_is_visibly_wrong():
    """The tolerance above tells adaptive sampling from a careless one: at a threshold of one
    whole brightness, pixels across lens rims keep their few pilot samples."""
    full, lax = _render("four-lamp-rear-combination", 0.0), _render("four-lamp-rear-combination", 1.0)
    assert np.abs(lax.image.astype(np.float64) - full.image).max() > 10 * MAX_OF_PEAK * full.image.max()


@pytest.mark.slow
def test_pixels_taking_every_sample_are_the_full_render():
    """With the smallest threshold every pixel whose pilot samples differ at all takes every
    sample, summed as without adaptive sampling; the others are flat, their mean of 4 equal
    values rounding as the mean of 16 does at most."""
    full, strict = _render("four-lamp-rear-combination", 0.0), _render("four-lamp-rear-combination", 1e-300)
    np.testing.assert_allclose(strict.image, full.image, rtol=1e-6, atol=0)


@pytest.mark.slow
def test_adaptive_is_the_same_whatever_the_threads_and_bands(monkeypatch):
    one = _render("four-lamp-rear-combination", None, size=(40, 30), threads=1).image
    monkeypatch.setattr(engine.sampling, "TILE_RAYS", 300)  # bands of 1-2 rows, pilot groups split mid-row
    many = _render("four-lamp-rear-combination", None, size=(40, 30), threads=2).image
    np.testing.assert_array_equal(one, many)


def test_one_sample_is_never_adaptive():
    scene = load_scene(PRESETS / "four-lamp-rear-combination.json")
    a = render_passes(scene, 40, 30, keep_passes=False, adaptive_threshold=0.5).image
    b = render_passes(scene, 40, 30, keep_passes=False, adaptive_threshold=0.0).image
    np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("samples", [5, 16, 64])
def test_pilot_samples_spread_over_the_pixel(samples):
    pilot = pilot_samples(samples)
    assert len(pilot) == 4 and pilot[0] == 0 and pilot[-1] == samples - 1
    assert len(set(pilot.tolist())) == 4


@pytest.mark.slow
def test_the_rows_outside_a_band_are_traced_only_where_they_decide(monkeypatch):
    """A band traces the pilot samples of its neighbours in the rows just outside it only next to
    its edge rows' calm pixels (``adaptive._outside_rows``): the day preset (sky, body, lenses and
    ground at the bands' edges) in bands of 3 rows is the image of one band, pass for pass, with the
    same busy pixels, while tracing fewer of the outside rows than all of them."""
    scene = load_scene(PRESETS / "four-lamp-day-lit.json")
    one = render_passes(scene, 64, 48, samples=16, threads=1)
    pilot_pixels = []
    per_sample = engine.sampling.per_sample

    def counting(ctx, band, pixels, sample_ids):
        if len(sample_ids) == len(pilot_samples(16)):
            pilot_pixels.append(len(pixels))
        return (yield from per_sample(ctx, band, pixels, sample_ids))

    monkeypatch.setattr(engine.sampling, "per_sample", counting)
    monkeypatch.setattr(engine.sampling, "TILE_RAYS", 5 * 64 * 4)  # bands of 3 rows
    many = render_passes(scene, 64, 48, samples=16, threads=2)
    assert many.stats["busy_pixels"] == one.stats["busy_pixels"]
    for name in engine.PASS_NAMES:  # (surroundings: float64 sums may differ in their last bit)
        np.testing.assert_array_max_ulp(many.passes[name], one.passes[name], maxulp=1)
    outside = sum(pilot_pixels) - 64 * 48
    assert 0 < outside < 2 * (48 // 3 - 1) * 64

"""Edge samples (engine.edges): more samples where a pixel's samples of the bulb pass disagree. Off by
default (RESULTS.md: no better than as many samples everywhere on the four-lamp night preset); these
tests turn them on and check what they do against an independent estimate, the render at many samples."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import PRESETS

from core_tracer import load_scene
from core_tracer.raytrace.engine import edges, render_passes

SIZE = (96, 60)


def _y(scene: dict, samples: int, threshold: float | None = None) -> np.ndarray:
    image = render_passes(scene, *SIZE, samples=samples, keep_passes=False, threads=1,
                          adaptive_threshold=threshold).image
    return image[..., 1].astype(np.float64)


@pytest.fixture(scope="module")
def night():
    scene = load_scene(PRESETS / "four-lamp-night-lit-photometric.json")
    reference = _y(scene, 48, threshold=0.0)  # no edge samples: EDGE_SAMPLES is 0 by default
    return scene, reference, reference >= 0.1 * np.percentile(reference, 99)


def test_off_by_default():
    assert edges.EDGE_SAMPLES == 0


@pytest.mark.parametrize("threshold", [None, 0.0])
def test_edge_samples_lower_the_lit_lens_error_and_keep_its_mean(night, monkeypatch, threshold):
    scene, reference, lit = night
    plain = _y(scene, 4, threshold)
    monkeypatch.setattr(edges, "EDGE_SAMPLES", 4)
    edged = _y(scene, 4, threshold)

    def error(y):
        return np.sqrt(np.mean((y[lit] - reference[lit]) ** 2)) / reference[lit].mean()

    assert error(edged) < 0.75 * error(plain)
    # The mean over the lit lens: within the plain render's distance of it (no bias beyond the noise).
    assert abs(edged[lit].mean() - reference[lit].mean()) <= max(abs(plain[lit].mean() - reference[lit].mean()),
                                                                 0.01 * reference[lit].mean())
    # Only pixels holding an emitter's edge change: the rest are the plain render's, bit for bit.
    changed = edged != plain
    assert 0 < changed.sum() < 0.5 * changed.size

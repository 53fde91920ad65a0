"""Edge samples (engine.edges): more samples, along the main branches, where a pixel's samples of the
emitter pass disagree. Checked against an independent estimate, the render at many samples without
them: the lit lens's error falls, its mean stays, and only pixels holding an edge change."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import PRESETS

from core_tracer import load_scene
from core_tracer.raytrace import pixel_filter
from core_tracer.raytrace.camera import eye_rays, make_camera
from core_tracer.raytrace.engine import edges, render_passes
from core_tracer.raytrace.engine.context import Context
from core_tracer.raytrace.engine.rays import BULB_PASS, Band
from core_tracer.raytrace.engine.walk import trace_rays

SIZE = (96, 60)


def _y(scene: dict, samples: int, threshold: float | None = None) -> np.ndarray:
    image = render_passes(scene, *SIZE, samples=samples, keep_passes=False, threads=1,
                          adaptive_threshold=threshold).image
    return image[..., 1].astype(np.float64)


def _edged(scene: dict, k: int) -> dict:
    """The scene with ``image.edge_samples`` K."""
    return {**scene, "image": {**scene["image"], "edge_samples": k}}


@pytest.fixture(scope="module")
def night():
    scene = load_scene(PRESETS / "four-lamp-night-lit-photometric.json")
    assert scene["image"]["edge_samples"] == 0  # off unless asked for
    reference = _y(scene, 48, threshold=0.0)
    return scene, reference, reference >= 0.1 * np.percentile(reference, 99)


def _error(y: np.ndarray, reference: np.ndarray, lit: np.ndarray) -> float:
    return float(np.sqrt(np.mean((y[lit] - reference[lit]) ** 2)) / reference[lit].mean())


@pytest.mark.parametrize("threshold", [None, 0.0])
@pytest.mark.parametrize("main_share", [edges.MAIN_SHARE, 0.0])
def test_edge_samples_lower_the_lit_lens_error_and_keep_its_mean(night, monkeypatch, threshold, main_share):
    scene, reference, lit = night
    plain = _y(scene, 4, threshold)
    monkeypatch.setattr(edges, "MAIN_SHARE", main_share)
    edged = _y(_edged(scene, 4), 4, threshold)
    assert _error(edged, reference, lit) < 0.75 * _error(plain, reference, lit)
    # The mean over the lit lens: no further from the reference's than the plain render's (or 1 %).
    assert abs(edged[lit].mean() - reference[lit].mean()) <= max(abs(plain[lit].mean() - reference[lit].mean()),
                                                                 0.01 * reference[lit].mean())
    # Only pixels holding an emitter's edge change: the rest are the plain render's, bit for bit.
    changed = edged != plain
    assert 0 < changed.sum() < 0.5 * changed.size


@pytest.mark.parametrize("share, relation", [(0.0, "all"), (edges.MAIN_SHARE, "most")])
def test_main_branches_are_the_trees_without_their_faint_branches(night, monkeypatch, share, relation):
    """``main_branches`` with MAIN_SHARE 0 is the whole tree, value for value; at MAIN_SHARE it keeps
    most of the emitter light and traces fewer segments."""
    scene = night[0]
    cam = make_camera(scene["camera"], *SIZE)
    ctx = Context(scene, cam, False, 4, "blackman-harris")
    pixels = np.arange(SIZE[0] * SIZE[1])
    o, d = eye_rays(cam, np.tile(pixels, 2), pixel_filter.grid_offsets("blackman-harris", pixels, np.arange(2), 4,
                                                                        sample_major=True))
    whole, main = Band(len(o), ctx), Band(len(o), ctx)
    trace_rays(ctx, whole, o, d)
    monkeypatch.setattr(edges, "MAIN_SHARE", share)
    edges.main_branches(ctx, main, o, d)
    if relation == "all":
        # the same values up to rounding: the walk's Fresnel split takes another order of products when
        # most of a generation is totally reflected (the guide's shortcut), and the generations differ
        np.testing.assert_allclose(main.acc, whole.acc, rtol=1e-12, atol=1e-12 * whole.acc.max())
        assert main.segments == whole.segments
    else:
        light, kept = whole.acc[BULB_PASS].sum(), main.acc[BULB_PASS].sum()
        assert 0.8 * light < kept <= light * (1 + 1e-12)
        assert main.segments < 0.7 * whole.segments

"""The pixels that can see the body (``body_box.screen_window``): every eye ray that meets the box
passes through one of them, so the tracer may leave the others out where they add nothing."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import FOUR_LAMPS, scene_with

from core_tracer import load_scene, render_passes
from core_tracer.raytrace import engine
from core_tracer.raytrace.camera import eye_rays, make_camera
from core_tracer.raytrace.parts import body_box


def _cameras(rng: np.random.Generator, n: int) -> list[dict]:
    """Cameras around a box near the origin: perspective and orthographic, wide and narrow, shifted."""
    cams = []
    for k in range(n):
        direction = rng.normal(size=3)
        direction[1] = -abs(direction[1]) - 0.2  # in front of the body (its front face is y = 0)
        direction /= np.linalg.norm(direction)
        target = rng.uniform(-60, 60, 3)
        cams.append({"type": "orthographic" if k % 3 == 0 else "perspective",
                     "position": (target + rng.uniform(150, 900) * direction).tolist(), "target": target.tolist(),
                     "up": [0.0, 0.0, 1.0], "fov_deg": float(rng.uniform(10, 70)),
                     "width": float(rng.uniform(100, 600)), "sensor_fit": "auto",
                     "shift": rng.uniform(-0.3, 0.3, 2).tolist()})
    return cams


@pytest.mark.parametrize("seed", range(4))
def test_every_ray_that_meets_the_box_is_inside_the_window(seed, rng):
    lo, hi = np.array([-80.0, 0.0, -40.0]), np.array([120.0, 90.0, 45.0])
    width, height = 96, 64
    checked = 0
    for cam_doc in _cameras(rng, 12):
        cam = make_camera(cam_doc, width, height)
        window = body_box.screen_window(cam, lo, hi)
        pixels = np.arange(width * height)
        t_near, t_far, _ = body_box.hit_box(*eye_rays(cam, pixels), lo, hi)
        hits = pixels[(t_near <= t_far) & (t_near > 0)]
        if window is None:
            continue
        first_col, last_col, first_row, last_row = window
        row, col = np.divmod(hits, width)
        assert ((col >= first_col) & (col <= last_col) & (row >= first_row) & (row <= last_row)).all()
        checked += len(hits)
        # and the window is the box's picture, not the whole image, when the box is small in it
        if len(hits) and len(hits) < 0.2 * len(pixels):
            assert (last_col - first_col + 1) * (last_row - first_row + 1) < len(pixels)
    assert checked > 1000


def test_a_box_reaching_behind_the_camera_gives_no_window():
    cam = make_camera({"type": "perspective", "position": [0.0, 20.0, 0.0], "target": [0.0, 100.0, 0.0],
                       "up": [0.0, 0.0, 1.0], "fov_deg": 40.0, "width": 100.0, "sensor_fit": "auto",
                       "shift": [0.0, 0.0]}, 32, 32)
    assert body_box.screen_window(cam, np.array([-50.0, 0.0, -50.0]), np.array([50.0, 90.0, 50.0])) is None


@pytest.mark.slow
@pytest.mark.parametrize("view", ["preset", "oblique", "off to the side"])
def test_leaving_out_the_pixels_outside_the_window_changes_no_bit(monkeypatch, view):
    scene = load_scene(FOUR_LAMPS) if view != "off to the side" else scene_with()
    if view == "oblique":
        scene["camera"] = {**scene["camera"], "position": [-380.0, -620.0, 220.0], "target": [0.0, 40.0, 0.0]}
    if view == "off to the side":  # most of the body out of the picture
        scene["camera"] = {**scene["camera"], "target": [scene["camera"]["target"][0] + 160.0,
                                                         *scene["camera"]["target"][1:]]}
    window = body_box.screen_window(make_camera(scene["camera"], 96, 72), *body_box.body_box(scene["body"]))
    if view != "oblique":  # (the oblique view sees the body in every pixel)
        first_col, last_col, first_row, last_row = window
        assert (last_col - first_col + 1) * (last_row - first_row + 1) < 0.7 * 96 * 72
    seen = render_passes(scene, 96, 72, threads=1)
    with monkeypatch.context() as patch:
        patch.setattr(body_box, "screen_window", lambda *args, **kwargs: None)
        every = render_passes(scene, 96, 72, threads=1)
    assert seen.stats["segments"] == every.stats["segments"]
    np.testing.assert_array_equal(seen.image, every.image)
    for name in engine.PASS_NAMES:
        np.testing.assert_array_equal(seen.passes[name], every.passes[name])

"""The camera mathematics of the add-on, without Blender: lens and size conversions, the camera axes,
the projection (checked against the tracer's eye rays) and the framing of the lamp body."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import FOUR_LAMPS

from core_tracer.raytrace.camera import eye_rays, make_camera
from core_tracer.scene.validate import load_scene
from lamp_addon.convert import camera as cm


def test_camera_formulas():
    assert cm.render_size(1920, 1080, 50) == (960, 540)
    assert cm.render_size(101, 33, 33) == (33, 10)  # Blender divides integers
    assert cm.fitted_side("auto", 48, 32) == "horizontal"
    assert cm.fitted_side("auto", 32, 48) == "vertical"
    assert cm.fitted_side("auto", 40, 40) == "horizontal"  # a tie fits horizontally, as Blender
    assert cm.fitted_side("vertical", 48, 32) == "vertical"
    assert cm.sensor_size("auto", 36.0, 24.0) == 36.0  # AUTO uses the sensor width for either side
    assert cm.sensor_size("vertical", 36.0, 24.0) == 24.0
    assert cm.fov_from_lens(50.0, 36.0) == pytest.approx(39.5977, abs=1e-4)  # Blender's default camera
    for fov in (0.5, 16.0, 90.0, 169.0):
        assert cm.fov_from_lens(cm.lens_from_fov(fov, 36.0), 36.0) == pytest.approx(fov, abs=1e-9)


def test_view_from_axes_keeps_world_up_when_level():
    right, up, back = cm.look_at_axes((0, -800, 100), (0, 0, 0), (0, 0, 1))
    view = cm.view_from_axes((0, -800, 100), up, back, math.dist((0, -800, 100), (0, 0, 0)))
    assert view["up"] == [0.0, 0.0, 1.0]
    assert view["target"] == pytest.approx([0, 0, 0], abs=1e-9)
    right, up, back = cm.look_at_axes((0, -800, 0), (0, 0, 0), (0.3, 0, 1))  # rolled
    view = cm.view_from_axes((0, -800, 0), up, back, 800.0)
    assert view["up"] == pytest.approx(list(up), abs=1e-12)


CAMERAS = [
    {"type": "perspective", "fov_deg": 16.0, "sensor_fit": "auto", "shift": [0.0, 0.0]},
    {"type": "perspective", "fov_deg": 40.0, "sensor_fit": "vertical", "shift": [0.1, -0.05]},
    {"type": "perspective", "fov_deg": 5.0, "sensor_fit": "horizontal", "shift": [0.0, 0.2]},
    {"type": "orthographic", "width": 10.0, "sensor_fit": "auto", "shift": [0.0, 0.0]},
    {"type": "orthographic", "width": 900.0, "sensor_fit": "vertical", "shift": [-0.1, 0.1]},
]
SIZES = [(64, 48), (40, 90), (50, 50)]


def _camera(base: dict, position, target, up=(0, 0, 1)) -> dict:
    return {"width": 250.0, "fov_deg": 16.0, **base, "position": list(position), "target": list(target),
            "up": list(up)}


@pytest.mark.seed(3)
def test_project_agrees_with_the_tracers_eye_rays(rng):
    """A point on the eye ray through a pixel centre projects onto that centre."""
    for base in CAMERAS:
        for size in SIZES:
            cam = _camera(base, (30, -700, 120), (10, 20, -5), (0.1, 0, 1))
            tracer = make_camera(cam, *size)
            pixels = rng.integers(0, size[0] * size[1], 20)
            origins, directions = eye_rays(tracer, pixels)
            points = origins + rng.uniform(200, 1500, (20, 1)) * directions
            got = np.array(cm.project(cam, size, points.tolist()))
            row, col = np.divmod(pixels, size[0])
            np.testing.assert_allclose(got[:, 0], col + 0.5, atol=1e-7)
            np.testing.assert_allclose(got[:, 1], row + 0.5, atol=1e-7)


def _directions(rng: np.random.Generator):
    yield (0, 1, 0), (0, 0, 1)  # straight at the front face
    for _ in range(12):
        d = rng.normal(size=3)
        d[1] = abs(d[1]) + 0.3  # from the front half-space
        yield tuple(d / np.linalg.norm(d)), tuple(rng.normal(size=3))


@pytest.mark.parametrize("base", CAMERAS, ids=lambda c: f"{c['type']}-{c['sensor_fit']}")
@pytest.mark.parametrize("size", SIZES, ids=str)
@pytest.mark.seed(7)
def test_frame_view_fits_the_box_with_the_margin(base, size, rng):
    """Every corner of the body box projects inside the image, the outermost one exactly at the margin;
    the direction and the image up are kept and the camera aims at the box centre."""
    box = ((-70.0, 0.0, -40.0), (205.0, 80.0, 25.0))
    centre = np.mean(box, axis=0)
    for forward, up in _directions(rng):
        start = np.array([50.0, -40.0, 10.0]) - 900.0 * np.array(forward)
        cam = _camera(base, start, start + 900.0 * np.array(forward), up)
        framed = cm.frame_view(cam, box, size)
        new_forward = np.subtract(framed["target"], framed["position"])
        np.testing.assert_allclose(new_forward / np.linalg.norm(new_forward), forward, atol=1e-9)
        np.testing.assert_allclose(framed["target"], centre, atol=1e-9)
        assert framed["up"] == cam["up"]
        points = np.array(cm.project(framed, size, cm.box_corners(*box)))
        assert (points[:, 2] > 0).all()  # in front of the camera
        # Distances from the image centre (shifted window: from the window's own centre line) in
        # units of the half image; the margin leaves 1/(1 + m) of it.
        cx, cy = size[0] / 2, size[1] / 2
        if _shift_keeps_axis(framed, size):
            (left, right), (bottom, top) = cm.window(framed, size)
            cx = -left / (right - left) * size[0]
            cy = top / (top - bottom) * size[1]
        assert (points[:, 0] >= -1e-6).all() and (points[:, 0] <= size[0] + 1e-6).all()
        assert (points[:, 1] >= -1e-6).all() and (points[:, 1] <= size[1] + 1e-6).all()
        # The tightest corner touches the shrunken window: the frame is as tight as the margin allows.
        reach = max(np.max(np.maximum((points[:, 0] - cx) / (size[0] - cx), (cx - points[:, 0]) / cx)),
                    np.max(np.maximum((points[:, 1] - cy) / (size[1] - cy), (cy - points[:, 1]) / cy)))
        assert reach == pytest.approx(1.0 / (1.0 + cm.FRAME_MARGIN), abs=1e-9) or (
            framed["type"] == "perspective" and _depth_limited(framed, box))


def _shift_keeps_axis(cam, size) -> bool:
    (left, right), (bottom, top) = cm.window(cam, size)
    return left < 0 < right and bottom < 0 < top


def _depth_limited(cam, box) -> bool:
    """The distance was set by keeping every corner in front of the camera (a very wide lens)."""
    forward = np.subtract(cam["target"], cam["position"])
    distance = np.linalg.norm(forward)
    reach = max(abs(np.dot(np.subtract(c, cam["target"]), forward / distance)) for c in cm.box_corners(*box))
    return distance == pytest.approx(reach * 1.001)


def test_frame_view_of_four_lamps_holds_every_lens():
    """The four-lamp preset's body, framed from its own camera: every lens rim projects inside the image."""
    scene = load_scene(str(FOUR_LAMPS))
    size = (64, 40)
    framed = cm.frame_view(scene["camera"], cm.body_box(scene), size)
    for lamp in scene["lamps"]:
        (x, z), r = lamp["center"], lamp["lens"]["radius"]
        rim = [(x + r * math.cos(a), 0.0, z + r * math.sin(a)) for a in np.linspace(0, 2 * math.pi, 64)]
        points = np.array(cm.project(framed, size, rim))
        assert (points[:, 0] > 0).all() and (points[:, 0] < size[0]).all()
        assert (points[:, 1] > 0).all() and (points[:, 1] < size[1]).all()


def test_looking_along_a_view_direction_then_framing():
    """Frame Lamp from a 3D View: the camera takes the view's direction and up, then frames the body."""
    cam = _camera(CAMERAS[0], (0, -800, 0), (0, 0, 0))
    forward, up = (0.5, 0.7, -0.3), (0.2, 0.1, 1.0)
    turned = cm.looking_along(cam, forward, up)
    assert math.dist(turned["position"], turned["target"]) == pytest.approx(800.0)
    right, true_up, back = cm.look_at_axes(turned["position"], turned["target"], turned["up"])
    np.testing.assert_allclose(-np.array(back), np.array(forward) / np.linalg.norm(forward), atol=1e-12)
    assert np.dot(true_up, up) > 0 and abs(np.dot(right, up)) < 1e-12
    box = ((-110.0, 0.0, -60.0), (110.0, 80.0, 60.0))
    framed = cm.frame_view(turned, box, (64, 48))
    points = np.array(cm.project(framed, (64, 48), cm.box_corners(*box)))
    assert (points[:, 0] > 0).all() and (points[:, 0] < 64).all() and (points[:, 1] > 0).all()

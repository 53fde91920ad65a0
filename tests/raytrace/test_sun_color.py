"""The sun's colour following the environment (``light.follow_environment_color``, sunlight.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import scene_with, write_exr

from core_tracer import render
from core_tracer.raytrace import environment, sunlight

W, H = 64, 32
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])  # Rec. 709


def _solid_angle(row: int) -> float:
    """The exact solid angle of a pixel of ``row`` (from the top) of a W x H equirectangular image."""
    top = math.pi / 2 - row * math.pi / H
    return (math.sin(top) - math.sin(top - math.pi / H)) * 2 * math.pi / W


def _sky_with_a_coloured_sun() -> tuple[np.ndarray, dict[tuple[int, int], tuple[float, float, float]]]:
    sky = np.full((H, W, 3), 0.5, np.float32)
    sun = {(5, 40): (1000.0, 600.0, 200.0), (6, 40): (900.0, 500.0, 300.0), (6, 41): (950.0, 700.0, 100.0)}
    for (row, col), rgb in sun.items():
        sky[row, col] = rgb
    sky[7, 40] = (400.0, 300.0, 100.0)  # luminance 306.8, under half the brightest (709.8): not the sun
    return sky, sun


def _scene(path: str, follow: bool = True, strength: float = 3.0, rotation_deg: float = 30.0, **edits) -> dict:
    return scene_with(**{
        "environment": {"world": "file", "file": path, "strength": strength, "rotation_deg": rotation_deg},
        "light": {"direction": [0.0, -1.0, 0.0], "color": [1, 1, 1], "ambient": 0.2, "strength": 2.0,
                  "sun_color": [0.1, 0.9, 0.1], "follow_environment_color": follow},
        "image": {"width": 24, "height": 16},
        **edits})


def test_followed_colour_is_the_light_of_the_sun_pixels_at_luminance_1(tmp_path):
    sky, sun = _sky_with_a_coloured_sun()
    path = write_exr(tmp_path / "sun.exr", sky)
    # Closed form: sum of radiance x solid angle over the sun's pixels, divided by its luminance.
    light = sum(np.array(rgb) * _solid_angle(row) for (row, _), rgb in sun.items())
    expected = light / (light @ LUMINANCE)
    for strength, turn in ((1.0, 0.0), (3.0, 30.0), (0.25, -120.0)):  # neither changes the colour
        scene = _scene(path, strength=strength, rotation_deg=turn)
        np.testing.assert_allclose(sunlight.sun_color(scene), expected, rtol=1e-6)
        assert sunlight.from_scene(scene, None).color @ LUMINANCE == pytest.approx(1.0)
    assert expected[0] > expected[1] > expected[2]  # a warm sun stays warm
    # The same pixels as the sun's direction: moving the brightest pixel moves both.
    env = environment.from_scene(_scene(path))
    assert sunlight.followed_color(env) == pytest.approx(expected)


@pytest.mark.slow
def test_following_the_colour_renders_as_writing_that_colour_in(tmp_path):
    sky, _ = _sky_with_a_coloured_sun()
    path = write_exr(tmp_path / "sun.exr", sky)
    followed = _scene(path)
    colour = sunlight.sun_color(followed).tolist()
    written = _scene(path, follow=False, **{"light.sun_color": colour})
    assert np.array_equal(render(followed), render(written))
    assert not np.array_equal(render(followed), render(_scene(path, follow=False)))  # the spec's sun_color


def test_out_of_gamut_values_count_as_zero_and_a_dark_image_gives_white(tmp_path):
    sky = np.full((H, W, 3), 0.5, np.float32)
    sky[10, 20] = (50.0, 20.0, -3.0)  # some HDR images hold slightly negative values near the sun
    colour = sunlight.sun_color(_scene(write_exr(tmp_path / "neg.exr", sky)))
    assert colour[2] == 0.0 and colour @ LUMINANCE == pytest.approx(1.0)
    black = sunlight.sun_color(_scene(write_exr(tmp_path / "black.exr", np.zeros((H, W, 3), np.float32))))
    assert colour.min() >= 0.0 and np.array_equal(black, np.ones(3))


def test_without_surroundings_or_switched_off_the_spec_colour_holds():
    assert scene_with()["light"]["follow_environment_color"] is False  # what earlier documents mean
    paper = scene_with(**{"image": {"width": 32, "height": 24}})
    switched = scene_with(**{"image": {"width": 32, "height": 24}, "light.follow_environment_color": True})
    assert np.array_equal(sunlight.sun_color(switched), switched["light"]["sun_color"])
    assert np.array_equal(render(paper), render(switched))  # the paper's setting, bit for bit


def test_blenders_sunset_gives_a_warm_sun(world_images):
    scene = scene_with(**{"environment": {"world": "sunset"}, "light.follow_environment_color": True})
    r, g, b = sunlight.sun_color(scene)
    assert r > g > b >= 0.0

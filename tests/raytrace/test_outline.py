"""The lens outline (``core_tracer.scene.outline``): a rectangular lens with rounded corners,
its wall found in closed form against a brute-force test of its eight pieces, its area, and
the whole tracer with a rectangular lens against the one-ray-at-a-time reference tracer."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import scene_with
from reference_tracer import Lamp, compare

from core_tracer import render, render_passes
from core_tracer.raytrace.lamp_table import LampTable
from core_tracer.raytrace.parts import outer_face, side_wall
from core_tracer.scene import outline
from core_tracer.scene.derived import lamp_geometry
from core_tracer.scene.outline import Outline

SQUARE = {"lamps[0].lens.outline": "rectangular", "lamps[0].lens.width": 90.0, "lamps[0].lens.height": 60.0,
          "lamps[0].lens.corner_radius": 10.0}


def square_scene(**edits) -> dict:
    """The paper baseline with a 90 x 60 mm rectangular lens, corners of radius 10 mm."""
    return scene_with(**{**SQUARE, **edits})


def _rays_inside(shape: Outline, n: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """n rays from random points inside the outline's prism in random directions."""
    pts = np.column_stack([rng.uniform(-shape.half_w, shape.half_w, 4 * n), rng.uniform(0, 20, 4 * n),
                           rng.uniform(-shape.half_h, shape.half_h, 4 * n)])
    pts = pts[shape.signed_distance(pts[:, 0], pts[:, 2]) < -1e-6][:n]
    d = rng.normal(size=(len(pts), 3))
    return pts, d / np.linalg.norm(d, axis=1, keepdims=True)


def _walls(shape: Outline, n: int) -> tuple[np.ndarray, np.ndarray]:
    return np.full((n, 2), [shape.half_w, shape.half_h]), np.full(n, shape.corner)


@pytest.mark.slow
@pytest.mark.parametrize("shape", [Outline(45, 30, 10), Outline(45, 30, 0), Outline(30, 30, 30),
                                   Outline(60, 12, 11.5)], ids=["rounded", "sharp", "all-corner", "slot"])
@pytest.mark.seed(12)
def test_wall_exit_agrees_with_every_piece_tested_on_random_rays(shape, rng):
    o, d = _rays_inside(shape, 5000, rng)
    assert len(o) > 3000
    half, corner = _walls(shape, len(o))
    fast = side_wall.hit_outline_wall(o, d, half, corner)
    lamp_doc = square_scene()["lamps"][0]  # the reference's wall reads only the outline's fields
    lamp_doc["lens"].update(width=2 * shape.half_w, height=2 * shape.half_h, corner_radius=shape.corner)
    lamp = Lamp(lamp_doc)
    brute = np.array([(lamp.wall(oi, di) or (math.inf, None))[0] for oi, di in zip(o, d, strict=True)])
    vertical = d[:, 0] ** 2 + d[:, 2] ** 2 == 0
    assert np.all(np.isinf(fast[vertical]))
    np.testing.assert_allclose(fast[~vertical], brute[~vertical], rtol=1e-9, atol=1e-9)
    hit = o + fast[:, None] * d
    np.testing.assert_allclose(shape.signed_distance(hit[:, 0], hit[:, 2]), 0.0, atol=1e-9)


@pytest.mark.seed(3)
def test_from_a_wall_hit_there_is_no_closer_hit(rng):
    # Onward from the hit the ray is outside: no hit beyond T_MIN. Back along the ray the wall is
    # next met at the ray's other crossing, never before the origin the ray came from (inside).
    shape = Outline(45, 30, 10)
    o, d = _rays_inside(shape, 4000, rng)
    half, corner = _walls(shape, len(o))
    t = side_wall.hit_outline_wall(o, d, half, corner)
    p = o + t[:, None] * d
    assert np.all(np.isinf(side_wall.hit_outline_wall(p, d, half, corner)))
    back = side_wall.hit_outline_wall(p, -d, half, corner)
    assert np.all(back >= t * (1 - 1e-12))


@pytest.mark.slow
def test_rectangle_area_is_w_h_less_the_corners():
    assert Outline(45, 30, 0).area == 90 * 60
    assert Outline(45, 30, 10).area == pytest.approx(90 * 60 - (4 - math.pi) * 100, rel=1e-15)
    # and the inside test counts the same area (a 0.05 mm grid: error of order the perimeter x cell)
    shape = Outline(45, 30, 10)
    step = 0.05
    x, z = np.meshgrid(np.arange(-45, 45, step) + step / 2, np.arange(-30, 30, step) + step / 2)
    assert shape.inside(x, z).sum() * step * step == pytest.approx(shape.area, rel=2e-4)


def test_perimeter_lies_on_the_outline_within_the_chord_tolerance():
    shape = Outline(45, 30, 10)
    ring = shape.perimeter(0.05, max_edge=3.0)
    assert np.abs(shape.signed_distance(ring[:, 0], ring[:, 1])).max() < 1e-12
    mid = (ring + np.roll(ring, -1, axis=0)) / 2  # the chords' midpoints sag inward at most tol
    sag = -shape.signed_distance(mid[:, 0], mid[:, 1])
    assert sag.max() <= 0.05 and sag.min() >= -1e-12
    assert np.hypot(*(ring - np.roll(ring, -1, axis=0)).T).max() <= 3.0 + 1e-9
    assert tuple(ring[0]) == (45.0, 0.0)
    x, z = ring[:, 0], ring[:, 1]
    assert 0.5 * np.sum(x * np.roll(z, -1) - np.roll(x, -1) * z) > 0  # counter-clockwise from -y


def test_round_outline_is_the_lens_circle():
    scene = scene_with()
    shape = Outline.of_lens(scene["lamps"][0]["lens"])
    assert (shape.half_w, shape.half_h, shape.corner, shape.round) == (45.0, 45.0, 45.0, True)
    assert shape.reach == 45.0 and shape.area == pytest.approx(math.pi * 45 ** 2)


def test_reflector_meets_the_rim_plane_at_the_outline_corner():
    scene = square_scene()
    g = lamp_geometry(scene["lamps"][0])
    reach = math.hypot(45 - 10, 30 - 10) + 10
    assert g["vertex"] == pytest.approx(g["rim"] + reach ** 2 / (4 * 18.0), rel=1e-15)


@pytest.mark.seed(5)
def test_lens_test_of_eye_rays_follows_the_outline(rng):
    scene = square_scene(**{"lamps[0].center": [10.0, -5.0]})
    table = LampTable.from_scene(scene)
    shape = Outline(45, 30, 10)
    x, z = rng.uniform(-60, 60, 20000), rng.uniform(-40, 40, 20000)
    lamp = outer_face.lens_at(x + 10.0, z - 5.0, table)
    np.testing.assert_array_equal(lamp == 0, shape.signed_distance(x, z) <= 0)


@pytest.mark.slow
@pytest.mark.parametrize("edits", [{}, {"lamps[0].lens.corner_radius": 0.0},
                                   {"lamps[0].lens.ior": 2.4, "lamps[0].cuts.height": 4.0}],
                         ids=["rounded", "sharp", "steep-cuts"])
def test_rectangular_lamp_matches_the_reference_pixel_by_pixel(edits):
    # The reference tracer tests every piece of the wall and trims the paraboloid to the prism
    # explicitly; the fast tracer finds the wall in closed form and lets it bound the paraboloid.
    scene = square_scene(**{"camera": {"type": "orthographic", "position": [0, -500, 0], "target": [0, 0, 0],
                                       "up": [0, 0, 1], "width": 100.0},
                            "image": {"width": 56, "height": 40}, **edits})
    result = compare(scene, 56, 40, threshold=1e-5)
    assert result["lens_pixels"] > 1500 and result["escapes"] == 0, result
    assert result["wrong_by_0.1%"] == 0 and result["wrong"] <= 2, result


def test_wall_exit_of_rays_along_the_axis_is_none():
    o = np.array([[1.0, 2.0, 3.0]])
    d = np.array([[0.0, 1.0, 0.0]])
    assert np.isinf(outline.wall_exit(o, d, np.array([45.0]), np.array([30.0]), np.array([10.0])))[0]
    assert np.isinf(side_wall.hit_outline_wall(o, d, np.array([[45.0, 30.0]]), np.array([10.0])))[0]


@pytest.mark.slow
def test_square_lamp_shows_the_rounded_rectangle():
    # Seen head-on, the lens pixels are those inside the outline (the pixel centres of an
    # orthographic camera 0.5 mm apart) and the corners beyond the arcs are body.
    scene = square_scene(**{"camera": {"type": "orthographic", "position": [0, -500, 0], "target": [0, 0, 0],
                                       "up": [0, 0, 1], "width": 100.0},
                            "image": {"width": 200, "height": 140}, "lamps[0].bulb.on": False})
    result = render_passes(scene)
    lens = result.passes["lens_surface"].sum(axis=2) > 0
    x = (np.arange(200) + 0.5) * 0.5 - 50
    z = 35 - (np.arange(140) + 0.5) * 0.5
    inside = Outline(45, 30, 10).inside(x[None, :], z[:, None])
    assert np.array_equal(lens, inside)
    assert render(scene).shape == (140, 200, 3)


@pytest.mark.slow
def test_round_and_rectangular_lamps_together_match_the_reference():
    # The side wall splits its rays between the circle's formula and the outline's: both in one scene.
    import json

    from helpers import FOUR_LAMPS

    from core_tracer import parse_scene

    doc = json.loads(FOUR_LAMPS.read_text())
    for lamp in doc["lamps"][1::2]:
        lamp["lens"].update(outline="rectangular", width=100.0, height=80.0, corner_radius=20.0)
    # (pixel centres off the cut cells' borders: on a crease the two tracers may pick either cap)
    doc["camera"] = {"type": "orthographic", "position": [1.3, -900, 0.7], "target": [1.3, 0, 0.7],
                     "up": [0, 0, 1], "width": 480.0}
    doc["image"] = {"width": 96, "height": 24}
    result = compare(parse_scene(doc), 96, 24, threshold=1e-5)
    assert result["lens_pixels"] > 900 and result["escapes"] == 0, result
    assert result["wrong_by_0.1%"] == 0 and result["wrong"] <= 2, result

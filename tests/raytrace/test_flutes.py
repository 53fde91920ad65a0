"""Cylindrical flutes: the strip walk against a test of every strip, re-intersection from a hit,
and the lens rendered through them."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import scene_with

from core_tracer.raytrace import optics
from core_tracer.raytrace import paths as P
from core_tracer.raytrace.engine import render_passes
from core_tracer.raytrace.parts import base, cuts, flutes, side_wall
from core_tracer.scene.derived import flute_radius

R, T = 45.0, 3.0
CASES = [(9.0, 1.5, 0.0), (5.0, 2.4, 30.0), (3.0, 0.3, -90.0), (12.0, 6.0, 137.0)]  # pitch, height, orientation


def _across(orientation_deg: float) -> np.ndarray:
    th = math.radians(orientation_deg)
    return np.array([-math.sin(th), math.cos(th)])


def brute_force(o, d, pitch, h, across, t_limit, skip=None):
    """Every strip's cylinder (but strip ``skip``) for every ray; the nearest root inside its own strip
    and the slab."""
    rho = flute_radius(pitch, h)
    best = np.full(len(o), np.inf)
    s0 = o[:, 0] * across[0] + o[:, 2] * across[1]
    ds = d[:, 0] * across[0] + d[:, 2] * across[1]
    cy = T + h - rho
    for k in range(-int(np.ceil(R / pitch)) - 2, int(np.ceil(R / pitch)) + 3):
        if k == skip:
            continue
        qs, qy = s0 - k * pitch, o[:, 1] - cy
        a = ds * ds + d[:, 1] ** 2
        b = qs * ds + qy * d[:, 1]
        c = qs * qs + qy * qy - rho * rho
        with np.errstate(invalid="ignore", divide="ignore"):
            sq = np.sqrt(b * b - a * c)
            roots = ((-b - sq) / a, (-b + sq) / a)
        for t in roots:
            s, y = s0 + t * ds, o[:, 1] + t * d[:, 1]
            ok = (np.abs(s - k * pitch) <= pitch / 2 + 1e-9) & (y >= T - 1e-9) & (t > base.T_MIN) & (t < t_limit)
            best = np.where(ok & (t < best), t, best)
    return best


def random_rays(rng, n, h):
    r = R * 0.97 * np.sqrt(rng.uniform(0, 1, n))
    a = rng.uniform(0, 2 * np.pi, n)
    kind = rng.integers(0, 2, n)
    y = np.where(kind == 0, 0.0, rng.uniform(T + h + 0.01, T + h + 10, n))
    o = np.stack([r * np.cos(a), y, r * np.sin(a)], axis=1)
    d = rng.normal(size=(n, 3))
    d[:, 1] = np.where(kind == 0, np.abs(d[:, 1]) + 0.05, -np.abs(d[:, 1]) * rng.choice([1.0, 0.02], n))
    return o, d / np.linalg.norm(d, axis=1, keepdims=True)


def _walk(o, d, pitch, h, across, t_limit, on_cap=None):
    n = len(o)
    return flutes.hit_flutes(o, d, np.full(n, T), np.full(n, T + h), np.full(n, pitch),
                             np.full(n, flute_radius(pitch, h)), np.tile(across, (n, 1)), t_limit, on_cap)


def _random_rays_walked(rng, pitch, h, orientation):
    """5000 random rays through the lens walked across its flutes: (o, d, across, t_limit, t, normal)."""
    across = _across(orientation)
    o, d = random_rays(rng, 5000, h)
    t_limit = side_wall.hit_side_wall(o, d, np.full(len(o), R))
    return o, d, across, t_limit, *_walk(o, d, pitch, h, across, t_limit)


@pytest.mark.parametrize("pitch, h, orientation", CASES)
@pytest.mark.seed(7)
def test_strip_walk_agrees_with_every_strip_tested(pitch, h, orientation, rng):
    o, d, across, t_limit, t_walk, normal = _random_rays_walked(rng, pitch, h, orientation)
    t_brute = brute_force(o, d, pitch, h, across, t_limit)
    assert np.array_equal(np.isfinite(t_walk), np.isfinite(t_brute))
    hit = np.isfinite(t_walk)
    assert hit.sum() > 0.5 * len(o)
    np.testing.assert_allclose(t_walk[hit], t_brute[hit], rtol=1e-9, atol=1e-9)
    p = o[hit] + t_walk[hit, None] * d[hit]
    height = flutes.profile_height(p[:, 0], p[:, 2], T + h, pitch, flute_radius(pitch, h), across)
    np.testing.assert_allclose(p[:, 1], height, atol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(normal[hit], axis=1), 1.0, rtol=1e-12)
    assert np.all(normal[hit, 1] > 0)  # out of the lens: toward the lamp interior


@pytest.mark.parametrize("pitch, h, orientation", CASES)
@pytest.mark.seed(11)
def test_a_ray_leaving_a_flute_finds_the_next_hit_not_its_own(pitch, h, orientation, rng):
    o, d, across, _, t, normal = _random_rays_walked(rng, pitch, h, orientation)
    hit = np.isfinite(t)
    p, d, normal = o[hit] + t[hit, None] * d[hit], d[hit], normal[hit]
    into_air = optics.dot(d, normal) < 0  # arriving from the air, the reflection leaves into the air
    d2 = optics.reflect(d, normal)
    on_cap = np.where(into_air, cuts.INTO_AIR, cuts.INTO_LENS).astype(np.int8)
    limit = side_wall.hit_side_wall(p, d2, np.full(len(p), R))
    t2, _ = _walk(p, d2, pitch, h, across, limit, on_cap)
    t_brute = brute_force(p, d2, pitch, h, across, limit)
    t_brute = np.where(t_brute < 1e-7, np.inf, t_brute)  # the start point itself, a rounding error away
    assert np.all(t2 > 1e-6)
    agree = np.isclose(t2, t_brute, rtol=1e-9, atol=1e-9) | (np.isinf(t2) & np.isinf(t_brute))
    assert agree.mean() > 0.999


def test_a_fluted_lens_renders_with_every_transition_in_table_1():
    scene = scene_with(**{"lamps[0].cuts.type": "flutes", "lamps[0].cuts.height": 2.0,
                          "lamps[0].cuts.orientation": 90.0, "image": {"width": 64, "height": 48}})
    result = render_passes(scene, record_transitions=True)
    assert not [t for t in result.stats["transitions"] if not P.allowed(*t)]
    assert np.all(np.isfinite(result.image)) and result.image.max() > 0


@pytest.mark.seed(5)
def test_a_grazing_ray_leaving_a_flute_into_the_air_never_meets_it_again(rng):
    """Grazing rays leave flute 0 into the air from 1e-12 mm on the wrong side (inside the lens, as a
    rounded hit may): by distance alone many meet their own flute again; told that they start on
    it, the walk finds only what every other strip gives."""
    pitch, h, across = 9.0, 3.0, _across(0.0)
    rho = flute_radius(pitch, h)
    n = 400
    x, z = rng.uniform(-30, 30, n), rng.uniform(-0.45 * pitch, 0.45 * pitch, n)
    y = flutes.profile_height(x, z, T + h, pitch, rho, across)
    normal = np.column_stack([np.zeros(n), y - (T + h - rho), z]) / rho
    tangent = np.column_stack([rng.normal(size=n), -z, y - (T + h - rho)])  # along the ridge and round it
    tangent -= np.einsum("ij,ij->i", tangent, normal)[:, None] * normal
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    d = optics.normalize(tangent + 1e-8 * normal)  # grazing, outward
    o = np.column_stack([x, y, z]) - 1e-12 * normal
    limit = side_wall.hit_side_wall(o, d, np.full(n, R))
    t_threshold, _ = _walk(o, d, pitch, h, across, limit)
    t_geometry, _ = _walk(o, d, pitch, h, across, limit, np.full(n, cuts.INTO_AIR, np.int8))
    assert np.count_nonzero(t_threshold < 1e-3) > n // 4  # own flute met again, beyond T_MIN
    expected = brute_force(o, d, pitch, h, across, limit, skip=0)  # every strip but the start's own
    assert np.array_equal(np.isinf(t_geometry), np.isinf(expected))
    hit = np.isfinite(expected)
    np.testing.assert_allclose(t_geometry[hit], expected[hit], rtol=1e-9)

"""The saw-tooth cuts: the strip walk against a test of every strip, re-intersection from a hit,
Snell's law at the tooth angle, and the dispatch by cut type in the tracer."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from helpers import FOUR_LAMPS, scene_with

from core_tracer.raytrace import optics
from core_tracer.raytrace import paths as P
from core_tracer.raytrace.engine import render, render_passes
from core_tracer.raytrace.lamp_table import LampTable
from core_tracer.raytrace.parts import base, cut_surface, cuts, sawtooth, side_wall
from core_tracer.raytrace.parts.base import Segments
from core_tracer.scene.validate import parse_scene

R, T = 45.0, 3.0
# (pitch, tooth angle deg, orientation deg): horizontal, oblique and vertical ridges, shallow and steep
CASES = [(4.0, 25.0, 0.0), (6.0, 40.0, 30.0), (2.5, 10.0, -90.0), (9.0, 55.0, 137.0)]


def _across(orientation_deg: float) -> np.ndarray:
    th = math.radians(orientation_deg)
    return np.array([-math.sin(th), math.cos(th)])


def brute_force(o, d, pitch, slope, across, t_limit):
    """Every strip's inclined facet and every border's return facet, for every ray; the nearest
    hit inside its own facet (and the normal out of the lens there)."""
    h = pitch * slope
    best = np.full(len(o), np.inf)
    best_n = np.zeros((len(o), 3))
    s0 = o[:, 0] * across[0] + o[:, 2] * across[1]
    ds = d[:, 0] * across[0] + d[:, 2] * across[1]
    n_facet = np.array([-slope * across[0], 1.0, -slope * across[1]]) / math.sqrt(1 + slope * slope)
    n_wall = np.array([across[0], 0.0, across[1]])
    n_strips = int(np.ceil(R / pitch)) + 2
    for k in range(-n_strips, n_strips + 1):
        lo, hi = (k - 0.5) * pitch, (k + 0.5) * pitch
        with np.errstate(divide="ignore", invalid="ignore"):
            t_f = (o[:, 1] - T - slope * (s0 - lo)) / (slope * ds - d[:, 1])
            t_w = (hi - s0) / ds
        s_f = s0 + t_f * ds
        y_w = o[:, 1] + t_w * d[:, 1]
        for t, ok, nrm in ((t_f, (s_f >= lo - 1e-9) & (s_f <= hi + 1e-9), n_facet),
                           (t_w, (y_w >= T - 1e-9) & (y_w <= T + h + 1e-9), n_wall)):
            good = ok & (t > base.T_MIN) & (t < t_limit) & (t < best)
            best = np.where(good, t, best)
            best_n[good] = nrm
    return best, best_n


def random_rays(rng, n, h):
    """Rays from the outer face into the lens, from the air behind the ridges toward them (some
    grazing), and from points inside the slab itself, in every direction."""
    r = R * 0.97 * np.sqrt(rng.uniform(0, 1, n))
    a = rng.uniform(0, 2 * np.pi, n)
    kind = rng.integers(0, 3, n)
    y = np.where(kind == 0, 0.0, np.where(kind == 1, rng.uniform(T + h + 0.01, T + h + 10, n),
                                          rng.uniform(T, T + h, n)))
    o = np.stack([r * np.cos(a), y, r * np.sin(a)], axis=1)
    d = rng.normal(size=(n, 3))
    d[:, 1] = np.where(kind == 0, np.abs(d[:, 1]) + 0.05,
                       np.where(kind == 1, -np.abs(d[:, 1]) * rng.choice([1.0, 0.02], n), d[:, 1]))
    return o, d / np.linalg.norm(d, axis=1, keepdims=True)


def _walk(o, d, pitch, slope, across, t_limit):
    n = len(o)
    return sawtooth.hit_sawtooth(o, d, np.full(n, T), np.full(n, T + pitch * slope), np.full(n, pitch),
                                 np.full(n, slope), np.tile(across, (n, 1)), t_limit)


@pytest.mark.parametrize("pitch, angle, orientation", CASES)
@pytest.mark.seed(1990)
def test_strip_walk_agrees_with_every_strip_tested(pitch, angle, orientation, rng):
    slope, across = math.tan(math.radians(angle)), _across(orientation)
    o, d = random_rays(rng, 6000, pitch * slope)
    t_limit = side_wall.hit_side_wall(o, d, np.full(len(o), R))
    t_walk, n_walk = _walk(o, d, pitch, slope, across, t_limit)
    t_brute, n_brute = brute_force(o, d, pitch, slope, across, t_limit)
    assert np.array_equal(np.isfinite(t_walk), np.isfinite(t_brute))
    hit = np.isfinite(t_walk)
    assert hit.sum() > 0.5 * len(o)
    np.testing.assert_allclose(t_walk[hit], t_brute[hit], rtol=1e-9, atol=1e-9)
    # Away from the creases (where two facets meet and either normal is right) the facets agree.
    p = o[hit] + t_walk[hit, None] * d[hit]
    s = p[:, 0] * across[0] + p[:, 2] * across[1]
    u = s / pitch + 0.5 - np.floor(s / pitch + 0.5)
    inner = (u > 1e-6) & (u < 1 - 1e-6)
    np.testing.assert_allclose(n_walk[hit][inner], n_brute[hit][inner], atol=1e-12)
    # The hits on inclined facets lie on the profile; the others on a border, within the slab.
    on_facet = n_walk[hit, 1] > 0
    height = sawtooth.profile_height(p[:, 0], p[:, 2], T, pitch, slope, across)
    np.testing.assert_allclose(p[on_facet & inner, 1], height[on_facet & inner], atol=1e-9)
    assert (~on_facet).sum() > 0.02 * hit.sum()  # the return facets are met, too
    np.testing.assert_allclose(np.minimum(u[~on_facet], 1 - u[~on_facet]), 0.0, atol=1e-9)


@pytest.mark.parametrize("pitch, angle, orientation", CASES)
@pytest.mark.seed(12)
def test_a_ray_leaving_a_hit_point_finds_no_closer_hit(pitch, angle, orientation, rng):
    """From each hit, the reflected and the refracted ray (into the lens or into the air) find
    the same next hit as every strip tested, and never their own facet again."""
    slope, across = math.tan(math.radians(angle)), _across(orientation)
    o, d = random_rays(rng, 6000, pitch * slope)
    t_limit = side_wall.hit_side_wall(o, d, np.full(len(o), R))
    t, normal = _walk(o, d, pitch, slope, across, t_limit)
    hit = np.isfinite(t)
    p, d, normal = o[hit] + t[hit, None] * d[hit], d[hit], normal[hit]
    facing = np.where((optics.dot(d, normal) < 0)[:, None], normal, -normal)
    for d2 in (optics.reflect(d, normal), optics.refract(d, facing, 1.0 / 1.49)):
        limit = side_wall.hit_side_wall(p, d2, np.full(len(p), R))
        t2, _ = _walk(p, d2, pitch, slope, across, limit)
        t_brute, _ = brute_force(p, d2, pitch, slope, across, limit)
        assert np.all(t2 > 1e-6)
        # every strip tested also sees the start point's own facet a rounding error away: skip those
        t_brute = np.where(t_brute < 1e-7, np.inf, t_brute)
        far = np.isfinite(t_brute) & (t_brute > 1e-6)
        agree = np.isclose(t2, t_brute, rtol=1e-9, atol=1e-9) | (np.isinf(t2) & ~far)
        assert agree.mean() > 0.999, np.nonzero(~agree)[0][:5]


@pytest.mark.seed(3)
def test_grazing_rays_leaving_a_facet_never_meet_it_again(rng):
    pitch, slope, across = 5.0, math.tan(math.radians(30.0)), _across(0.0)
    n = 4000
    s = rng.uniform(-20, 20, n)
    k = np.floor(s / pitch + 0.5)
    y = T + slope * (s - (k - 0.5) * pitch)
    x = rng.uniform(-20, 20, n)
    p = np.stack([x, y, s], axis=1)
    # directions within 1e-9 rad of the facet plane, along the ridge or across it
    t_dir = np.array([0.0, slope, 1.0]) / math.sqrt(1 + slope * slope)
    d = np.where(rng.uniform(size=n)[:, None] < 0.5, [1.0, 0.0, 0.0], t_dir)
    nrm = np.array([0.0, 1.0, -slope]) / math.sqrt(1 + slope * slope)
    d = optics.normalize(d + rng.uniform(-1e-9, 1e-9, n)[:, None] * nrm)
    t, _ = _walk(p, d, pitch, slope, across, np.full(n, np.inf))
    q = p + np.where(np.isfinite(t), t, 0.0)[:, None] * d
    # a hit, if any, is on another facet: at least across the rest of its own strip away
    assert np.all(~np.isfinite(t) | (np.abs(q[:, 2] - s) > 1e-3) | (np.abs(q[:, 0] - x) > 1e-3))


@pytest.mark.parametrize("ior, angle", [(1.49, 20.0), (1.49, 35.0), (1.59, 10.0)])
def test_a_facet_deviates_a_collimated_ray_by_snell_at_the_tooth_angle(ior, angle):
    """Light from the reflector travelling -y (out of the lamp) enters a facet inclined at alpha
    and leaves through the flat outer face: a prism of apex angle alpha, so the ray leaves at
    sin(theta) = n sin(alpha - asin(sin(alpha) / n)) from the axis, toward the ridges' thick end."""
    lamps = LampTable.from_scene(scene_with(**{
        "lamps[0].cuts.type": "sawtooth", "lamps[0].cuts.pitch": 6.0, "lamps[0].cuts.tooth_angle": angle,
        "lamps[0].lens.ior": ior}))
    n = 50
    o = np.stack([np.linspace(-20, 20, n), np.full(n, 40.0), np.linspace(-20.3, 19.7, n)], axis=1)
    d = np.tile([0.0, -1.0, 0.0], (n, 1))
    rays = Segments(o, d, np.zeros(n, int), np.full(n, P.REFLECTOR, np.int8), np.full(n, P.IN_AIR, np.int8))
    t, normal = cut_surface.intersect(rays, lamps, np.full(n, np.inf))
    assert np.all(np.isfinite(t)) and np.all(normal[:, 1] > 0)  # every vertical ray meets an inclined facet
    inside = optics.refract(d, normal, 1.0 / ior)
    out = optics.refract(inside, np.tile([0.0, -1.0, 0.0], (n, 1)), ior)
    a = math.radians(angle)
    expected = math.asin(ior * math.sin(a - math.asin(math.sin(a) / ior)))
    np.testing.assert_allclose(np.arcsin(out[:, 2]), expected, rtol=1e-12)  # orientation 0: toward +z
    np.testing.assert_allclose(out[:, 0], 0.0, atol=1e-15)


@pytest.mark.slow
def test_fisheye_lamps_render_the_same_beside_a_sawtooth_lamp():
    """The dispatch by cut type: the four-lamp combination's fish-eye lamps keep every pixel when
    lamp 1 becomes saw-tooth (a ray never leaves its lamp), and the explicit default type changes
    nothing."""
    doc = json.loads(FOUR_LAMPS.read_text())
    doc["image"] = {"width": 96, "height": 24}
    fish = render(parse_scene(doc))
    explicit = json.loads(json.dumps(doc))
    for lamp in explicit["lamps"]:
        lamp["cuts"]["type"] = "fisheye"
    assert np.array_equal(render(parse_scene(explicit)), fish)
    doc["lamps"][0]["cuts"].update(type="sawtooth", tooth_angle=30.0)
    changed = np.any(render(parse_scene(doc)) != fish, axis=2)
    assert changed.sum() > 20
    # where each changed pixel's eye ray meets the front plane y = 0 (camera at y = -1900 on the axis)
    half = math.tan(math.radians(doc["camera"]["fov_deg"] / 2)) * -doc["camera"]["position"][1]
    x = (2 * (np.nonzero(changed)[1] + 0.5) / 96 - 1) * half
    cx, r = doc["lamps"][0]["center"][0], doc["lamps"][0]["lens"]["radius"]
    assert np.all(np.abs(x - cx) < r + half / 48)  # within lamp 1's lens (to a pixel)


def test_cuts_module_is_untouched_by_the_dispatch_without_sawtooth():
    lamps = LampTable.from_scene(scene_with())
    o = np.array([[1.0, 0.0, 2.0]])
    d = optics.normalize(np.array([[0.1, 1.0, 0.2]]))
    rays = Segments(o, d, np.array([0]), np.array([P.OUTER], np.int8), np.array([P.IN_LENS], np.int8))
    t_fish, n_fish = cuts.intersect(rays, lamps, np.array([np.inf]))
    t, nrm = cut_surface.intersect(rays, lamps, np.array([np.inf]))
    assert t[0] == t_fish[0] and np.array_equal(nrm, n_fish)
    assert cut_surface.SURFACE == sawtooth.SURFACE == cuts.SURFACE and sawtooth.MEDIA == cuts.MEDIA


@pytest.mark.slow
def test_steep_teeth_reach_the_cut_to_cut_paths_and_stay_in_table_1():
    """Between a facet and the next strip's return facet a ray meets the cut twice, in the lens (⑧)
    and in the air (⑨); every transition is still one of Table 1's."""
    scene = scene_with(**{"lamps[0].cuts.type": "sawtooth", "lamps[0].cuts.tooth_angle": 35.0,
                          "lamps[0].cuts.pitch": 5.0, "lamps[0].cuts.orientation": 20.0, "lamps[0].lens.ior": 1.7})
    result = render_passes(scene, 96, 96, record_transitions=True)
    seen = result.stats["transitions"]
    assert not [t for t in seen if not P.allowed(*t)]
    assert {c for *_, c in seen} >= {2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12}
    assert np.all(np.isfinite(result.image)) and np.all(result.image >= 0)


def test_a_zero_tooth_angle_is_the_flat_inner_face_of_a_zero_cut_height():
    """Both cut types degenerate to the same flat inner face at plane A: the same image, bit for bit."""
    size = {"image": {"width": 48, "height": 32}}
    flat = render(scene_with(**size, **{"lamps[0].cuts.height": 0.0}))
    saw = render(scene_with(**size, **{"lamps[0].cuts.type": "sawtooth", "lamps[0].cuts.tooth_angle": 0.0,
                                       "lamps[0].cuts.orientation": 33.0}))
    assert np.array_equal(saw, flat)

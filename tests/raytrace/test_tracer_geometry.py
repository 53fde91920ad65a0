"""The lamp's surfaces: the cut-surface cell walk against brute force, quadrics, re-intersection."""

from __future__ import annotations

import numpy as np
import pytest

from core_tracer.raytrace.parts import base, body_box, bulb, cuts, reflector, side_wall, socket
from core_tracer.scene.derived import cut_sphere_radius

R, T, P_, H = 45.0, 3.0, 9.0, 1.5
RHO = cut_sphere_radius(P_, H)


def brute_force_cuts(o, d, plane_a, plane_b, pitch, rho, t_limit):
    """Test every cell's sphere for every ray; keep the nearest root inside its own cell."""
    n_cells = int(np.ceil(R / pitch)) + 1
    best = np.full(len(o), np.inf)
    for i in range(-n_cells, n_cells + 1):
        for j in range(-n_cells, n_cells + 1):
            c = np.array([i * pitch, plane_b - rho, j * pitch])
            oc = o - c
            b = np.einsum("ij,ij->i", oc, d)
            cc = np.einsum("ij,ij->i", oc, oc) - rho * rho
            with np.errstate(invalid="ignore"):
                sq = np.sqrt(b * b - cc)
            for t in (-b - sq, -b + sq):
                p = o + t[:, None] * d
                inside = (np.abs(p[:, 0] - i * pitch) <= pitch / 2) & (np.abs(p[:, 2] - j * pitch) <= pitch / 2)
                ok = (t > base.T_MIN) & inside & (p[:, 1] >= plane_a - 1e-9) & (t < t_limit)
                best = np.where(ok & (t < best), t, best)
    return best


def random_rays(rng, n, where):
    if where == "lens":  # from the outer face, into the lens
        r = R * np.sqrt(rng.uniform(0, 1, n))
        a = rng.uniform(0, 2 * np.pi, n)
        o = np.stack([r * np.cos(a), np.zeros(n), r * np.sin(a)], axis=1)
        d = rng.normal(size=(n, 3))
        d[:, 1] = np.abs(d[:, 1]) + 0.05
    else:  # from the air above the cuts, heading back toward them, some nearly grazing
        r = R * 0.95 * np.sqrt(rng.uniform(0, 1, n))
        a = rng.uniform(0, 2 * np.pi, n)
        o = np.stack([r * np.cos(a), rng.uniform(T + H + 0.01, 12, n), r * np.sin(a)], axis=1)
        d = rng.normal(size=(n, 3))
        d[:, 1] = -np.abs(d[:, 1]) * rng.choice([1.0, 0.05], n)
    return o, d / np.linalg.norm(d, axis=1, keepdims=True)


@pytest.mark.parametrize("where", ["lens", "air"])
@pytest.mark.seed(1990)
def test_cell_walk_agrees_with_brute_force(where, rng):
    o, d = random_rays(rng, 4000, where)
    n = len(o)
    radius = np.full(n, R)
    t_limit = side_wall.hit_side_wall(o, d, radius)
    args = (np.full(n, T), np.full(n, T + H), np.full(n, P_), np.full(n, RHO))
    t_walk, normal = cuts.hit_cuts(o, d, *args, t_limit)
    t_brute = brute_force_cuts(o, d, T, T + H, P_, RHO, t_limit)
    both = np.isfinite(t_walk) & np.isfinite(t_brute)
    assert np.array_equal(np.isfinite(t_walk), np.isfinite(t_brute))
    assert both.sum() > 0.4 * n
    np.testing.assert_allclose(t_walk[both], t_brute[both], rtol=1e-9, atol=1e-9)
    # the hit lies on the cut surface, and the normal is the cap's unit normal
    p = o[both] + t_walk[both, None] * d[both]
    height = cuts.cut_surface_height(p[:, 0], p[:, 2], T + H, P_, RHO)
    np.testing.assert_allclose(p[:, 1], height, atol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(normal[both], axis=1), 1.0, rtol=1e-12)


@pytest.mark.seed(3)
def test_cell_walk_from_the_surface_itself_finds_the_next_cap_not_its_own(rng):
    # Re-intersect from hit points (pbrt's habit): rays leaving the cut surface into the air,
    # heading up, never hit the cut surface again unless they cross into a neighbouring cap.
    o, d = random_rays(rng, 2000, "lens")
    n = len(o)
    args = (np.full(n, T), np.full(n, T + H), np.full(n, P_), np.full(n, RHO))
    t, normal = cuts.hit_cuts(o, d, *args, side_wall.hit_side_wall(o, d, np.full(n, R)))
    ok = np.isfinite(t)
    p = o[ok] + t[ok, None] * d[ok]
    up = np.tile([0.0, 1.0, 0.0], (ok.sum(), 1))  # straight up, away from every cap
    t2, _ = cuts.hit_cuts(p, up, *(a[ok] for a in args), np.full(ok.sum(), np.inf))
    assert np.all(np.isinf(t2))


def test_flat_inner_face_is_plane_a():
    o = np.array([[1.0, 0.0, 2.0]])
    d = np.array([[0.0, 1.0, 0.0]])
    t, normal = cuts.hit_cuts(o, d, np.array([3.0]), np.array([3.0]), np.array([9.0]), np.array([np.inf]),
                           np.array([np.inf]))
    assert t[0] == pytest.approx(3.0)
    np.testing.assert_array_equal(normal[0], [0.0, 1.0, 0.0])


@pytest.mark.seed(5)
def test_paraboloid_hits_lie_on_the_surface_and_focus_reflects_to_axis(rng):
    f, R_, rim = 18.0, 45.0, 4.5
    vertex = rim + R_ * R_ / (4 * f)
    focus = np.array([0.0, vertex - f, 0.0])
    d = rng.normal(size=(3000, 3))
    d[:, 1] = np.abs(d[:, 1])
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    o = np.tile(focus, (3000, 1))
    n = len(o)
    t = reflector.hit_reflector(o, d, np.full(n, f), np.full(n, vertex), np.full(n, rim))
    ok = np.isfinite(t)
    assert ok.sum() > 1000
    p = o[ok] + t[ok, None] * d[ok]
    np.testing.assert_allclose(p[:, 1], vertex - (p[:, 0] ** 2 + p[:, 2] ** 2) / (4 * f), atol=1e-9)
    assert np.all(p[:, 1] >= rim - 1e-9)
    # a paraboloid sends light from its focus out parallel to its axis (toward -y)
    normal = reflector.reflector_normal(p, np.full(ok.sum(), f))
    out = d[ok] - 2 * np.einsum("ij,ij->i", d[ok], normal)[:, None] * normal
    np.testing.assert_allclose(out, np.tile([0.0, -1.0, 0.0], (ok.sum(), 1)), atol=1e-9)


def test_sphere_and_socket_hits():
    o = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [3.0, 20.0, 0.0]])
    d = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]])
    c = np.tile([0.0, 14.0, 0.0], (3, 1))
    t = bulb.hit_sphere(o, d, c, np.full(3, 8.0))
    assert t[0] == pytest.approx(6.0) and np.isinf(t[1])
    ts = socket.hit_socket(o, d, np.full(3, 2.0), np.full(3, 14.0), np.full(3, 30.0))
    # along the axis the ray meets the disk that closes the socket at the bulb-centre plane (docs/model.md §3)
    assert ts[0] == pytest.approx(14.0) and np.isinf(ts[1]) and ts[2] == pytest.approx(1.0)


@pytest.mark.seed(5)
def test_a_ray_leaving_a_cap_never_meets_that_cap_again_even_from_the_wrong_side(rng):
    # Grazing rays leave the cap of cell (0, 0) into the air, starting 1e-12 mm on the wrong side
    # (inside the lens, as a rounded hit may). A distance threshold (T_MIN) alone lets many of them
    # meet their own cap again; told that they start on the cap, the walk agrees with a cell-by-
    # cell test that excludes the cap by geometry.
    from helpers import scene_with
    from reference_tracer import Lamp

    n = 400
    x, z = rng.uniform(-0.45 * P_, 0.45 * P_, n), rng.uniform(-0.45 * P_, 0.45 * P_, n)
    y = cuts.cut_surface_height(x, z, T + H, P_, RHO)
    hit = np.column_stack([x, y, z])
    normal = (hit - [0.0, T + H - RHO, 0.0]) / RHO
    tangent = np.cross(normal, rng.normal(size=(n, 3)))
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    d = tangent + 1e-8 * normal  # grazing, outward
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    o = hit - 1e-12 * normal
    args = (np.full(n, T), np.full(n, T + H), np.full(n, P_), np.full(n, RHO),
            side_wall.hit_side_wall(o, d, np.full(n, R)))
    t_threshold, _ = cuts.hit_cuts(o, d, *args)
    t_geometry, _ = cuts.hit_cuts(o, d, *args, np.full(n, cuts.INTO_AIR, np.int8))
    assert np.count_nonzero(t_threshold < 1e-4) > n // 2  # own cap met again, beyond T_MIN
    lamp = Lamp(scene_with()["lamps"][0])
    for k in range(n):
        ref = lamp.cuts(o[k], d[k], args[-1][k], ("cut", 0, 0), False)
        if ref is None:
            assert np.isinf(t_geometry[k]), k
        else:
            assert t_geometry[k] == pytest.approx(ref[0], rel=1e-9), k


@pytest.mark.seed(8)
def test_a_ray_leaving_the_reflector_meets_it_only_at_its_other_root(rng):
    from helpers import scene_with
    from reference_tracer import Lamp

    f, rim = 18.0, T + H
    vertex = rim + R * R / (4 * f)
    n = 400
    r, a = rng.uniform(5, 44, n), rng.uniform(0, 2 * np.pi, n)
    hit = np.column_stack([r * np.cos(a), vertex - r * r / (4 * f), r * np.sin(a)])
    normal = reflector.reflector_normal(hit, np.full(n, f))
    tangent = np.cross(normal, rng.normal(size=(n, 3)))
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    d = tangent + 1e-5 * normal  # grazing, into the lamp
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    o = hit - 1e-10 * normal  # a rounding error behind the mirror: the mirror itself is 1e-5 mm ahead
    params = (np.full(n, f), np.full(n, vertex), np.full(n, rim))
    assert np.count_nonzero(reflector.hit_reflector(o, d, *params) < 1e-4) > n // 2  # itself, beyond T_MIN
    t = reflector.hit_reflector(o, d, *params, np.ones(n, bool))
    lamp = Lamp(scene_with()["lamps"][0])
    for k in range(n):
        ref = lamp.reflector(o[k], d[k], "reflector")
        if ref is None:
            assert np.isinf(t[k]), k
        else:
            assert t[k] == pytest.approx(ref[0], rel=1e-9), k


def test_box_entry_exit_and_face():
    lo, hi = np.array([-10.0, 0.0, -5.0]), np.array([10.0, 8.0, 5.0])
    o = np.array([
        [0.0, -20.0, 0.0],  # straight at the front face
        [-30.0, 4.0, 0.0],  # at the left face, parallel to the y and z slabs (inside them)
        [0.0, -20.0, 7.0],  # parallel to the z slab, outside it: a miss
        [3.0, -20.0, -12.0],  # oblique, in through the front face and out through the top
        [0.0, 4.0, 0.0],  # from inside the box
    ])
    d = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.8, 0.6], [0.0, 1.0, 0.0]])
    t_near, t_far, face = body_box.hit_box(o, d, lo, hi)
    np.testing.assert_allclose(t_near[[0, 1, 3]], [20.0, 20.0, 25.0])
    np.testing.assert_allclose(t_far[[0, 1, 3]], [28.0, 40.0, 17.0 / 0.6])
    assert list(face[[0, 1, 3]]) == [1, 0, 1]
    hit = (t_near <= t_far) & (t_near > 0)
    assert list(hit) == [True, True, False, True, False]  # from inside: not a hit from outside
    assert t_near[4] < 0 < t_far[4]


def test_body_box_corners():
    lo, hi = body_box.body_box({"center": [5.0, -2.0], "size": [40.0, 20.0], "depth": 30.0})
    assert lo.tolist() == [-15.0, 0.0, -12.0] and hi.tolist() == [25.0, 30.0, 8.0]

"""The paper's model on meshes against closed forms: the slab series through a flat lens mesh, a
mesh paraboloid focusing axis-parallel rays, and Embree's hits against a plain Möller–Trumbore."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import slab_series
from needs import require

from core_tracer.freeform import GeometryCache, render_passes, shapes
from core_tracer.freeform.render import surface_hits
from core_tracer.raytrace.engine.rays import CUTOFF
from core_tracer.scene.validate import parse_scene

require("embreex")



def slab_design(ior: float, lens_values: dict, thickness: float, intensity) -> tuple[dict, dict]:
    """A flat lens slab in y in [0, t] seen straight on by an orthographic camera, a bulb wall behind."""
    meshes = {m.name: m for m in (shapes.box("Slab", (-30, 0, -30), (30, thickness, 30)),
                                  shapes.box("Bulb", (-60, 20, -60), (60, 30, 60)))}
    doc = {"schema": "lamp-scene/2", "lamps": [{}],
           "camera": {"type": "orthographic", "position": [0, -500, 0], "target": [0, 0, 0], "up": [0, 0, 1],
                      "width": 20.0},
           "image": {"width": 9, "height": 9},
           "freeform": {"mesh_file": "slab.glb", "parts": [
               {"object": "Slab", "role": "lens", "lens": {"ior": ior, "specular": 0.0, "diffuse_color": [0, 0, 0],
                                                           **lens_values}},
               {"object": "Bulb", "role": "bulb", "bulb": {"intensity": list(intensity)}}]}}
    return parse_scene(doc), meshes


@pytest.mark.parametrize("ior", [1.3, 1.49, 2.4])
def test_bulb_through_a_clear_slab_mesh_is_the_slab_series(ior):
    scene, meshes = slab_design(ior, {"absorption": [0, 0, 0]}, 3.0, (8.0, 7.0, 6.0))
    result = render_passes(scene, meshes, record_transitions=True)
    r = ((ior - 1) / (ior + 1)) ** 2
    expected = np.array([8.0, 7.0, 6.0]) * slab_series(r, np.ones(3), CUTOFF)
    np.testing.assert_allclose(result.image[4, 4], expected, rtol=1e-6)
    np.testing.assert_allclose(result.passes["bulb"][4, 4], expected, rtol=1e-6)
    # The walk is Table 1's: ① → ② → ⑪, with ② ⇄ ⑥ inside and ⑩ out.
    assert {(1, 1, 2), (2, 1, 11)} <= result.stats["transitions"]
    if ior == 2.4:  # r = 0.17: the second pass clears the cut-off and is traced
        assert (2, 0, 6) in result.stats["transitions"] and (6, 0, 2) in result.stats["transitions"]


@pytest.mark.parametrize("form", ["absorption", "transmitted_color"])
def test_bulb_through_an_absorbing_slab_mesh_follows_equation_2(form):
    t, ior = 4.0, 1.49
    a = np.array([0.02, 0.6, 1.1])
    values = {"absorption": a.tolist()} if form == "absorption" else \
        {"transmitted_color": np.exp(-a * 2.0).tolist(), "reference_thickness": 2.0}
    scene, meshes = slab_design(ior, values, t, (5.0, 5.0, 5.0))
    centre = render_passes(scene, meshes).image[4, 4]
    r = ((ior - 1) / (ior + 1)) ** 2
    np.testing.assert_allclose(centre, 5.0 * slab_series(r, np.exp(-a * t), CUTOFF), rtol=1e-5)


def test_lens_surface_is_fresnel_times_phong_at_the_outer_face():
    # Eye rays at normal incidence on the outer face: r × eq. (1) with the lens's diffuse colour.
    scene, meshes = slab_design(1.49, {"absorption": [0, 0, 0]}, 3.0, (0.0, 0.0, 0.0))
    scene["freeform"]["parts"][0]["lens"].update(diffuse_color=[0.5, 0.2, 0.1], specular=0.0)
    light = scene["light"]
    ld = np.asarray(light["direction"]) / np.linalg.norm(light["direction"])
    cos_theta = max(0.0, -ld[1])  # the outer face's normal is -y
    r = (0.49 / 2.49) ** 2
    expected = r * (light["ambient"] + (1 - light["ambient"]) * cos_theta) * np.array([0.5, 0.2, 0.1])
    result = render_passes(scene, meshes)
    np.testing.assert_allclose(result.passes["lens_surface"][4, 4], expected, rtol=1e-6)


def chord_error(dish, focal: float, vertex_y: float) -> float:
    """The largest distance (along y, an upper bound of the normal distance) between the mesh and
    the paraboloid, sampled on every triangle."""
    p = dish.vertices[dish.triangles]
    w = np.array([[1, 1, 1], [4, 1, 1], [1, 4, 1], [1, 1, 4], [2, 2, 1], [1, 2, 2], [2, 1, 2]], float)
    w /= w.sum(axis=1, keepdims=True)
    s = np.einsum("wk,tkc->twc", w, p).reshape(-1, 3)
    surface_y = vertex_y - (s[:, 0] ** 2 + s[:, 2] ** 2) / (4 * focal)
    return float(np.abs(s[:, 1] - surface_y).max())


@pytest.mark.slow
@pytest.mark.parametrize("rings,segments", [(32, 64), (96, 192)])
@pytest.mark.seed(3)
def test_mesh_paraboloid_focuses_axis_parallel_rays_within_the_chord_error(rings, segments, rng):
    f, rim_radius, vertex_y = 18.0, 45.0, 32.0
    dish = shapes.paraboloid_dish("Dish", f, rim_radius, vertex_y, rings=rings, segments=segments)
    scene = parse_scene({"schema": "lamp-scene/2", "lamps": [{}], "freeform": {"mesh_file": "d.glb", "parts": [
        {"object": "Dish", "role": "reflector"}]}})
    radius = rim_radius * np.sqrt(rng.uniform(0.02, 0.95, 2000))
    phi = rng.uniform(0, 2 * math.pi, 2000)
    o = np.stack([radius * np.cos(phi), np.full(2000, -10.0), radius * np.sin(phi)], axis=1)
    d = np.tile([0.0, 1.0, 0.0], (2000, 1))
    hits = surface_hits(scene, {"Dish": dish}, o, d)
    assert (hits["triangle"] >= 0).all()
    n = hits["normal"]
    n = np.where((np.einsum("ij,ij->i", n, d) > 0)[:, None], -n, n)
    reflected = d - 2 * np.einsum("ij,ij->i", d, n)[:, None] * n
    focus = np.array([0.0, vertex_y - f, 0.0])
    to_focus = focus - hits["point"]
    # Distance of the focus from each reflected ray's line.
    miss = np.linalg.norm(np.cross(to_focus, reflected), axis=1)
    delta = chord_error(dish, f, vertex_y)
    # A hit displaced by δ along the axis reflects a line displaced by at most 2δ·sin(angle) ≤ 2δ;
    # the interpolated normals add the same order (their error is the chord's slope error).
    assert miss.max() <= 4 * delta, (miss.max(), delta)
    assert np.median(miss) <= delta
    if rings == 96:
        assert delta < 0.01  # the finer mesh: the focus within 40 µm


def moller_trumbore(o: np.ndarray, d: np.ndarray, corners: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Nearest hit of every ray over every triangle, brute force in double precision."""
    p0, p1, p2 = corners[:, 0], corners[:, 1], corners[:, 2]
    e1, e2 = p1 - p0, p2 - p0
    best_t = np.full(len(o), np.inf)
    best = np.full(len(o), -1)
    for start in range(0, len(corners), 256):
        sl = slice(start, start + 256)
        pvec = np.cross(d[:, None, :], e2[None, sl])
        det = np.einsum("tc,rtc->rt", e1[sl], pvec)
        ok = np.abs(det) > 1e-12
        inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
        tvec = o[:, None, :] - p0[None, sl]
        u = np.einsum("rtc,rtc->rt", tvec, pvec) * inv
        qvec = np.cross(tvec, e1[None, sl])
        v = np.einsum("rc,rtc->rt", d, qvec) * inv
        t = np.einsum("tc,rtc->rt", e2[sl], qvec) * inv
        valid = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)
        t = np.where(valid, t, np.inf)
        j = t.argmin(axis=1)
        tj = t[np.arange(len(o)), j]
        better = tj < best_t
        best_t[better] = tj[better]
        best[better] = j[better] + start
    return best_t, best


@pytest.mark.slow
@pytest.mark.seed(11)
def test_embree_hits_agree_with_brute_force_moller_trumbore(rng):
    parts = [shapes.uv_sphere("Ball", (10, 40, -5), 12, 24), shapes.box("Block", (-40, 20, -30), (-10, 50, 10)),
             shapes.paraboloid_dish("Dish", 15, 35, 70, rings=12, segments=24),
             shapes.cylinder("Post", (25, 25), 6, 10, 60, segments=20)]
    roles = ["lens", "body", "reflector", "socket"]
    scene = parse_scene({"schema": "lamp-scene/2", "lamps": [{}], "freeform": {"mesh_file": "m.glb", "parts": [
        {"object": m.name, "role": role} for m, role in zip(parts, roles, strict=True)]}})
    meshes = {m.name: m for m in parts}
    n = 4000
    o = rng.uniform(-80, 80, (n, 3)) + [0, -100, 0]
    target = rng.uniform(-50, 50, (n, 3)) + [0, 45, 0]
    d = target - o
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    cache = GeometryCache()
    hits = surface_hits(scene, meshes, o, d, cache)
    corners = cache.geometry.corners(np.arange(len(cache.geometry.triangles)))
    t_ref, tri_ref = moller_trumbore(o, d, corners)
    both = np.isfinite(t_ref) & (hits["triangle"] >= 0)
    assert both.sum() > n // 3  # the rays do hit the meshes
    # The same rays hit and miss, except where a ray grazes an edge (single vs double precision).
    disagree = np.isfinite(t_ref) != (hits["triangle"] >= 0)
    assert disagree.sum() <= n // 1000, disagree.sum()
    np.testing.assert_allclose(hits["t"][both], t_ref[both], rtol=0, atol=1e-6 * 200)
    same = hits["triangle"][both] == tri_ref[both]
    # A different triangle only at a shared edge, at the same distance.
    assert same.mean() > 0.995

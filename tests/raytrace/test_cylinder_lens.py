"""The cylindrical lens: the curved cut walk against a brute-force test of every cell, hits that
re-intersect to nothing nearer, the outer cylinder and the curved body front on their surfaces,
a large radius converging to the flat lens, and the flat default unchanged."""

from __future__ import annotations

import copy
import json
import math
from pathlib import Path

import numpy as np
import pytest

from core_tracer.raytrace import paths as P
from core_tracer.raytrace.engine import render
from core_tracer.raytrace.lamp_table import CYLINDER_KEYS, LampTable
from core_tracer.raytrace.parts import body_box, cut_surface, cuts, cylinder_lens, flutes, sawtooth
from core_tracer.raytrace.parts.base import T_MIN, Segments
from core_tracer.raytrace.parts.cuts import INTO_AIR, INTO_LENS, OFF_CAP
from core_tracer.raytrace.parts.side_wall import hit_side_wall
from core_tracer.scene.derived import body_wraps, cut_sphere_radius, lens_cylinder
from core_tracer.scene.validate import normalize
from tests.helpers import baseline_doc

R, THICK, PITCH, HEIGHT = 45.0, 3.0, 9.0, 1.5


def _lamp(radius: float, side: str, pitch: float = PITCH, height: float = HEIGHT) -> dict:
    return {"lens": {"radius": R, "thickness": THICK, "shape": "cylindrical", "wrap_radius": radius,
                     "wrap_toward": side}, "cuts": {"pitch": pitch, "height": height}}


def _per_ray(cyl: dict, n: int) -> dict[str, np.ndarray]:
    return {k: np.full(n, float(cyl[k])) for k in CYLINDER_KEYS}


def _brute_force(o, d, cyl, pitch, rho, t_limit, on_cap, start_cell):
    """Every cell of the lens and beyond, each cap's sphere roots kept where they lie in their
    own cell (angle, height and the shell's radius): the nearest, per ray."""
    n = len(o)
    best = np.full(n, np.inf)
    base, apex, side, ax, rc = cyl["base"], cyl["apex"], cyl["side"], cyl["axis_x"], cyl["radius"]
    i_max = math.ceil(math.pi / 2 * base / pitch) + 2
    j_max = math.ceil(R / pitch) + 2
    for i in range(-i_max, i_max + 1):
        phi = cyl["phi_center"] + i * pitch / base
        e = np.array([side * math.sin(phi), -math.cos(phi), 0.0])
        for j in range(-j_max, j_max + 1):
            centre = np.array([ax, rc, j * pitch]) + (apex + rho) * e
            oc = o - centre
            b = np.einsum("ij,ij->i", oc, d)
            c = np.einsum("ij,ij->i", oc, oc) - rho * rho
            with np.errstate(invalid="ignore"):
                sq = np.sqrt(b * b - c)
            own = (on_cap != OFF_CAP) & (start_cell[:, 0] == i) & (start_cell[:, 1] == j)
            for k, t in enumerate((-b - sq, -b + sq)):
                if k == 0:
                    t = np.where(own, np.nan, t)  # the near root of its own sphere is the start
                else:
                    t = np.where(own & (on_cap == INTO_AIR), np.nan, t)
                p = o + np.where(np.isfinite(t), t, 0.0)[:, None] * d
                ph = np.arctan2(side * (p[:, 0] - ax), rc - p[:, 1])
                r = np.hypot(p[:, 0] - ax, p[:, 1] - rc)
                half = pitch / base / 2
                inside = ((np.abs(ph - phi) <= half + 1e-9) & (np.abs(p[:, 2] - j * pitch) <= pitch / 2 + 1e-9)
                          & (r <= cyl["corner"] + 1e-9))
                with np.errstate(invalid="ignore"):
                    ok = inside & (t > T_MIN) & (t < t_limit) & (t < best)
                best = np.where(ok, t, best)
    return best


def _limit(o, d, cyl):
    """The side wall, and the plane of the cylinder's axis: behind it lies the far side of the
    cylinder, which is no part of the lens (in a lamp the reflector closes the space before it)."""
    with np.errstate(divide="ignore"):
        t_axis = np.where(d[:, 1] > 0, (cyl["radius"] - o[:, 1]) / d[:, 1], np.inf)
    return np.minimum(hit_side_wall(o, d, np.full(len(o), R)), t_axis)


def _random_rays(rng, cyl, n):
    """Rays from points in and around the lens (inside the side wall, between the outer face and
    beyond the cuts), in random directions."""
    u = rng.uniform(-R, R, n)
    z = rng.uniform(-R, R, n)
    r = rng.uniform(cyl["apex"] - 6.0, cyl["radius"] - 0.01, n)
    keep = (u * u + z * z < R * R) & (np.abs(u - cyl["axis_x"]) < r)
    u, z, r = u[keep], z[keep], r[keep]
    phi = np.arcsin(cyl["side"] * (u - cyl["axis_x"]) / r)
    x = cyl["axis_x"] + cyl["side"] * r * np.sin(phi)
    y = cyl["radius"] - r * np.cos(phi)
    o = np.stack([x, y, z], axis=1)
    d = rng.normal(size=(len(u), 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    return o, d


@pytest.mark.slow
@pytest.mark.parametrize("side", ["+x", "-x"])
@pytest.mark.parametrize("pitch, height", [(9.0, 1.5), (6.0, 4.0), (12.0, 0.3)])
@pytest.mark.seed(12)
def test_the_curved_cut_walk_finds_what_testing_every_cell_finds(side, pitch, height, rng):
    cyl = lens_cylinder(_lamp(100.0, side, pitch, height))
    rho = cut_sphere_radius(pitch, height)
    o, d = _random_rays(rng, cyl, 4000)
    n = len(o)
    t_limit = _limit(o, d, cyl)
    on_cap = np.zeros(n, np.int8)
    t, _ = cylinder_lens.hit_cylinder_cuts(o, d, _per_ray(cyl, n), np.full(n, pitch), np.full(n, rho), t_limit, on_cap)
    brute = _brute_force(o, d, cyl, pitch, rho, t_limit, on_cap, np.full((n, 2), np.nan))
    assert np.isfinite(t).sum() > n // 5  # the rays do meet the cuts
    assert np.array_equal(np.isfinite(t), np.isfinite(brute))
    hit = np.isfinite(t)
    np.testing.assert_allclose(t[hit], brute[hit], rtol=0, atol=1e-7)


@pytest.mark.slow
@pytest.mark.parametrize("side", ["+x", "-x"])
@pytest.mark.seed(5)
def test_a_ray_leaving_a_curved_cut_finds_no_nearer_hit_and_not_its_own_cap(side, rng):
    cyl = lens_cylinder(_lamp(100.0, side))
    rho = cut_sphere_radius(PITCH, HEIGHT)
    o, d = _random_rays(rng, cyl, 6000)
    n = len(o)
    geo, pitch, rhos = _per_ray(cyl, n), np.full(n, PITCH), np.full(n, rho)
    t_limit = _limit(o, d, cyl)
    t, normal = cylinder_lens.hit_cylinder_cuts(o, d, geo, pitch, rhos, t_limit, np.zeros(n, np.int8))
    hit = np.nonzero(np.isfinite(t))[0]
    assert len(hit) > 500
    # nothing nearer: the same rays limited to just short of their hits find nothing
    t_short, _ = cylinder_lens.hit_cylinder_cuts(o[hit], d[hit], {k: v[hit] for k, v in geo.items()}, pitch[hit],
                                                 rhos[hit], t[hit] - 1e-6, np.zeros(len(hit), np.int8))
    assert np.isinf(t_short).all()
    # from the hit, reflected and transmitted-like directions: never the own cap again at ~0
    p = o[hit] + t[hit, None] * d[hit]
    nrm = normal[hit]
    for sign, code in ((1.0, INTO_AIR), (-1.0, INTO_LENS)):
        new_d = rng.normal(size=(len(hit), 3))
        new_d /= np.linalg.norm(new_d, axis=1)[:, None]
        new_d *= np.where(np.einsum("ij,ij->i", new_d, nrm) * sign >= 0, 1.0, -1.0)[:, None]
        m = len(hit)
        sub = {k: v[hit] for k, v in geo.items()}
        limit = _limit(p, new_d, cyl)
        t2, _ = cylinder_lens.hit_cylinder_cuts(p, new_d, sub, pitch[hit], rhos[hit], limit, np.full(m, code, np.int8))
        start_cell = cylinder_lens._cell_of(p, new_d, np.zeros(m), sub, pitch[hit])
        brute = _brute_force(p, new_d, cyl, PITCH, rho, limit, np.full(m, code, np.int8), start_cell)
        assert (t2 > 1e-6).all()
        assert np.array_equal(np.isfinite(t2), np.isfinite(brute))
        finite = np.isfinite(t2)
        np.testing.assert_allclose(t2[finite], brute[finite], rtol=0, atol=1e-7)


@pytest.mark.seed(3)
def test_the_cut_hits_lie_on_their_caps_and_the_normal_points_to_the_air(rng):
    cyl = lens_cylinder(_lamp(100.0, "+x"))
    rho = cut_sphere_radius(PITCH, HEIGHT)
    o, d = _random_rays(rng, cyl, 3000)
    n = len(o)
    t, normal = cylinder_lens.hit_cylinder_cuts(o, d, _per_ray(cyl, n), np.full(n, PITCH), np.full(n, rho),
                                                _limit(o, d, cyl), np.zeros(n, np.int8))
    hit = np.isfinite(t)
    p = o[hit] + t[hit, None] * d[hit]
    r = np.hypot(p[:, 0] - cyl["axis_x"], p[:, 1] - cyl["radius"])
    assert (r >= cyl["apex"] - 1e-9).all() and (r <= cyl["corner"] + 1e-9).all()
    # the air lies toward the cylinder axis: the normal's radial part points inward
    radial = np.stack([p[:, 0] - cyl["axis_x"], p[:, 1] - cyl["radius"]], axis=1) / r[:, None]
    assert (np.einsum("ij,ij->i", normal[hit][:, :2], radial) < 0).all()
    np.testing.assert_allclose(np.linalg.norm(normal[hit], axis=1), 1.0, atol=1e-12)


@pytest.mark.seed(4)
def test_a_smooth_inner_face_is_the_base_cylinder(rng):
    cyl = lens_cylinder(_lamp(120.0, "-x", height=0.0))
    o, d = _random_rays(rng, cyl, 2000)
    n = len(o)
    t, normal = cylinder_lens.hit_cylinder_cuts(o, d, _per_ray(cyl, n), np.full(n, PITCH), np.full(n, np.inf),
                                                np.full(n, np.inf), np.zeros(n, np.int8))
    hit = np.isfinite(t)
    p = o[hit] + t[hit, None] * d[hit]
    np.testing.assert_allclose(np.hypot(p[:, 0] - cyl["axis_x"], p[:, 1] - cyl["radius"]), cyl["base"], atol=1e-9)


@pytest.mark.seed(6)
def test_the_outer_cylinder_is_met_from_inside_on_the_cylinder(rng):
    cyl = lens_cylinder(_lamp(100.0, "+x"))
    o, d = _random_rays(rng, cyl, 2000)
    n = len(o)
    t, normal = cylinder_lens.hit_outer_cylinder(o, d, np.full(n, cyl["axis_x"]), np.full(n, cyl["radius"]),
                                                 np.zeros(n, bool))
    assert np.isfinite(t).all() and (t > 0).all()
    p = o + t[:, None] * d
    np.testing.assert_allclose(np.hypot(p[:, 0] - cyl["axis_x"], p[:, 1] - cyl["radius"]), cyl["radius"], atol=1e-9)
    assert (np.einsum("ij,ij->i", normal, d) > 0).all()  # leaving: along the outward normal
    # from the hit point, heading back in (reflected), the face is met only across the cylinder
    back = d - 2 * np.einsum("ij,ij->i", d, normal)[:, None] * normal
    t2, _ = cylinder_lens.hit_outer_cylinder(p, back, np.full(n, cyl["axis_x"]), np.full(n, cyl["radius"]),
                                             np.ones(n, bool))
    finite = np.isfinite(t2)
    assert (t2[finite] > 1e-3).all()


def _wrap_scene(radius: float = 100.0) -> dict:
    doc = baseline_doc()
    lamp = doc["lamps"][0]
    lamp["lens"].update({"shape": "cylindrical", "wrap_radius": radius, "wrap_toward": "+x"})
    doc["body"]["center"] = [-5, 0]  # the side at x = 54, short of the quarter turn (x = 55)
    doc["body"]["size"] = [118, 120]
    doc["body"]["depth"] = 160
    doc["image"] = {"width": 96, "height": 96}
    return doc


@pytest.mark.seed(8)
def test_the_body_front_curves_on_its_cylinder_and_rays_enter_it_from_outside(rng):
    scene = normalize(_wrap_scene())
    (side, x_t, radius), = body_wraps(scene)
    assert (side, x_t, radius) == (1.0, -R, 100.0)
    lo, hi = body_box.body_box(scene["body"])
    target = np.stack([rng.uniform(-70, 70, 5000), rng.uniform(0, 60, 5000), rng.uniform(-70, 70, 5000)], axis=1)
    o = np.array([300.0, -400.0, 50.0]) + rng.normal(size=(5000, 3)) * 20
    d = target - o
    d /= np.linalg.norm(d, axis=1)[:, None]
    t, hit, face, normal = body_box.hit_body(o, d, lo, hi, [(side, x_t, radius)])
    curved = hit & (face == body_box.CURVED_FRONT)
    assert curved.sum() > 200
    p = o[curved] + t[curved, None] * d[curved]
    np.testing.assert_allclose(np.hypot(p[:, 0] - x_t, p[:, 1] - radius), radius, atol=1e-9)
    assert (p[:, 0] >= x_t).all() and (np.einsum("ij,ij->i", normal[curved], d[curved]) < 0).all()
    # nothing nearer: points a little before every hit lie outside the body (in front of the panel)
    for frac in (0.999, 0.5):
        q = o[hit] + (t[hit] * frac)[:, None] * d[hit]
        u = np.maximum(q[:, 0] - x_t, 0)
        with np.errstate(invalid="ignore"):
            f = radius - np.sqrt(radius * radius - u * u)
        outside_box = ((q < lo - 1e-9) | (q > hi + 1e-9)).any(axis=1)
        assert (outside_box | (q[:, 1] < f) | np.isnan(f)).all()


@pytest.mark.slow
def test_a_flat_lens_that_names_the_cylinder_fields_renders_the_default_image_bit_for_bit():
    plain = baseline_doc()
    plain["image"] = {"width": 64, "height": 64}
    named = copy.deepcopy(plain)
    named["lamps"][0]["lens"].update({"shape": "flat", "wrap_radius": 250.0, "wrap_toward": "-x"})
    assert np.array_equal(render(normalize(plain)), render(normalize(named)))


@pytest.mark.slow
def test_a_large_wrap_radius_converges_to_the_flat_lens_image():
    flat = _wrap_scene()
    flat["lamps"][0]["lens"]["shape"] = "flat"
    reference = render(normalize(flat))
    scale = float(np.mean(reference))
    diffs = []
    for radius in (1.0e3, 1.0e4):
        image = render(normalize(_wrap_scene(radius)))
        diffs.append(float(np.mean(np.abs(image - reference))) / scale)
    # the deviation falls with the radius (the lens's sag across it goes as 1 / radius)
    assert diffs[1] < diffs[0] / 3
    assert diffs[1] < 0.01, diffs


@pytest.mark.parametrize("edit, field, allowed", [
    (lambda d: d["lamps"][0]["lens"].update(wrap_radius=90.0), "lamps[0].lens.wrap_radius", "(94.5, 1e+04] mm"),
    (lambda d: d["lamps"][0]["cuts"].update(pitch=9.0, height=6.3), "lamps[0].cuts.height", "allowed [0, "),
    (lambda d: d["body"].update(size=[124, 120]), "body.size", "allowed width below 120 mm"),
    # the curved base is walked as the fish-eye grid only: saw-tooth and flutes need a flat lens
    (lambda d: d["lamps"][0]["cuts"].update(type="sawtooth"), "lamps[0].cuts.type", 'allowed "fisheye"'),
    (lambda d: d["lamps"][0]["cuts"].update(type="flutes"), "lamps[0].cuts.type", 'allowed "fisheye"'),
])
def test_bad_cylindrical_lenses_are_refused_naming_the_field(edit, field, allowed):
    from core_tracer.scene import SceneError
    doc = _wrap_scene()
    edit(doc)
    with pytest.raises(SceneError) as err:
        normalize(doc)
    assert str(err.value).startswith(field) and allowed in str(err.value)


def test_a_flat_lens_on_the_curved_front_is_refused():
    from core_tracer.scene import SceneError
    doc = _wrap_scene()
    doc["body"]["size"] = [118, 320]
    other = copy.deepcopy(doc["lamps"][0])
    other["lens"]["shape"] = "flat"
    other["center"] = [0, 100]
    doc["lamps"].append(other)
    with pytest.raises(SceneError, match=r"^lamps\[1\]\.center: .* curved front"):
        normalize(doc)


@pytest.mark.slow
def test_every_transition_through_a_cylindrical_lens_is_in_table_1():
    from core_tracer.raytrace import paths
    from core_tracer.raytrace.engine import render_passes
    scene = normalize(_wrap_scene())
    scene["camera"] = {**scene["camera"], "position": [400.0, -900.0, 120.0], "target": [0.0, 20.0, 0.0]}
    result = render_passes(scene, 96, 96, record_transitions=True)
    seen = result.stats["transitions"]
    assert {child for _, _, child in seen} >= {2, 3, 6, 8, 9, 10, 11}
    assert [t for t in seen if not paths.allowed(*t)] == []
    assert np.all(np.isfinite(result.image)) and np.all(result.image >= 0)


def test_the_panel_hint_gives_the_smallest_wrap_radius_validation_allows():
    from core_tracer.scene import SceneError
    from core_tracer.scene.limits import lamp_limits
    doc = normalize(_wrap_scene())
    hint = lamp_limits(doc, 0)["lens.wrap_radius"]
    assert hint.startswith("more than 94.5 mm")
    for radius, ok in ((94.5, False), (94.51, True)):
        trial = copy.deepcopy(doc)
        trial["lamps"][0]["lens"]["wrap_radius"] = radius
        trial["body"]["size"] = [2 * R + 8, 120]  # the side short of the quarter turn for both
        trial["body"]["center"] = [-1, 0]
        if ok:
            normalize(trial)
        else:
            with pytest.raises(SceneError, match=r"^lamps\[0\]\.lens\.wrap_radius"):
                normalize(trial)


@pytest.mark.slow
def test_a_lens_wrapping_toward_minus_x_renders_the_mirror_image_of_one_wrapping_toward_plus_x():
    plus = _wrap_scene()
    plus["camera"] = {"position": [300.0, -900.0, 80.0], "target": [0.0, 20.0, 0.0], "up": [0, 0, 1],
                      "fov_deg": 14.0}
    plus["light"]["direction"] = [0.3, -1.0, 0.6]
    minus = copy.deepcopy(plus)
    minus["lamps"][0]["lens"]["wrap_toward"] = "-x"
    minus["body"]["center"] = [5, 0]
    minus["camera"]["position"][0] = -300.0
    minus["light"]["direction"] = [-0.3, -1.0, 0.6]
    a, b = render(normalize(plus)), render(normalize(minus))
    assert float(np.mean(a)) > 0.01
    # the pixel grid mirrors exactly; a ray and its mirror differ by rounding only, which the
    # lens's chaotic internal reflections amplify in a few pixels
    diff = np.abs(a - b[:, ::-1])
    assert float(np.mean(diff)) < 1e-3 * float(np.mean(a))
    assert float(np.mean(diff > 1e-3 * float(a.max()))) < 0.01


@pytest.mark.slow
def test_surroundings_light_and_surround_a_wrapped_body(tmp_path):
    # Under a uniform world W with the sun off, a Lambertian body shows rho W on its flat and its
    # curved front alike, and the rays that miss see W (docs/model.md: surroundings; cylindrical lens).
    from core_tracer import render_passes
    from tests.helpers import write_exr

    # the irradiance integral's full grid: a uniform world of 128 x 64 pixels
    path = write_exr(tmp_path / "grey.exr", np.full((64, 128, 3), 0.3))
    doc = _wrap_scene()
    doc["environment"] = {"world": "file", "file": path}
    doc["light"].update(ambient=0.0, strength=0.0)
    doc["body"]["specular"] = 0.0
    doc["camera"] = {"position": [300.0, -500.0, 80.0], "target": [0.0, 0.0, 0.0], "fov_deg": 30.0}
    scene = normalize(doc)
    result = render_passes(scene)
    body = result.passes["body"].reshape(-1, 3)
    seen = body[body.max(axis=1) > 0]
    assert len(seen) > 500
    np.testing.assert_allclose(seen, np.broadcast_to(0.3 * np.array(scene["body"]["color"]), seen.shape), rtol=1e-3)
    others = sum(v for name, v in result.passes.items() if name != "background").reshape(-1, 3)
    missed = result.image.reshape(-1, 3)[others.max(axis=1) == 0]
    assert len(missed) > 500
    np.testing.assert_allclose(missed, 0.3, rtol=1e-6)


@pytest.mark.seed(7)
def test_the_cut_dispatch_gives_each_ray_its_own_lamps_walk(rng):
    """``cut_surface`` on a scene with all four cut walks (fish-eye on a flat lens, fish-eye on a
    cylindrical lens, saw-tooth, flutes): every ray gets exactly what its lamp's walk alone gives."""
    doc = json.loads((Path(__file__).resolve().parents[2] / "presets" / "four-lamp-rear-combination.json").read_text())
    doc["body"]["depth"] = 100.0
    doc["lamps"][3]["lens"].update(shape="cylindrical", wrap_radius=110.0, wrap_toward="+x")
    doc["lamps"][1]["cuts"].update(type="sawtooth", tooth_angle=25.0, orientation=0.0)
    doc["lamps"][2]["cuts"].update(type="flutes", orientation=30.0)
    lamps = LampTable.from_scene(normalize(doc))
    n = 4000
    lamp = rng.integers(0, 4, n)
    o = np.stack([rng.uniform(-30, 30, n), rng.uniform(-2.0, 12.0, n), rng.uniform(-30, 30, n)], axis=1)
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    src = np.where(rng.random(n) < 0.5, P.CUT, P.REFLECTOR).astype(np.int8)
    medium = np.where(rng.random(n) < 0.5, P.IN_AIR, P.IN_LENS).astype(np.int8)
    t_limit = np.where(rng.random(n) < 0.8, np.inf, rng.uniform(0.0, 20.0, n))
    t, normal = cut_surface.intersect(Segments(o, d, lamp, src, medium), lamps, t_limit)
    on_cap = np.where(src != P.CUT, OFF_CAP, np.where(medium == P.IN_AIR, INTO_AIR, INTO_LENS)).astype(np.int8)
    for li in range(4):
        k = np.nonzero(lamp == li)[0]
        ls = lamp[k]
        if li == 1:
            t_own, n_own = sawtooth.hit_sawtooth(o[k], d[k], lamps.plane_a[ls], lamps.plane_b[ls], lamps.pitch[ls],
                                                 lamps.tooth_slope[ls], lamps.ridge_across[ls], t_limit[k])
        elif li == 2:
            t_own, n_own = flutes.hit_flutes(o[k], d[k], lamps.plane_a[ls], lamps.plane_b[ls], lamps.pitch[ls],
                                             lamps.flute_radius[ls], lamps.ridge_across[ls], t_limit[k], on_cap[k])
        elif li == 3:
            t_own, n_own = cylinder_lens.hit_cylinder_cuts(o[k], d[k], lamps.cylinder_of(ls), lamps.pitch[ls],
                                                           lamps.cut_radius[ls], t_limit[k], on_cap[k])
        else:
            t_own, n_own = cuts.hit_cuts(o[k], d[k], lamps.plane_a[ls], lamps.plane_b[ls], lamps.pitch[ls],
                                         lamps.cut_radius[ls], t_limit[k], on_cap[k])
        assert np.isfinite(t_own).sum() > 50, li  # each walk finds hits here
        assert np.array_equal(t[k], t_own), li
        hit = np.isfinite(t_own)
        assert np.array_equal(normal[k][hit], n_own[hit]), li

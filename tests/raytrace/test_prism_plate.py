"""The prism plate (docs/model.md, the prism plate): the ring walk against every ring, re-intersection
from a hit, the closed form of the Fresnel-lens design, its path classes, its validation."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import BASELINE

from core_tracer import load_scene, render_passes
from core_tracer.raytrace import optics, paths
from core_tracer.raytrace.parts import plate_front, prism_rings
from core_tracer.scene import SceneError, lamp_geometry
from core_tracer.scene.prism_profile import MAX_FACET_INCIDENCE_DEG, facet_incidence_deg, ring_slopes
from core_tracer.scene.validate import normalize

R, PITCH, FOCAL, IOR = 45.0, 2.0, 50.0, 1.49
Y_A = 10.0


def _plate(radius=R, pitch=PITCH, focal=FOCAL, ior=IOR):
    slopes = ring_slopes(radius, pitch, focal, ior)
    return slopes, Y_A + float(slopes.max()) * pitch


def _walk(o, d, slopes, y_b, radius=R, pitch=PITCH, on_rings=None, t_limit=None):
    n = len(o)
    return prism_rings.hit_rings(o, d, np.full(n, Y_A), np.full(n, y_b), np.full(n, pitch), np.full(n, radius),
                                 slopes[None, :], np.zeros(n, np.int64), np.full(n, len(slopes)),
                                 np.full(n, np.inf) if t_limit is None else t_limit, on_rings)


def _random_rays(rng, n, y_lo, y_hi, radius=R):
    r = radius * np.sqrt(rng.random(n))
    th = rng.random(n) * 2 * np.pi
    o = np.stack([r * np.cos(th), y_lo + (y_hi - y_lo) * rng.random(n), r * np.sin(th)], axis=1)
    d = rng.normal(size=(n, 3))
    return o, d / np.linalg.norm(d, axis=1)[:, None]


@pytest.mark.parametrize("pitch, focal, ior", [(2.0, 50.0, 1.49), (0.7, 60.0, 1.59), (9.0, 55.0, 1.49)])
@pytest.mark.seed(12)
def test_ring_walk_agrees_with_every_ring_tested(pitch, focal, ior, rng):
    slopes, y_b = _plate(pitch=pitch, focal=focal, ior=ior)
    # from inside the plate, from behind it, and from inside the slab of the rings
    o = np.concatenate([_random_rays(rng, 4000, Y_A - 2.0, Y_A, )[0], _random_rays(rng, 4000, y_b, y_b + 40)[0],
                        _random_rays(rng, 4000, Y_A, y_b)[0]])
    d = _random_rays(rng, len(o), 0, 1)[1]
    t, _ = _walk(o, d, slopes, y_b, pitch=pitch)
    brute = prism_rings.brute_force_rings(o, d, Y_A, pitch, R, slopes)
    same = np.isclose(t, brute, rtol=1e-9, atol=1e-9) | (np.isinf(t) & np.isinf(brute))
    assert same.all(), np.c_[t, brute][~same][:5]
    assert np.isfinite(t).sum() > 3000  # the rays do meet the rings


@pytest.mark.seed(21)
def test_ring_walk_agrees_with_every_ring_tested_when_every_ray_walks(rng):
    # Rays that all start between planes A and B (on the rings, as most rays the walk sees do):
    # the walk takes them all without gathering them, and still finds what testing every ring finds.
    slopes, y_b = _plate()
    o, d = _random_rays(rng, 6000, Y_A, y_b)
    n = len(o)
    entered = prism_rings._enter(o, d, np.full(n, Y_A), np.full(n, y_b), np.full(n, PITCH), np.full(n, R),
                                 np.full(n, len(slopes)), np.full(n, np.inf))
    assert entered[0] is None  # the branch that walks every ray
    t, _ = _walk(o, d, slopes, y_b)
    brute = prism_rings.brute_force_rings(o, d, Y_A, PITCH, R, slopes)
    same = np.isclose(t, brute, rtol=1e-9, atol=1e-9) | (np.isinf(t) & np.isinf(brute))
    assert same.all(), np.c_[t, brute][~same][:5]
    assert np.isfinite(t).sum() > 3000


@pytest.mark.seed(3)
def test_ring_walk_stops_at_its_limit(rng):
    slopes, y_b = _plate()
    o, d = _random_rays(rng, 3000, y_b, y_b + 30)
    free, _ = _walk(o, d, slopes, y_b)
    limit = 0.5 * np.where(np.isfinite(free), free, 100.0)
    t, _ = _walk(o, d, slopes, y_b, t_limit=limit)
    assert np.isinf(t).all()


def test_ring_walk_visits_a_few_rings_not_all():
    # A ray from the focus crosses the ring slab within one or two rings: the walk's steps are
    # bounded by the rings crossed, whatever their number.
    slopes, y_b = _plate(pitch=0.1)
    assert len(slopes) == 450
    o = np.tile([0.0, Y_A + FOCAL, 0.0], (200, 1))
    ang = np.linspace(0.0, 0.7, 200)
    d = np.stack([np.sin(ang), -np.cos(ang), np.zeros(200)], axis=1)
    entry = o[:, 1] - y_b
    exit_ = o[:, 1] - Y_A
    crossed = np.floor(exit_ * np.tan(ang) / 0.1) - np.floor(entry * np.tan(ang) / 0.1) + 1
    assert crossed.max() <= 3
    t, _ = _walk(o, d, slopes, y_b, pitch=0.1)
    assert np.isfinite(t).all()


@pytest.mark.seed(5)
def test_reintersecting_from_a_hit_finds_no_closer_hit(rng):
    slopes, y_b = _plate()
    o, d = _random_rays(rng, 20000, y_b, y_b + 40)
    t, normal = _walk(o, d, slopes, y_b)
    hit = np.isfinite(t)
    p = o[hit] + t[hit, None] * d[hit]
    d_hit, n_hit = d[hit], normal[hit]
    facing = np.where((optics.dot(d_hit, n_hit) < 0)[:, None], n_hit, -n_hit)
    eta = 1.0 / IOR
    cos_i = -optics.dot(d_hit, facing)
    inside = eta * eta * (1 - cos_i * cos_i) < 1
    for name, direction in (("reflected", optics.reflect(d_hit, facing)),
                            ("transmitted", optics.refract(d_hit, facing, eta)), ("continued", d_hit)):
        keep = inside if name == "transmitted" else np.ones(len(p), bool)
        t2, _ = _walk(p[keep], direction[keep], slopes, y_b, on_rings=np.ones(int(keep.sum()), bool))
        # brute force from the hit, its own element excluded by distance: the walk never reports
        # a hit nearer than that, and agrees with it away from grazing starts
        brute = prism_rings.brute_force_rings(p[keep] + 1e-7 * direction[keep], direction[keep], Y_A, PITCH, R,
                                              slopes) + 1e-7
        assert np.all(t2 > 1e-6), name
        same = np.isclose(t2, brute, rtol=1e-6, atol=1e-5) | (np.isinf(t2) & np.isinf(brute))
        assert np.mean(~same) < 1e-3, (name, np.c_[t2, brute][~same][:5])


def _through_plate(ang: np.ndarray, slopes: np.ndarray, pitch=PITCH, focal=FOCAL, ior=IOR):
    """Rays from the focus at angles ``ang`` from the axis, refracted by the ring face and the flat
    front face: their directions out of the plate and the ring each crossed."""
    n = len(ang)
    y_b = Y_A + float(slopes.max()) * pitch
    o = np.tile([0.0, Y_A + focal, 0.0], (n, 1))
    d = np.stack([np.sin(ang), -np.cos(ang), np.zeros(n)], axis=1)
    t, normal = _walk(o, d, slopes, y_b, pitch=pitch)
    assert np.isfinite(t).all()
    p = o + t[:, None] * d
    inside = optics.refract(d, normal, 1.0 / ior)  # the normal points out of the plate, toward the bulb
    t_front = plate_front.hit_plate_front(p, inside, np.full(n, Y_A - 2.0), np.full(n, R), np.ones(n, bool))
    out = optics.refract(inside, -plate_front.NORMAL[None, :].repeat(n, 0), ior)
    out[~np.isfinite(t_front)] = np.nan  # (through a draft face and out at the rim)
    return out, np.floor(np.hypot(p[:, 0], p[:, 2]) / pitch).astype(int), p


def test_the_design_ray_of_every_ring_leaves_exactly_parallel_to_the_axis():
    slopes, _ = _plate()
    mid = (np.arange(len(slopes)) + 0.5) * PITCH
    y_mid = Y_A + 0.5 * slopes * PITCH  # the facet's mid-radius point
    ang = np.arctan2(mid, Y_A + FOCAL - y_mid)
    out, ring, _ = _through_plate(ang, slopes)
    np.testing.assert_array_equal(ring, np.arange(len(slopes)))
    off_axis = np.degrees(np.arctan2(np.hypot(out[:, 0], out[:, 2]), -out[:, 1]))
    assert off_axis.max() < 1e-9


def test_every_ray_from_the_focus_leaves_parallel_to_within_the_ring_discretisation():
    # The bound (docs/model.md): a ray from the focus leaves the plate at most as far from the axis as the
    # angle between it and its ring's design ray, seen from the focus (to first order the exit
    # angle is that difference times cos(incidence) / cos(refraction) < 1 at the facet).
    slopes, _ = _plate()
    ang = np.linspace(0.0, math.atan(44.0 / (FOCAL + 1.0)), 5000)
    out, ring, p = _through_plate(ang, slopes)
    mid = (ring + 0.5) * PITCH
    design = np.arctan2(mid, Y_A + FOCAL - (Y_A + 0.5 * slopes[ring] * PITCH))
    off_axis = np.arctan2(np.hypot(out[:, 0], out[:, 2]), -out[:, 1])
    hit_facet = np.abs(p[:, 1] - (Y_A + slopes[ring] * ((ring + 1) * PITCH - np.hypot(p[:, 0], p[:, 2])))) < 1e-9
    assert np.isfinite(out[hit_facet]).all()
    assert hit_facet.mean() > 0.6  # the rest meet a draft face (vertical: it shadows the next facet)
    bound = np.abs(ang - design)[hit_facet]
    assert np.all(off_axis[hit_facet] <= bound + 1e-12)
    # half a ring's width as seen from the focus: under 1.2 degrees for 2 mm rings at 50 mm
    assert np.degrees(off_axis[hit_facet].max()) < 1.2


def test_profile_is_the_fixed_point_of_the_design():
    slopes = ring_slopes(R, PITCH, FOCAL, IOR)
    mid = (np.arange(len(slopes)) + 0.5) * PITCH
    dy = 0.5 * slopes * PITCH - FOCAL
    u_r, u_y = mid / np.hypot(mid, dy), dy / np.hypot(mid, dy)
    np.testing.assert_allclose(slopes, u_r / (IOR + u_y), rtol=1e-13)
    assert np.all(np.diff(slopes) > 0)  # steeper toward the rim
    assert facet_incidence_deg(R, PITCH, FOCAL, IOR).max() <= MAX_FACET_INCIDENCE_DEG


def _prism_scene(**plate):
    scene = load_scene(BASELINE)
    scene["lamps"][0]["collection"] = "prism_plate"
    scene["lamps"][0]["prism_plate"].update(plate)
    return normalize(scene)


@pytest.mark.slow
def test_prism_plate_lamp_renders_through_its_table():
    scene = _prism_scene()
    result = render_passes(scene, 96, 96, record_transitions=True)
    seen = result.stats["transitions"]
    assert not [t for t in seen if not paths.allowed(*t)]
    assert {c for *_, c in seen} >= set(range(13, 20)) | {6, 7, 11, 12}
    assert not {c for *_, c in seen} & {3, 4, 5}  # no reflector
    assert not result.passes["reflector_constant"].any() and not result.passes["reflector_scatter"].any()
    np.testing.assert_allclose(sum(result.passes.values()), result.image, rtol=1e-6, atol=1e-7)
    assert np.isfinite(result.image).all() and (result.image >= 0).all()


@pytest.mark.slow
def test_prism_plate_sends_the_bulb_straight_through_to_an_eye_on_the_axis():
    # An orthographic eye on the axis: parallel rays through a flat clear lens and the plate all
    # converge on the focus, so the whole plate shows the bulb, except where they meet a draft.
    scene = _prism_scene()
    lamp = scene["lamps"][0]
    lamp["cuts"]["height"] = 0.0
    lamp["lens"].update(absorption=[0.0, 0.0, 0.0], diffuse_color=[0.0, 0.0, 0.0], specular=0.0)
    scene["camera"].update(type="orthographic", width=100.0, position=[0.0, -800.0, 0.0], target=[0.0, 0.0, 0.0])
    result = render_passes(normalize(scene), 101, 101)
    bulb = result.passes["bulb"][..., 0] / lamp["bulb"]["intensity"][0]
    yy, xx = np.mgrid[-50:51, -50:51] * (100.0 / 101)
    plate = np.hypot(xx, yy) < 40.0
    assert np.mean(bulb[plate] > 0.5) > 0.95
    # on the axis: four faces at normal incidence, the slab formula for lens and plate together
    r = ((1.49 - 1) / (1.49 + 1)) ** 2
    assert bulb[50, 50] == pytest.approx((1 - r) ** 4, rel=0.02)


def test_switching_collection_back_renders_the_reflector_lamp_bit_for_bit():
    base = load_scene(BASELINE)
    explicit = load_scene(BASELINE)
    explicit["lamps"][0]["collection"] = "reflector"
    explicit["lamps"][0]["prism_plate"]["focal_length"] = 70.0  # unused by a reflector lamp
    a = render_passes(base, 48, 32).image
    b = render_passes(normalize(explicit), 48, 32).image
    np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("change, field, text", [
    ({"focal_length": 30.0}, "lamps[0].prism_plate.focal_length", "allowed [49.09, 1000] mm"),
    ({"pitch": 50.0}, "lamps[0].prism_plate.pitch", "allowed [0.09, 45] mm"),
    ({"pitch": 0.05}, "lamps[0].prism_plate.pitch", "is too fine"),
    ({"housing_depth": 75.0}, "lamps[0].prism_plate.housing_depth", "allowed (0, 69.5] mm, or body.depth"),
    ({"housing_depth": 50.0}, "lamps[0].bulb.offset", "through the housing; allowed y in"),
    ({"ior": 1.001}, "lamps[0].prism_plate.ior", "too weak"),
])
def test_bad_prism_plates_are_refused_naming_the_field_and_the_allowed_range(change, field, text):
    with pytest.raises(SceneError) as err:
        _prism_scene(**change)
    assert str(err.value).startswith(field + ":")
    assert text in str(err.value)


@pytest.mark.parametrize("lens, field", [
    ({"outline": "rectangular", "width": 90.0, "height": 60.0}, "lamps[0].lens.outline"),
    ({"shape": "cylindrical", "wrap_radius": 300.0}, "lamps[0].lens.shape"),
])
def test_a_prism_plate_needs_a_round_flat_lens(lens, field):
    # the rings are circles about the lamp axis behind a flat lens (docs/model.md, the prism plate)
    scene = load_scene(BASELINE)
    scene["lamps"][0]["collection"] = "prism_plate"
    scene["lamps"][0]["lens"].update(lens)
    with pytest.raises(SceneError) as err:
        normalize(scene)
    assert str(err.value).startswith(field + ":") and "allowed" in str(err.value)


def test_bulb_reaching_into_the_plate_is_refused():
    scene = _prism_scene()
    scene["lamps"][0]["bulb"]["offset"] = [0.0, -46.0, 0.0]
    with pytest.raises(SceneError, match=r"^lamps\[0\]\.bulb\.offset: .* into the prism plate; allowed y in"):
        normalize(scene)


def test_geometry_of_a_prism_plate_lamp():
    scene = _prism_scene()
    g = lamp_geometry(scene["lamps"][0])
    assert g["plate_front"] == 3.0 + 1.5 + 4.0
    assert g["plate_base"] == g["plate_front"] + 2.0
    assert g["focus"] == g["plate_base"] + 50.0 and g["bulb_center"] == (0.0, g["focus"], 0.0)
    assert g["vertex"] == g["plate_base"] + 60.0
    assert g["plate_base"] < g["plate_peak"] < g["plate_base"] + 2.0


def test_limits_shown_beside_a_prism_plate_lamps_sliders():
    from core_tracer.scene.limits import lamp_limits

    scene = _prism_scene()
    limits = lamp_limits(scene, 0)
    assert limits["prism_plate.focal_length"] == "at least 49.09 mm for this radius, pitch and ior"
    g = lamp_geometry(scene["lamps"][0])
    low, high = (float(x) for x in limits["bulb.offset"][len("y in ["):-len("] mm")].split(", "))
    assert low == pytest.approx(g["plate_peak"] + 8.0 - g["focus"], abs=0.01)  # 4 digits, rounded inward
    assert high == pytest.approx(g["vertex"] - 8.0 - g["focus"], abs=0.01)
    assert "bulb.radius" in limits and "reflector" not in " ".join(limits)


def test_the_bulb_offset_range_is_shown_without_rounding_noise():
    # the bulb's back touches the housing's back at offset 0: the range ends at 0, not at -7e-15
    scene = load_scene(BASELINE)
    scene["lamps"][0]["collection"] = "prism_plate"
    scene["lamps"][0]["cuts"]["height"] = 0.6
    scene["lamps"][0]["prism_plate"]["housing_depth"] = 58.0
    with pytest.raises(SceneError, match=r"through the housing; allowed y in \(-40\.2, 0\) mm$"):
        normalize(scene)


@pytest.mark.slow
def test_a_study_varies_the_prism_plates_fields():
    from core_tracer.study.parameters import apply_value, resolve_parameter, study_parameters

    assert {"prism_plate.focal_length", "prism_plate.pitch", "prism_plate.ior"} <= set(study_parameters())
    base = _prism_scene()
    means = []
    for pitch in (1.0, 2.0):
        scene = normalize(base)
        apply_value(scene, resolve_parameter("prism_plate.pitch", scene), pitch)
        means.append(render_passes(normalize(scene), 48, 48).image.mean())
    assert means[0] != means[1]  # the rings change the image

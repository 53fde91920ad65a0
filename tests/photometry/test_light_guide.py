"""The light guide (docs/photometric.md, light guides): its geometry against brute force, and the
flux through a clear guide against its closed form."""

from __future__ import annotations

import copy
import json
import math
from pathlib import Path

import numpy as np
import pytest

from core_tracer.measures.guide_flux import far_end_flux
from core_tracer.raytrace.engine import make_context
from core_tracer.raytrace.parts import light_guide
from core_tracer.raytrace.parts.base import Segments
from core_tracer.scene.validate import parse_scene

ROOT = Path(__file__).resolve().parents[2]


def guide_scene(**guide) -> dict:
    """The photometric tail lamp lit by an LED and a light guide behind its lens (``on``: the lamp's switch)."""
    scene = json.loads((ROOT / "presets" / "photometric-tail-lamp.json").read_text())
    lamp = scene["lamps"][0]
    lamp["reflector"]["focal_length"] = 10.0
    settings = dict(enabled=True, section="rectangular", width=4.0, thickness=4.0, length=60.0, depth=15.0,
                    prism_depth=0.0, material="pmma", filter="custom", filter_edge_nm=500.0, filter_slope_nm=40.0,
                    filter_range=[0.90, 0.97], filter_thickness=10.0)
    settings.update(guide)
    lamp["light_guide"] = settings
    # the lamp's LED: one 1 mm die of 20 lm facing the first end face, 0.1 µm from it
    lamp["source"] = "led"
    lamp["led"] = dict(position=[-settings["length"] / 2 - 1e-4, settings["depth"], 0.0], normal=[1.0, 0.0, 0.0],
                       die_size=[1.0, 1.0], flux_lm=20.0, spectrum="red_led")
    return parse_scene(scene)


def fresnel_sp(cos_i: np.ndarray, n1: float, n2: float) -> tuple[np.ndarray, np.ndarray]:
    """The s and p reflectances (Hecht, Optics, 5th ed., eqs. 4.34 and 4.40); 1 in total reflection."""
    sin_t = n1 / n2 * np.sqrt(1.0 - cos_i**2)
    cos_t = np.sqrt(np.clip(1.0 - sin_t**2, 0.0, None))
    rs = ((n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t)) ** 2
    rp = ((n1 * cos_t - n2 * cos_i) / (n1 * cos_t + n2 * cos_i)) ** 2
    total = sin_t >= 1.0
    return np.where(total, 1.0, rs), np.where(total, 1.0, rp)


def closed_form_out(scene: dict) -> float:
    """Flux (lm) out of the far end of a clear guide lit by a Lambertian die at its first end:

        Φ_out = Σ_λ Φ(λ) ∫₀^{π/2} 2 sin θ cos θ Σ_{s,p} ½ T(θ)² a / (1 − R(θ)² a²) dθ,

    a = exp(−α(λ) L / cos θ') the internal transmittance along the rod at the refracted angle θ'
    (sin θ' = sin θ / n(λ)); T = 1 − R the transmittance of each end face, the same from inside at θ'
    as from the air at θ (Stokes), the geometric series the light reflected back and forth between
    the end faces. Every ray that enters is trapped: θ' ≤ θ_c, so the side walls meet it at ≥ 90° − θ_c
    > θ_c (n > √2)."""
    ctx = make_context(scene, 1, 1)
    lamps, guide = ctx.lamps, ctx.lamps.guide
    n_bands = lamps.plate_ior_bands[0]
    alpha = lamps.plate_absorption[0]
    area = 4.0 * lamps.led_half[0, 0] * lamps.led_half[0, 1] * 1e-6  # m²
    flux_lm = math.pi * lamps.led_radiance[0] * area * ctx.photometric.to_xyz[:, 1]  # lm per band: Φ = π L A
    theta = (np.arange(20000) + 0.5) * (0.5 * math.pi / 20000)
    weight = 2.0 * np.sin(theta) * np.cos(theta) * (0.5 * math.pi / 20000)
    out = 0.0
    for n, a_mm, lm in zip(n_bands, alpha, flux_lm, strict=True):
        cos_t = np.sqrt(1.0 - (np.sin(theta) / n) ** 2)
        a = np.exp(-a_mm * guide.length[0] / cos_t)
        per_angle = 0.0
        for r in fresnel_sp(np.cos(theta), 1.0, n):
            per_angle = per_angle + 0.5 * (1.0 - r) ** 2 * a / (1.0 - r**2 * a**2)
        out += lm * float((weight * per_angle).sum())
    return out


@pytest.mark.slow
def test_a_clear_guide_passes_its_closed_form_flux():
    scene = guide_scene()
    expected = closed_form_out(scene)
    measured = far_end_flux(scene, photons=40_000, seed=3)
    assert measured.emitted_lm == pytest.approx(20.0, rel=1e-9)
    # the rod absorbs a little: out of 20 lm, the two end faces' Fresnel losses and the bulk's
    assert 0.6 * 20.0 < expected < 0.9 * 20.0
    assert measured.out_lm == pytest.approx(expected, rel=0.01), (measured, expected)
    assert measured.stderr_lm < 0.003 * expected
    # the few branches near the critical angle at the end faces, bouncing between them, end at the limit
    assert measured.cut_at_depth < 0.01 * 40_000


def _brute_inside(points: np.ndarray, scene: dict) -> np.ndarray:
    ctx = make_context(scene, 1, 1)
    g = ctx.lamps.guide
    lamp = np.zeros(len(points), int)
    s, u, v, *_ = light_guide.to_guide(points, np.zeros_like(points), g, lamp)
    return light_guide.inside(s, u, v, light_guide.gathered(g, lamp))


def _march_checked(ctx, o: np.ndarray, d: np.ndarray, inside, reach: float) -> np.ndarray:
    """Assert each ray's hit is the first change of ``inside`` along a 0.01 mm march up to ``reach``, to
    within the step, with the rod behind its normal and not in front; the normals of the rays whose
    march found a change (NaN rows for the others)."""
    n = len(o)
    lamp = np.zeros(n, int)
    t, normal = light_guide.intersect(Segments(o, d, lamp, np.zeros(n, np.int8), np.zeros(n, np.int8)),
                                      ctx.lamps, np.full(n, np.inf))
    steps = np.arange(1, int(round(reach / 0.01)) + 1) * 0.01
    start_inside = inside(o)
    out = np.full((n, 3), np.nan)
    for i in range(n):
        change = np.nonzero(inside(o[i] + steps[:, None] * d[i]) != start_inside[i])[0]
        if not len(change):
            assert not np.isfinite(t[i]) or t[i] > steps[-1] - 0.02
            continue
        first = steps[change[0]]
        assert first - 0.011 <= t[i] <= first + 1e-9, (i, t[i], first)
        # out of the material: the inside lies behind the normal
        hit = o[i] + t[i] * d[i]
        assert inside((hit - 0.003 * normal[i])[None])[0]
        assert not inside((hit + 0.003 * normal[i])[None])[0]
        out[i] = normal[i]
    return out


@pytest.mark.slow
@pytest.mark.parametrize("section", ["round", "rectangular"])
def test_guide_hits_are_where_a_fine_march_finds_the_boundary(section):
    """Random rays from points in and around the rod: the hit is the first change of inside/outside
    along a fine march (0.01 mm steps), to within the step, and the normal points out of the rod."""
    scene = guide_scene(section=section, diameter=5.0, prism_depth=0.8, prism_pitch=3.0, prism_angle=50.0,
                        length=20.0)
    ctx = make_context(scene, 1, 1)
    rng = np.random.default_rng(5)
    n = 400
    g = ctx.lamps.guide
    centre = g.start[0] + 10.0 * g.axis[0]
    o = centre + rng.uniform(-1, 1, (n, 3)) * np.array([12.0, 3.5, 3.5])
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    normal = _march_checked(ctx, o, d, lambda p: _brute_inside(p, scene), 40.0)
    assert np.isfinite(normal[:, 0]).sum() > 100


def test_lamps_without_a_guide_have_no_guide_parts():
    scene = json.loads((ROOT / "presets" / "photometric-tail-lamp.json").read_text())
    ctx = make_context(parse_scene(copy.deepcopy(scene)), 1, 1)
    assert ctx.lamps.guide is None
    assert light_guide not in ctx.parts


@pytest.mark.parametrize(("change", "field", "words"), [
    (dict(light_model="paper"), "lamps[0].light_guide.enabled", 'needs light_model "photometric"'),
    (dict(prism_depth=2.5), "lamps[0].light_guide.prism_depth", "allowed [0, 2)"),
    (dict(prism_depth=1.5, prism_pitch=2.0), "lamps[0].light_guide.prism_depth", "wider than their pitch"),
    (dict(source="bulb"), "lamps[0].light_guide.enabled", 'allowed with source "led"'),
    (dict(depth=4.0), "lamps[0].light_guide.depth", "into the lens"),
])
def test_a_guide_that_cannot_be_is_refused_in_one_line_naming_the_field(change, field, words):
    from core_tracer.scene.reading import SceneError
    scene = json.loads((ROOT / "presets" / "photometric-tail-lamp.json").read_text())
    lamp = scene["lamps"][0]
    lamp["reflector"]["focal_length"] = 10.0
    lamp["bulb"]["on"] = False
    guide = dict(enabled=True, section="rectangular", width=4.0, thickness=4.0, length=60.0, depth=15.0)
    lamp["source"] = "led"
    lamp["led"] = dict(position=[-30.5, 15.0, 0.0], normal=[1.0, 0.0, 0.0])
    if "light_model" in change:
        scene["light_model"] = change["light_model"]
    elif "source" in change:
        lamp["source"] = change["source"]
    else:
        guide.update(change)
    lamp["light_guide"] = guide
    with pytest.raises(SceneError) as caught:
        parse_scene(scene)
    assert caught.value.path == field, str(caught.value)
    assert words in str(caught.value) and "\n" not in str(caught.value)


@pytest.mark.slow
def test_a_guide_lit_at_both_ends_passes_each_end_the_one_end_far_plus_near_flux():
    """Superposition and symmetry: the mirrored array's light leaves the far end as the first array's
    leaves the first end, so each end of the guide lit at both ends passes Φ_far + Φ_near of one end."""
    one = far_end_flux(guide_scene(), photons=40_000, seed=3)
    both = far_end_flux(guide_scene(lit_ends="both"), photons=40_000, seed=4)
    assert both.emitted_lm == pytest.approx(2.0 * one.emitted_lm, rel=1e-9)  # the same flux per die, twice the dies
    # light back out of the first end: the Fresnel reflection at the far face, some 4 % of what reaches it
    assert 0.02 * one.out_lm < one.near_lm < 0.1 * one.out_lm
    expected = one.out_lm + one.near_lm
    spread = 4.0 * math.hypot(both.stderr_lm, one.stderr_lm)
    assert abs(both.out_lm - expected) < spread + 0.01 * one.near_lm, (both, one)
    assert both.near_lm == pytest.approx(both.out_lm, rel=0.02), both  # the two ends alike
    # (not twice the far flux: the second array's light leaves by the far end only once reflected at the first)


def test_the_mirrored_leds_are_where_the_engine_meets_and_sees_them():
    """The second array is the first's mirror image through the guide's middle: a ray toward the far end
    face's die meets it at the mirrored distance and sees the same luminance as the first die head-on."""
    from core_tracer.raytrace.parts import led_die

    ctx = make_context(guide_scene(lit_ends="both"), 1, 1)
    lamps = ctx.lamps
    depth = lamps.guide.start[0, 1]
    o = np.array([[0.0, depth, 0.0], [0.0, depth, 0.0], [0.0, depth, 0.0], [40.0, depth, 0.0], [-40.0, depth, 0.0]])
    d = np.array([[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    lamp = np.zeros(5, int)
    t = led_die.hit_dies(o, d, lamps, lamp)
    # the die at x = −30 − 1e-4 and its image at +30 + 1e-4, met from the middle; nothing beyond them
    assert t[0] == pytest.approx(30.0 + 1e-4) and t[1] == pytest.approx(30.0 + 1e-4)
    assert np.isinf(t[2]) and np.isinf(t[3]) and t[4] == pytest.approx(10.0 - 1e-4)
    at = o + np.where(np.isfinite(t), t, 0.0)[:, None] * d
    seen = led_die.emitted(lamps, lamp, d, at)
    assert seen[0] == pytest.approx(seen[1]) and seen[0].max() > 0  # each die seen from its front
    assert not seen[4].any()  # the die's back, met from outside the guide, is dark
    one = make_context(guide_scene(), 1, 1).lamps
    assert np.isinf(led_die.hit_dies(o[:1], d[:1], one, lamp[:1])[0])  # lit at one end: no image


@pytest.mark.slow
def test_the_guide_lit_at_both_ends_is_the_sum_of_its_two_one_end_pictures():
    """The preset's guide seen head-on (128 × 48, 16 samples, the same seed): lit at both ends, its picture
    is the one-end picture plus that of the same lamp with its LED moved by hand to the far end face
    (light adds; the dies are opaque, so the sum differs a little where one die hides the other's
    light), and its two halves pass alike within the noise of the LED's sparse bright images in the
    prisms (lit at one end, the near half is several times the far one)."""
    from core_tracer.raytrace.engine import render

    base = json.loads((ROOT / "presets" / "led-light-guide-tail-lamp.json").read_text())

    def picture(ends: str, far_end: bool = False) -> np.ndarray:
        scene = copy.deepcopy(base)
        scene["camera"].update(position=[0.0, -240.0, 0.0], target=[0.0, 0.0, 0.0])
        scene["image"].update(width=128, height=48, samples=16)
        scene["environment"] = {"world": "none"}
        lamp = scene["lamps"][0]
        # the preset's first design, which the tolerances below were measured on: 50° prisms behind a smooth
        # lens (the shipped one's pillows scatter the LED's images into sparkle that 16 samples do not settle)
        lamp["cuts"] = {"pitch": 6.0, "height": 0.0}
        lamp["light_guide"]["prism_angle"] = 50.0
        lamp["light_guide"]["lit_ends"] = ends
        if far_end:
            x, y, z = lamp["led"]["position"]
            lamp["led"].update(position=[-x, y, z], normal=[-1.0, 0.0, 0.0])
        return render(parse_scene(scene)).sum(axis=2)

    near, far, both = picture("one"), picture("one", far_end=True), picture("both")
    assert far.sum() > 0.5 * near.sum()
    assert np.abs(both - near - far).sum() < 0.08 * both.sum()  # measured 0.039
    half = both.shape[1] // 2
    left, right = both[:, :half].sum(), both[:, half:].sum()
    assert abs(left - right) < 0.15 * (left + right) / 2, (left, right)  # measured 0.89 : 1
    assert near[:, :half].sum() > 3.0 * near[:, half:].sum()  # measured 3.9 : 1


def test_a_guide_lit_at_both_ends_counts_both_arrays_in_the_lamps_flux_and_refuses_leds_in_its_middle():
    from core_tracer.measures.export import lamp_flux
    from core_tracer.measures.states import states_of
    from core_tracer.scene.reading import SceneError

    one, both = guide_scene(), guide_scene(lit_ends="both")
    assert lamp_flux(one) == pytest.approx(20.0) and lamp_flux(both) == pytest.approx(40.0)
    state = states_of(both)[1]  # after the surroundings
    assert state.rendered == pytest.approx(40.0) and "2 LEDs" in state.label
    raw = json.loads((ROOT / "presets" / "led-light-guide-tail-lamp.json").read_text())
    raw["lamps"][0]["light_guide"]["lit_ends"] = "both"
    raw["lamps"][0]["led"]["position"] = [0.0, 20.0, 0.0]  # behind the guide's middle
    raw["lamps"][0]["led"]["normal"] = [0.0, -1.0, 0.0]
    with pytest.raises(SceneError) as caught:
        parse_scene(raw)
    assert caught.value.path == "lamps[0].light_guide.lit_ends" and "straddle" in str(caught.value)
    assert "\n" not in str(caught.value)


def arc_scene(radius: float = 30.0, sweep: float = 90.0, **guide) -> dict:
    """``guide_scene`` with its guide along an arc (orientation 0: its middle's tangent +x, bending toward
    +z about C = (0, depth, R)), the LED 0.1 µm before the first end face facing along its tangent."""
    scene = guide_scene(path="arc", arc_radius=radius, arc_sweep=sweep, **guide)
    half = math.radians(sweep) / 2
    depth = scene["lamps"][0]["light_guide"]["depth"]
    tangent = np.array([math.cos(half), 0.0, -math.sin(half)])
    end = np.array([-radius * math.sin(half), depth, radius - radius * math.cos(half)])
    scene["lamps"][0]["led"].update(position=list(end - 1e-4 * tangent), normal=list(tangent))
    return scene


def _arc_inside(points: np.ndarray, guide: dict) -> np.ndarray:
    """The arc rod as docs/model.md §8.7a states it, written out here: |ρ − R| <= w/2, |v| <= h/2,
    |φ| <= Φ/2, and off the V groove of the prism nearest along the axis (planar facets, τ from the
    radial plane of its apex)."""
    from core_tracer.raytrace.guide_table import prism_layout

    radius, sweep = guide["arc_radius"], math.radians(guide["arc_sweep"])
    rel = points - np.array([0.0, guide["depth"], radius])
    rho, v = np.hypot(rel[:, 0], rel[:, 2]), rel[:, 1]
    phi = np.arctan2(rel[:, 0], -rel[:, 2])
    ok = (np.abs(rho - radius) <= guide["width"] / 2) & (np.abs(v) <= guide["thickness"] / 2)
    ok &= np.abs(phi) <= sweep / 2
    slope = math.tan(math.radians(guide["prism_angle"]))
    count, first = prism_layout(radius * sweep, guide["prism_pitch"], guide["prism_depth"], slope)
    k = np.clip(np.floor((radius * (phi + sweep / 2) - first) / guide["prism_pitch"] + 0.5), 0, count - 1)
    apex = (first + k * guide["prism_pitch"]) / radius - sweep / 2
    tau = rel[:, 0] * np.cos(apex) + rel[:, 2] * np.sin(apex)
    return ok & (v <= guide["thickness"] / 2 - guide["prism_depth"] + slope * np.abs(tau))


def test_arc_guide_hits_are_where_a_fine_march_finds_the_boundary():
    """Random rays from points in and around a 90° arc of radius 30 mm with prisms: the hit is the first
    change of inside/outside along a 0.01 mm march, to within the step, and the normal points out."""
    scene = arc_scene(prism_depth=0.8, prism_pitch=3.0, prism_angle=50.0)
    guide = scene["lamps"][0]["light_guide"]
    ctx = make_context(scene, 1, 1)
    rng = np.random.default_rng(7)
    n = 400
    # points near the arc's axis: a random angle in and a little beyond the sweep, offsets across it
    phi = rng.uniform(-0.9, 0.9, n) * math.radians(90.0) * 0.6
    rho = 30.0 + rng.uniform(-3.5, 3.5, n)
    o = np.stack([rho * np.sin(phi), guide["depth"] + rng.uniform(-3.5, 3.5, n), 30.0 - rho * np.cos(phi)], axis=1)
    d = rng.normal(size=(n, 3))
    d[: n // 4, 1] *= 0.05  # a quarter of them nearly along the lens plane, through many prisms' cells
    d /= np.linalg.norm(d, axis=1)[:, None]
    normal = _march_checked(ctx, o, d, lambda p: _arc_inside(p, guide), 60.0)
    checked = np.isfinite(normal[:, 0])
    crossed_facets = int((checked & (np.abs(normal[:, 1]) != 0.0) & (np.abs(normal[:, 1]) != 1.0)).sum())
    assert checked.sum() > 150 and crossed_facets > 10, (checked.sum(), crossed_facets)


@pytest.mark.slow
def test_total_internal_reflection_carries_light_around_a_gentle_arc():
    """A clear rod 4 × 4 mm bent along a 60° arc of radius 100 mm (≫ its thickness) passes more than
    80 % of what the straight rod of the same length (104.7 mm) passes out of its far end (the light
    that enters stays within θ_c of the axis; a gentle bend tilts it against the walls by w / R at most)."""
    straight = far_end_flux(guide_scene(length=100.0 * math.radians(60.0)), photons=20_000, seed=3)
    bent = far_end_flux(arc_scene(radius=100.0, sweep=60.0), photons=20_000, seed=3)
    ratio = bent.out_lm / straight.out_lm
    assert 0.8 < ratio <= 1.0 + 4 * bent.stderr_lm / bent.out_lm, (bent, straight)  # measured 0.996
    # a tight bend (radius 1.5 widths, 120°) lets much of it out through its outer wall: the test can fail
    short = far_end_flux(guide_scene(length=6.0 * math.radians(120.0)), photons=20_000, seed=3)
    tight = far_end_flux(arc_scene(radius=6.0, sweep=120.0), photons=20_000, seed=3)
    assert tight.out_lm < 0.8 * short.out_lm  # measured 0.65


@pytest.mark.parametrize(("change", "field", "words"), [
    (dict(section="round"), "lamps[0].light_guide.path", "torus"),
    (dict(radius=3.0), "lamps[0].light_guide.arc_radius", "allowed more than 4 mm"),
    (dict(radius=6.0, prism_depth=1.0, prism_pitch=2.4, prism_angle=50.0), "lamps[0].light_guide.prism_depth",
     "at the inside of the arc"),
])
def test_an_arc_guide_that_cannot_be_is_refused_in_one_line(change, field, words):
    from core_tracer.scene.reading import SceneError

    with pytest.raises(SceneError) as caught:
        arc_scene(**change)
    assert caught.value.path == field and words in str(caught.value) and "\n" not in str(caught.value)


@pytest.mark.slow
def test_an_arc_guide_lit_at_both_ends_passes_the_same_flux_out_of_each_end():
    """The mirror plane of an arc guide is the radial plane through its middle: the image of the LED
    at the first end faces the far end along its tangent, so both ends pass alike (symmetry), each the
    one-end arc's far plus near flux (superposition)."""
    one = far_end_flux(arc_scene(radius=40.0, sweep=90.0), photons=20_000, seed=3)
    both = far_end_flux(arc_scene(radius=40.0, sweep=90.0, lit_ends="both"), photons=20_000, seed=4)
    assert both.near_lm == pytest.approx(both.out_lm, rel=0.03), both
    spread = 4.0 * math.hypot(both.stderr_lm, one.stderr_lm)
    assert abs(both.out_lm - one.out_lm - one.near_lm) < spread + 0.01 * one.near_lm, (both, one)

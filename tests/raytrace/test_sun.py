"""The sun of equation (1) (strength, colour) and its phantom light in the reflectors (sunlight.py)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from helpers import PRESETS, fresnel_unpolarised, scene_with

from core_tracer import parse_scene, render_passes
from core_tracer.raytrace import optics, sunlight
from core_tracer.raytrace.camera import eye_rays, make_camera
from core_tracer.scene.derived import lamp_geometry


@pytest.mark.seed(3)
def test_the_general_sun_at_strength_1_and_white_is_the_papers_light(rng):
    normal = optics.normalize(rng.normal(size=(50, 3)))
    view = optics.normalize(rng.normal(size=(50, 3)))
    paper = sunlight.Sun(optics.normalize(np.array([0.3, -1.0, 0.6])), np.array([1.0, 0.9, 0.8]), 0.25, 1.0,
                         np.ones(3), True)
    general = sunlight.Sun(paper.direction, paper.highlight, 0.25, 1.0, np.ones(3), False)
    colour = np.array([0.6, 0.3, 0.1])
    np.testing.assert_allclose(general.shade(normal, view, colour, 0.5, 30.0),
                               paper.shade(normal, view, colour, 0.5, 30.0), rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize("per_point", [False, True])
@pytest.mark.seed(4)
def test_the_general_sun_is_its_plain_formula_bit_for_bit(per_point, rng):
    # Sun.shade works in place a channel at a time: the same operations on every element as the
    # plain expression of eq. (1) with strength and colour below, so the same bits.
    normal = optics.normalize(rng.normal(size=(5000, 3)))
    view = optics.normalize(rng.normal(size=(5000, 3)))
    sun = sunlight.Sun(optics.normalize(np.array([0.3, -1.0, 0.6])), np.array([1.0, 0.9, 0.8]), 0.25, 1.7,
                       np.array([1.0, 0.8, 0.6]), False)
    colour = rng.random((5000, 3)) if per_point else np.array([0.6, 0.3, 0.1])
    specular, shininess = (rng.random(5000), rng.uniform(1.0, 60.0, 5000)) if per_point else (0.5, 30.0)
    L = sun.direction
    cos_theta = np.maximum(0.0, normal[:, 0] * L[0] + normal[:, 1] * L[1] + normal[:, 2] * L[2])
    cos_beta = np.maximum(0.0, np.einsum("ij,ij->i", normal, optics.normalize(view + L)))
    lit = sun.ambient + (1.0 - sun.ambient) * sun.strength * cos_theta[:, None] * sun.color
    spec = np.where(cos_theta > 0.0, sun.strength * np.asarray(specular) * np.power(cos_beta, shininess), 0.0)
    expected = lit * colour + spec[:, None] * sun.highlight
    got = sun.shade(normal, view, colour, specular, shininess)
    assert (got.view(np.uint64) == expected.view(np.uint64)).all()


def test_strength_and_colour_scale_the_sunlit_part_only():
    scene = scene_with(**{"light": {"direction": [0, -1, 0], "color": [1, 1, 1], "ambient": 0.2, "strength": 2.0,
                                    "sun_color": [1.0, 0.5, 0.25]},
                          "body.specular": 0.0, "image": {"width": 16, "height": 16},
                          "camera": {"type": "orthographic", "position": [0, -500, 0], "target": [0, 0, 0],
                                     "up": [0, 0, 1], "width": 300.0}})
    body = render_passes(scene).passes["body"].reshape(-1, 3)
    seen = body[body.max(axis=1) > 0]
    # [d + (1 - d) s S cos theta] C0 with the front face facing the sun (cos theta = 1).
    expected = (0.2 + 0.8 * 2.0 * np.array([1.0, 0.5, 0.25])) * np.array(scene["body"]["color"])
    np.testing.assert_allclose(seen, np.broadcast_to(expected, seen.shape), rtol=1e-6)  # float32 passes


def test_old_documents_mean_the_papers_light():
    scene = scene_with()
    assert scene["light"]["strength"] == 1.0 and scene["light"]["sun_color"] == [1.0, 1.0, 1.0]
    assert scene["light"]["phantom"] is False and scene["light"]["follow_environment"] is False


# -- Phantom light -----------------------------------------------------------------------------------

SUN = (0.25, -1.0, 0.2)


def _flat_clear_lens_over_a_scattering_reflector(sun=SUN, phantom=True) -> dict:
    return scene_with(**{
        "camera": {"type": "orthographic", "position": [0, -500, 0], "target": [0, 0, 0], "up": [0, 0, 1],
                   "width": 84.0},
        "image": {"width": 21, "height": 21},
        "light": {"direction": list(sun), "color": [1, 1, 1], "ambient": 0.25, "strength": 2.0,
                  "sun_color": [1.0, 0.8, 0.6], "phantom": phantom},
        "lamps[0].cuts.height": 0.0,
        "lamps[0].lens.absorption": [0.0, 0.0, 0.0],
        "lamps[0].lens.specular": 0.0,
        "lamps[0].lens.diffuse_color": [0.0, 0.0, 0.0],
        "lamps[0].reflector.reflectance": 0.0,
        "lamps[0].reflector.color": [0.0, 0.0, 0.0],
        "lamps[0].bulb.on": False,
    })


def test_phantom_light_of_a_flat_clear_lens_is_the_closed_form():
    scene = _flat_clear_lens_over_a_scattering_reflector()
    scatter = render_passes(scene).passes["reflector_scatter"].reshape(-1, 3)
    lamp = scene["lamps"][0]
    g = lamp_geometry(lamp)
    f, n = lamp["reflector"]["focal_length"], lamp["lens"]["ior"]
    w, shininess = lamp["reflector"]["scatter"], lamp["reflector"]["shininess"]
    sun = np.array(SUN) / np.linalg.norm(SUN)
    r0 = fresnel_unpolarised(1.0, n)
    r_sun = fresnel_unpolarised(-sun[1], n)
    cam = make_camera(scene["camera"], 21, 21)
    origins, _ = eye_rays(cam, np.arange(21 * 21))
    checked = 0
    for i, (x, _, z) in enumerate(origins):
        rho2 = x * x + z * z
        if not 10.0**2 < rho2 < 40.0**2:  # clear of the bulb and socket, inside the rim
            continue
        y = g["vertex"] - rho2 / (4 * f)
        normal = np.array([-x / (2 * f), -1.0, -z / (2 * f)])
        normal /= np.linalg.norm(normal)
        s = (g["plane_b"] - y) / sun[1]
        through_lens = (x + s * sun[0]) ** 2 + (z + s * sun[2]) ** 2 <= lamp["lens"]["radius"] ** 2
        half = (np.array([0.0, -1.0, 0.0]) + sun) / np.linalg.norm(np.array([0.0, -1.0, 0.0]) + sun)
        # Normal incidence: the eye ray and its first internal reflection (k = (1 - r)^2 r^2 > 0.1 %) reach
        # the same reflector point; the sun comes in through both faces, (1 - r_sun)^2.
        k = (1 - r0) ** 2 * (1 + r0 * r0)
        expected = k * (1 - r_sun) ** 2 * w * max(0.0, normal @ half) ** shininess * 2.0 * np.array([1.0, 0.8, 0.6])
        np.testing.assert_allclose(scatter[i], expected * through_lens, rtol=1e-6, atol=1e-12)  # float32 passes
        checked += 1
    assert checked > 100


def test_no_phantom_light_with_the_sun_behind_or_switched_off():
    behind = _flat_clear_lens_over_a_scattering_reflector(sun=(0.25, 1.0, 0.2))
    assert not render_passes(behind).passes["reflector_scatter"].any()
    off = _flat_clear_lens_over_a_scattering_reflector(phantom=False)
    assert not render_passes(off).passes["reflector_scatter"].any()


def _unlit_four_lamps(sun) -> dict:
    doc = json.loads((PRESETS / "four-lamp-rear-combination.json").read_text())
    doc["image"] = {"width": 96, "height": 48}
    doc["camera"] = {"position": [0, -1900, 0], "target": [0, 0, 0], "up": [0, 0, 1], "fov_deg": 16}
    doc["light"] = {"direction": list(sun), "color": [1, 1, 1], "ambient": 0.25, "phantom": True}
    for lamp in doc["lamps"]:
        lamp["bulb"]["on"] = False
    return parse_scene(doc)


@pytest.mark.slow
@pytest.mark.parametrize("height", [0.1, 0.3])
def test_an_unlit_lamp_in_low_frontal_sun_looks_lit_and_with_the_sun_behind_it_does_not(height):
    front = render_passes(_unlit_four_lamps((0.3, -1.0, height)))
    behind = render_passes(_unlit_four_lamps((0.3, 1.0, height)))
    lens = front.passes["lens_surface"].max(axis=2) > 0
    assert lens.sum() > 300
    front_mean = front.image[lens].mean(axis=0)
    behind_mean = behind.image[lens].mean(axis=0)
    assert not behind.passes["reflector_scatter"].any()
    # The scatter of a unit sun is about an eighth of the lit bulb's (I0 = 8, 7, 6): a fifth or more on
    # top of the reflector's and lens's own colours.
    assert (front_mean > 1.15 * behind_mean).all(), (front_mean, behind_mean)

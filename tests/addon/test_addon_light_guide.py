"""A light-guide lamp built as Blender objects (docs/model.md §8.7a): the rod's mesh against the rod
as the docs state it (written out again here, not taken from the add-on's mesh code), its LEDs, their
material from the photometric equivalents, the lamp's LED facing its end, and a lamp without a guide
keeping no guide object."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from helpers import PRESETS, build_parts, local_mm

import core_tracer

pytestmark = pytest.mark.blender

PRESET = PRESETS / "led-light-guide-tail-lamp.json"




def _rod_height(s: np.ndarray, guide: dict) -> np.ndarray:
    """The back of the rod at s from its first end, as docs/model.md §8.7a states it: V grooves of
    depth δ whose facets rise at α, at the pitch, as many as fit, the row centred."""
    depth, pitch, slope = guide["prism_depth"], guide["prism_pitch"], math.tan(math.radians(guide["prism_angle"]))
    width, length = 2.0 * depth / slope, guide["length"]
    count = int(math.floor((length - width) / pitch + 1e-9)) + 1
    first = 0.5 * (length - (count - 1) * pitch)
    apexes = first + pitch * np.arange(count)
    half = guide["thickness"] / 2.0
    return np.minimum(half, (half - depth + slope * np.abs(s[:, None] - apexes[None, :])).min(axis=1))


def test_the_guide_lamp_is_built_with_its_rod_and_leds(lamp_addon, bl_scene):
    scene = core_tracer.load_scene(PRESET)
    lamp = scene["lamps"][0]
    guide = lamp["light_guide"]
    parts = build_parts(lamp_addon, bl_scene, scene)
    rod = parts["lamps[0].light_guide"]
    points = local_mm(rod, lamp)
    cx, cz = guide["center"]
    s = points[:, 0] - (cx - guide["length"] / 2)  # orientation 0: along x
    u, v = points[:, 2] - cz, points[:, 1] - guide["depth"]
    assert s.min() == pytest.approx(0.0, abs=1e-3) and s.max() == pytest.approx(guide["length"], abs=1e-3)
    assert np.abs(u).max() == pytest.approx(guide["width"] / 2, abs=1e-3)
    assert v.min() == pytest.approx(-guide["thickness"] / 2, abs=1e-3)
    # every vertex on the back lies on the prisms' profile (the grooves exact), none above it
    back = v > -guide["thickness"] / 2 + 1e-6
    assert np.all(v[back] <= _rod_height(s[back], guide) + 2e-3)
    assert np.any(v[back] < guide["thickness"] / 2 - guide["prism_depth"] + 1e-3)  # the grooves' bottoms
    # the lamp's LED faces the first end face (its own object, the LED source's)
    die = local_mm(parts["lamps[0].led"], lamp)
    assert np.ptp(die[:, 2]) == pytest.approx(lamp["led"]["die_size"][0], abs=1e-3)
    assert die[:, 0].max() < cx - guide["length"] / 2
    # its material from the photometric equivalents: glass of PMMA's n_d, clear
    bsdf = rod.data.materials[0].node_tree.nodes["Light Guide BSDF"]
    assert bsdf.inputs["IOR"].default_value == pytest.approx(1.491, abs=1e-3)
    absorption = rod.data.materials[0].node_tree.nodes["Light Guide Absorption"]
    assert absorption.inputs["Density"].default_value == pytest.approx(0.0, abs=1e-9)


def test_a_lamp_without_a_guide_keeps_no_guide_objects(lamp_addon, bl_scene):
    scene = core_tracer.load_scene(PRESET)
    build_parts(lamp_addon, bl_scene, scene)
    raw = json.loads(PRESET.read_text())
    raw["lamps"][0]["light_guide"]["enabled"] = False
    parts = build_parts(lamp_addon, bl_scene, core_tracer.normalize(raw))
    assert "lamps[0].light_guide" not in parts
    assert "lamps[0].lens" in parts


def test_a_guide_lit_at_both_ends_has_its_leds_mirrored_at_the_far_end(lamp_addon, bl_scene):
    """lit_ends "both": the LEDs object holds the lamp's die and its mirror image through the guide's
    middle, facing the far end face (its faces' normals toward the rod), with the same material."""
    raw = json.loads(PRESET.read_text())
    raw["lamps"][0]["light_guide"]["lit_ends"] = "both"
    scene = core_tracer.normalize(raw)
    lamp, guide = scene["lamps"][0], scene["lamps"][0]["light_guide"]
    leds = build_parts(lamp_addon, bl_scene, scene)["lamps[0].led"]
    assert len(leds.data.polygons) == 2
    die = local_mm(leds, lamp)
    cx, half = guide["center"][0], guide["length"] / 2
    near, far = die[die[:, 0] < cx], die[die[:, 0] > cx]
    assert len(near) == len(far) == 4
    x = lamp["led"]["position"][0]
    assert near[:, 0] == pytest.approx(np.full(4, x), abs=1e-3)
    assert far[:, 0] == pytest.approx(np.full(4, 2 * cx - x), abs=1e-3) and far[:, 0].min() > cx + half
    assert sorted(far[:, 2].round(3)) == sorted(near[:, 2].round(3))
    # each die wound to face the rod: the near one toward +x, the far one toward −x (in the lamp's frame)
    turn = np.array(leds.matrix_world)[:3, :3]
    normals = sorted(round(float((turn @ np.array(p.normal))[0] / np.linalg.norm(turn @ np.array(p.normal))))
                     for p in leds.data.polygons)
    assert normals == [-1, 1]


def test_an_arc_guide_is_built_on_its_cylinders_with_radial_ends_and_planar_facets(lamp_addon, bl_scene):
    """path "arc": every vertex on one of the two cylinders about the arc's centre (a rectangular section
    has its corners there), within the sweep, the end rings on the radial end planes, the back's
    vertices on the prisms' planar facets or the back (docs/model.md §8.7a, written out again here)."""
    raw = json.loads(PRESET.read_text())
    guide = raw["lamps"][0]["light_guide"]
    guide.update(path="arc", arc_radius=120.0, arc_sweep=70.0)
    scene = core_tracer.normalize(raw)
    lamp, guide = scene["lamps"][0], scene["lamps"][0]["light_guide"]
    points = local_mm(build_parts(lamp_addon, bl_scene, scene)["lamps[0].light_guide"], lamp)
    radius, sweep, hw, hh = guide["arc_radius"], math.radians(guide["arc_sweep"]), guide["width"] / 2, 2.0
    cx, cz = guide["center"]
    rel = points - np.array([cx, guide["depth"], cz + radius])  # orientation 0: bending toward +z
    rho, v = np.hypot(rel[:, 0], rel[:, 2]), rel[:, 1]
    phi = np.arctan2(rel[:, 0], -rel[:, 2])
    assert np.all(np.isclose(rho, radius - hw, atol=1e-3) | np.isclose(rho, radius + hw, atol=1e-3))
    assert np.abs(phi).max() == pytest.approx(sweep / 2, abs=1e-4)
    assert v.min() == pytest.approx(-hh, abs=1e-3) and v.max() == pytest.approx(hh, abs=1e-3)
    slope = math.tan(math.radians(guide["prism_angle"]))
    width, pitch, depth = 2 * guide["prism_depth"] / slope, guide["prism_pitch"], guide["prism_depth"]
    count = int(math.floor((radius * sweep - width) / pitch + 1e-9)) + 1
    apex = (0.5 * (radius * sweep - (count - 1) * pitch) + pitch * np.arange(count)) / radius - sweep / 2
    tau = rel[:, 0, None] * np.cos(apex)[None] + rel[:, 2, None] * np.sin(apex)[None]  # (N, prisms)
    nearest = np.abs(phi[:, None] - apex[None]).argmin(axis=1)
    height = np.minimum(hh, hh - depth + slope * np.abs(tau[np.arange(len(tau)), nearest]))
    back = v > -hh + 1e-6
    assert np.all(np.abs(v[back] - height[back]) < 2e-3)  # on the facets or the back, none off them
    assert np.any(v[back] < hh - depth + 1e-3)  # the grooves' bottoms
    assert len(points) > 8 * count  # rings at every prism, and chords along the walls

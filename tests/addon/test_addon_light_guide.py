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

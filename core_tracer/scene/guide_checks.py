"""The rules of a light guide (docs/photometric.md, light guides) that relate several fields: the
photometric mode, the lamp's LEDs to light it, no prism plate beside it, prisms that fit the rod and
each other, a rod behind the lens's cuts. Each raises ``SceneError`` naming the field to change."""

from __future__ import annotations

import math

import numpy as np

from . import spec as S
from .derived import lamp_geometry
from .led_array import LedArray, mirror_plane
from .messages import rounded
from .reading import SceneError


def check_light_guide(scene: dict, i: int) -> None:
    """Raise for the first rule lamps[i]'s light guide breaks (nothing without a guide)."""
    lamp = scene["lamps"][i]
    guide = lamp.get("light_guide")
    if not guide or not guide["enabled"]:
        return
    where = f"lamps[{i}].light_guide"
    if scene.get("light_model", "paper") != "photometric":
        raise SceneError(f"{where}.enabled", 'a light guide needs light_model "photometric"; allowed false in the '
                                             "paper mode")
    if lamp.get("source", "bulb") != "led":
        raise SceneError(f"{where}.enabled", 'a light guide is lit by the lamp\'s LEDs; allowed with source "led" '
                                             "(the led section placed facing an end face)")
    if lamp.get("collection", "reflector") == "prism_plate":
        raise SceneError(f"{where}.enabled", "a lamp with a prism plate cannot have a light guide too; allowed false "
                                             'with collection "prism_plate"')
    round_rod = guide["section"] == "round"
    arc = guide.get("path", "straight") == "arc"
    if arc and round_rod:
        raise SceneError(f"{where}.path", 'an arc guide has a rectangular section (a round one would be a torus); '
                                          'allowed "straight" with section "round"')
    if arc and guide["arc_radius"] <= guide["width"]:
        raise SceneError(f"{where}.arc_radius", f"{guide['arc_radius']:g} mm bends the guide tighter than its width "
                                                f"{guide['width']:g} mm; allowed more than {guide['width']:g} mm")
    length = guide["arc_radius"] * math.radians(guide["arc_sweep"]) if arc else guide["length"]
    thickness = guide["diameter"] if round_rod else guide["thickness"]
    depth, pitch = guide["prism_depth"], guide["prism_pitch"]
    if depth >= 0.5 * thickness:
        raise SceneError(f"{where}.prism_depth", f"{depth:g} cuts half through the rod ({thickness:g} mm thick); "
                                                 f"allowed [0, {rounded(0.5 * thickness, False)}) mm")
    if depth > 0:
        width = 2.0 * depth / math.tan(math.radians(guide["prism_angle"]))
        if width > pitch:
            deepest = deepest_at(pitch, guide)
            raise SceneError(f"{where}.prism_depth", f"{depth:g} makes each prism {width:.3g} mm wide, wider than "
                                                     f"their pitch {pitch:g} mm; allowed at most {deepest:.3g} mm")
        if length / pitch > S.MAX_GUIDE_PRISMS:
            raise SceneError(f"{where}.prism_pitch", f"{pitch:g} gives more than {S.MAX_GUIDE_PRISMS} prisms along "
                                                     f"{length:g} mm; allowed at least "
                                                     f"{length / S.MAX_GUIDE_PRISMS:.3g} mm")
        inner = guide["arc_radius"] - 0.5 * guide["width"]
        # the grooves fan out toward the arc's inside: there a groove spans 2 asin(w / 2ρ) of a cell's pitch / R
        if arc and 2.0 * math.asin(min(1.0, 0.5 * width / inner)) * guide["arc_radius"] > pitch:
            raise SceneError(f"{where}.prism_depth", f"{depth:g} makes each prism wider than their pitch {pitch:g} mm "
                                                     "at the inside of the arc; allowed at most "
                                                     f"{deepest_at(pitch * inner / guide['arc_radius'], guide):.3g} mm")
    front = guide["depth"] - 0.5 * thickness
    apexes = lamp_geometry(lamp)["plane_b"]
    if front <= apexes:
        raise SceneError(f"{where}.depth", f"{guide['depth']:g} puts the guide's front {front:.3g} mm deep, into the "
                                           f"lens (its cuts reach {apexes:.3g} mm); allowed more than "
                                           f"{apexes + 0.5 * thickness:.4g} mm")
    if guide.get("lit_ends", "one") == "both":
        _check_mirror(lamp, guide, where)


def deepest_at(pitch: float, guide: dict) -> float:
    """The deepest prisms whose grooves, 2 δ / tan α wide, fit in ``pitch``."""
    return 0.5 * pitch * math.tan(math.radians(guide["prism_angle"]))


def _check_mirror(lamp: dict, guide: dict, where: str) -> None:
    """A guide lit at both ends mirrors the lamp's LED array through its middle (s = L/2): the array must
    lie wholly on one side of that plane, else it and its image overlap."""
    leds = LedArray.of(lamp["led"])
    middle, axis = mirror_plane(guide)
    corners = np.array([c + sa * leds.half_size[0] * leds.across + sb * leds.half_size[1] * leds.up
                        for c in leds.die_centres() for sa in (-1, 1) for sb in (-1, 1)])
    side = (corners - middle) @ axis
    if side.min() <= 0.0 <= side.max():
        raise SceneError(f"{where}.lit_ends", "the LEDs straddle the guide's middle, where their mirror image "
                                              'would overlap them; allowed "one", or the LEDs at an end face')

"""The rules of a prism-plate lamp (docs/model.md, the prism plate) that relate several fields: the rings
fit the plate and can bend the bulb's light parallel, the housing fits the body, and the bulb sits
inside the housing behind the plate. Each raises ``SceneError`` naming the field to change."""

from __future__ import annotations

import math

from . import spec as S
from .messages import interval, rounded, show_value
from .prism_profile import MAX_FACET_INCIDENCE_DEG, shortest_focal_length
from .reading import SceneError


def check_prism_plate(scene: dict, i: int, g: dict) -> None:
    """Raise for the first rule lamps[i]'s prism plate breaks; ``g`` is its ``lamp_geometry``."""
    lamp, where = scene["lamps"][i], f"lamps[{i}]"
    plate, R = lamp["prism_plate"], lamp["lens"]["radius"]
    p, f, n = plate["pitch"], plate["focal_length"], plate["ior"]
    pitch_range = f"allowed {interval(R / S.MAX_RINGS, R)} mm (at most {S.MAX_RINGS} rings across the radius)"
    if p > R:
        raise SceneError(f"{where}.prism_plate.pitch", f"{p:g} is wider than the plate (lens radius {R:g} mm); "
                                                       f"{pitch_range}")
    if p < R / S.MAX_RINGS:
        raise SceneError(f"{where}.prism_plate.pitch", f"{p:g} is too fine for lens radius {R:g} mm; {pitch_range}")
    f_hi = S.PRISM_PLATE.fields["focal_length"].hi
    f_lo = shortest_focal_length(R, p, n, f_hi)
    if f_lo is None:
        raise SceneError(f"{where}.prism_plate.ior", f"{n:g} is too weak for a plate of radius {R:g} mm: no focal "
                         f"length up to {f_hi:g} mm bends the bulb's light parallel at the rim; allowed a higher "
                         f"index, at most {S.PRISM_PLATE.fields['ior'].hi:g}")
    if f < f_lo:
        raise SceneError(f"{where}.prism_plate.focal_length",
                         f"{f:g} is too short for lens radius {R:g} mm at ior {n:g}: the outer rings would meet the "
                         f"bulb's light more than {MAX_FACET_INCIDENCE_DEG:g} degrees from their normal and cannot "
                         f"bend it parallel; allowed {interval(f_lo, f_hi)} mm")
    depth = scene["body"]["depth"]
    if g["vertex"] > depth:
        room = depth - g["plate_base"]
        if room > 0:
            raise SceneError(f"{where}.prism_plate.housing_depth",
                             f"{plate['housing_depth']:g} puts the housing's back {g['vertex']:.4g} mm deep, deeper "
                             f"than the body ({depth:g} mm); allowed (0, {rounded(room, False)}] mm, or body.depth "
                             f"at least {rounded(g['vertex'], True)} mm")
        raise SceneError("body.depth", f"{depth:g} is shallower than the prism plate of lamps[{i}] (its rings start "
                                       f"{g['plate_base']:.4g} mm deep); allowed at least "
                                       f"{rounded(g['vertex'], True)} mm")
    _check_bulb(lamp, g, where)


def _check_bulb(lamp: dict, g: dict, where: str) -> None:
    """The bulb sphere must lie behind the plate's highest ring and inside the housing."""
    rb, off = lamp["bulb"]["radius"], lamp["bulb"]["offset"]
    bx, by, bz = g["bulb_center"]
    R = lamp["lens"]["radius"]
    front, back = g["plate_peak"], g["vertex"]
    room = min(R, (back - front) / 2)
    if rb >= room:
        raise SceneError(f"{where}.bulb.radius", f"{rb:g} does not fit in the housing between the prism plate's "
                         f"rings and the housing's back ({back - front:.4g} mm deep, radius {R:g} mm); allowed "
                         f"(0, {rounded(room, False)}) mm")
    # (to a nanometre: the positions are sums of the fields, whose rounding would show as -7e-15)
    y_lo, y_hi = round(front + rb - g["focus"], 9) + 0.0, round(back - rb - g["focus"], 9) + 0.0
    if not front + rb < by < back - rb:
        raise SceneError(f"{where}.bulb.offset", f"{show_value(off)} puts the bulb (radius {rb:g} mm) "
                         f"{'into the prism plate' if by - rb <= front else 'through the housing'}; allowed y in "
                         f"({interval(y_lo, y_hi)[1:-1]}) mm")
    if math.hypot(bx, bz) + rb >= R:
        raise SceneError(f"{where}.bulb.offset", f"{show_value(off)} puts the bulb (radius {rb:g} mm) through the "
                         f"housing's side; allowed a distance from the axis sqrt(x^2 + z^2) below "
                         f"{rounded(R - rb, False)} mm")


def prism_limits(lamp: dict, g: dict) -> dict[str, str]:
    """The limits of a prism-plate lamp's fields that depend on other fields, in words (``lamp_limits``)."""
    plate, R = lamp["prism_plate"], lamp["lens"]["radius"]
    rb = lamp["bulb"]["radius"]
    out = {"prism_plate.pitch": f"at most {R:g} mm, the lens radius"}
    f_lo = shortest_focal_length(R, plate["pitch"], plate["ior"], S.PRISM_PLATE.fields["focal_length"].hi)
    if f_lo is not None:
        out["prism_plate.focal_length"] = f"at least {rounded(f_lo, True)} mm for this radius, pitch and ior"
    front, back = g["plate_peak"], g["vertex"]
    if back - front > 2 * rb:
        out["bulb.offset"] = f"y in {interval(round(front + rb - g['focus'], 9), round(back - rb - g['focus'], 9))} mm"
    room = min(R, (back - front) / 2)
    if room > 0:
        out["bulb.radius"] = f"less than {rounded(room, False)} mm in the housing"
    return out

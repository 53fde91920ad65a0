"""The limits of a lamp's fields that depend on other fields, in words with their current values,
for the panel to show beside sliders whose fixed range cannot say them (``lamp_limits``)."""

from __future__ import annotations

import math

from . import spec as S
from .bulb_checks import bulb_limits
from .derived import lamp_geometry
from .geometry_checks import max_tooth_angle
from .messages import interval, rounded
from .outline import Outline
from .prism_checks import prism_limits


def lamp_limits(scene: dict, i: int) -> dict[str, str]:
    """The limits of lamps[i]'s fields that depend on other fields, in words with their current
    values (``{"cuts.height": "at most 6.363 mm for pitch 9 mm (pitch / sqrt 2)", ...}``), for a
    panel to show beside the sliders whose fixed range cannot say them. ``scene`` is a checked or
    unchecked document whose fields are present."""
    body, lamp = scene["body"], scene["lamps"][i]
    (bx, bz), (w, h) = body["center"], body["size"]
    R, pitch = lamp["lens"]["radius"], lamp["cuts"]["pitch"]
    shape = Outline.of_lens(lamp["lens"])
    flutes = lamp["cuts"].get("type") == "flutes"
    limits = {
        "cuts.height": f"at most {rounded(pitch / (2.0 if flutes else math.sqrt(2.0)), False)} mm for pitch "
                       f"{pitch:g} mm ({'pitch / 2' if flutes else 'pitch / sqrt 2'})",
        "cuts.tooth_angle": f"at most {rounded(max_tooth_angle(pitch), False)} deg for pitch {pitch:g} mm "
                            f"(ridges at most {S.MAX_TOOTH_HEIGHT:g} mm high)",
        "cuts.pitch": f"at most {2 * R:g} mm, the lens diameter",
        "socket.radius": f"less than {R:g} mm, the lens radius",
    }
    cx, cz = lamp["center"]
    if shape.round:
        room = min(w / 2 - abs(cx - bx), h / 2 - abs(cz - bz))
        if room > 0:
            limits["lens.radius"] = f"at most {rounded(room, False)} mm at this centre in the body"
    else:
        side = 2 * min(shape.half_w, shape.half_h)
        limits["cuts.pitch"] = f"at most {side:g} mm, the lens's smaller side"
        limits["socket.radius"] = f"less than {side / 2:g} mm, half the lens's smaller side"
        limits["lens.corner_radius"] = f"at most {side / 2:g} mm, half the lens's smaller side"
        room_w, room_h = w - 2 * abs(cx - bx), h - 2 * abs(cz - bz)
        if room_w > 0:
            limits["lens.width"] = f"at most {rounded(room_w, False)} mm at this centre in the body"
        if room_h > 0:
            limits["lens.height"] = f"at most {rounded(room_h, False)} mm at this centre in the body"
    hw, hh = shape.half_w, shape.half_h
    if 2 * hw <= w and 2 * hh <= h:
        limits["center"] = (f"x in {interval(bx - w / 2 + hw, bx + w / 2 - hw)}, "
                            f"z in {interval(bz - h / 2 + hh, bz + h / 2 - hh)} mm inside the body")
    if lamp["lens"].get("shape", "flat") == "cylindrical":
        lens = lamp["lens"]
        need = 2 * shape.half_w + lens["thickness"] + lamp["cuts"]["height"]
        limits["lens.wrap_radius"] = (f"more than {rounded(need, True)} mm for this lens (its width, thickness "
                                      "and cut height)")
    if lamp.get("collection", "reflector") == "prism_plate":
        limits.update(prism_limits(lamp, lamp_geometry(lamp)))
    else:
        limits.update(bulb_limits(lamp, lamp_geometry(lamp)))
    return limits

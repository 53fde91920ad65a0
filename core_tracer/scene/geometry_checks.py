"""The rules that relate several fields of a normalised scene (docs/scene-format.md, "Rules across fields"): the camera
sees the lamp, each lens fits the body and its neighbours, the cuts fit the lens, a cylindrical
lens's cuts and wrap fit, the reflector fits the body. The bulb's rules are ``bulb_checks``'s, a
prism plate's ``prism_checks``'s. Each raises ``SceneError`` naming the field to change."""

from __future__ import annotations

import math

from . import spec as S
from .bulb_checks import HALVINGS, check_bulb
from .derived import body_wraps, lamp_geometry, lens_cylinder, tooth_height
from .led_array import uses_leds
from .led_checks import check_leds
from .messages import interval, rounded, show_value
from .outline import Outline
from .prism_checks import check_prism_plate
from .reading import SceneError


def check_geometry(scene: dict) -> None:
    """The rules that relate several fields; raises ``SceneError`` naming the field to change."""
    cam = scene["camera"]
    if cam["position"][1] >= 0:
        raise SceneError("camera.position", f"y = {show_value(cam['position'][1])} is not in front of the "
                                            "lamp; allowed y < 0 mm (the lamp faces -Y)")
    fwd = [b - a for a, b in zip(cam["position"], cam["target"], strict=False)]
    if math.hypot(*fwd) < S.MIN_CAMERA_DISTANCE:
        raise SceneError("camera.target", f"is {math.hypot(*fwd):.3g} mm from camera.position; allowed at least "
                                          f"{S.MIN_CAMERA_DISTANCE:g} mm away (the camera needs a view direction)")
    cross = [fwd[1] * cam["up"][2] - fwd[2] * cam["up"][1], fwd[2] * cam["up"][0] - fwd[0] * cam["up"][2],
             fwd[0] * cam["up"][1] - fwd[1] * cam["up"][0]]
    if math.hypot(*cross) < 1e-9 * math.hypot(*fwd) * math.hypot(*cam["up"]):
        raise SceneError("camera.up", f"{show_value(cam['up'])} is parallel to the view direction; "
                                      "allowed any direction not along it")
    body = scene["body"]
    bx, bz = body["center"]
    half_w, half_h = body["size"][0] / 2, body["size"][1] / 2
    for i, lamp in enumerate(scene["lamps"]):
        where = f"lamps[{i}]"
        R = lamp["lens"]["radius"]
        shape = Outline.of_lens(lamp["lens"])
        if not shape.round:
            _check_rectangle(lamp["lens"], where)
        cx, cz = lamp["center"]
        if abs(cx - bx) + shape.half_w > half_w + 1e-9 or abs(cz - bz) + shape.half_h > half_h + 1e-9:
            _lens_outside_body(scene, i)
        for j in range(i):
            other = scene["lamps"][j]
            other_shape = Outline.of_lens(other["lens"])
            if shape.round and other_shape.round:
                d = math.hypot(cx - other["center"][0], cz - other["center"][1])
                if d < R + other["lens"]["radius"] - 1e-9:
                    raise SceneError(f"{where}.center", f"lens overlaps the lens of lamps[{j}] (centres "
                                     f"{d:g} mm apart); allowed at least {R + other['lens']['radius']:g} mm")
            else:
                _check_apart(shape, other_shape, cx - other["center"][0], cz - other["center"][1], where, j)
        pitch, h = lamp["cuts"]["pitch"], lamp["cuts"]["height"]
        if shape.round:
            pitch_lo, pitch_hi, across = 2 * R / S.MAX_CUTS_ACROSS, 2 * R, "across the lens diameter"
            fine = f"lens radius {R:g} mm"
        else:
            # The cut walk's bound (cuts.MAX_CELL_STEPS) holds for a path of |dx| + |dz| <= w + h
            # in x-z when (w + h) / p <= sqrt 2 * MAX_CUTS_ACROSS.
            w, hgt = 2 * shape.half_w, 2 * shape.half_h
            pitch_lo, pitch_hi = (w + hgt) / (math.sqrt(2.0) * S.MAX_CUTS_ACROSS), min(w, hgt)
            across, fine = "along (width + height) / sqrt 2", f"lens {w:g} x {hgt:g} mm"
        lo_text, hi_text = (f"{pitch_lo:g}", f"{pitch_hi:g}") if shape.round else \
            (rounded(pitch_lo, True), rounded(pitch_hi, False))
        pitch_range = f"allowed [{lo_text}, {hi_text}] mm (at most {S.MAX_CUTS_ACROSS} cuts " \
                      f"{across})"
        if pitch > pitch_hi:
            raise SceneError(f"{where}.cuts.pitch", f"{pitch:g} is larger than the lens; {pitch_range}")
        if pitch < pitch_lo:
            raise SceneError(f"{where}.cuts.pitch", f"{pitch:g} is too fine for {fine}; {pitch_range}")
        c = pitch / math.sqrt(2.0)
        if lamp["cuts"]["type"] == "sawtooth":
            _check_teeth(lamp["cuts"], where)
        elif lamp["cuts"]["type"] == "flutes":
            if h > pitch / 2:
                raise SceneError(f"{where}.cuts.height", f"{h:g} is more than a half cylinder for pitch {pitch:g}; "
                                 f"allowed [0, {rounded(pitch / 2, False)}] mm (pitch / 2)")
        elif h > c:
            raise SceneError(f"{where}.cuts.height", f"{h:g} is more than a hemisphere for pitch {pitch:g}; "
                             f"allowed [0, {rounded(c, False)}] mm (pitch / sqrt 2)")
        _check_cylinder(lamp, where)
        g = lamp_geometry(lamp)
        if lamp["collection"] == "prism_plate":
            _plate_needs_round_flat_lens(lamp, where)
            check_prism_plate(scene, i, g)
        else:
            if g["vertex"] > body["depth"]:
                _reflector_too_deep(scene, i, g)
            if not uses_leds(lamp):
                check_bulb(lamp, g, where)
        if uses_leds(lamp):
            check_leds(lamp, g, where)
        rs = lamp["socket"]["radius"]
        rs_hi = min(shape.half_w, shape.half_h)
        if rs >= rs_hi:
            shown = f"{rs_hi:g}" if shape.round else rounded(rs_hi, False)
            raise SceneError(f"{where}.socket.radius", f"{rs:g} is not inside the lens; allowed (0, {shown}) mm")
    _check_wraps(scene)


def _plate_needs_round_flat_lens(lamp: dict, where: str) -> None:
    """The prism plate's rings are circles about the lamp axis behind a flat round lens (docs/model.md)."""
    if not Outline.of_lens(lamp["lens"]).round:
        raise SceneError(f"{where}.lens.outline", 'a prism plate sits behind a round lens; allowed "round" '
                         '(or collection "reflector")')
    if lamp["lens"].get("shape", "flat") != "flat":
        raise SceneError(f"{where}.lens.shape", 'a prism plate sits behind a flat lens; allowed "flat" '
                         '(or collection "reflector")')


def _check_rectangle(lens: dict, where: str) -> None:
    """A rectangular outline's corners fit its sides: corner radius at most half the smaller side."""
    w, h, r = lens["width"], lens["height"], lens["corner_radius"]
    if r > min(w, h) / 2 + 1e-12:
        raise SceneError(f"{where}.lens.corner_radius", f"{r:g} is more than half the lens's smaller side "
                         f"({w:g} x {h:g} mm); allowed [0, {rounded(min(w, h) / 2, False)}] mm")


def _check_apart(shape: Outline, other: Outline, dx: float, dz: float, where: str, j: int) -> None:
    """Two lens outlines, one rectangular at least, must not overlap."""
    gap = shape.gap_to(other, dx, dz)
    if gap < -1e-9:
        need_x, need_z = shape.half_w + other.half_w, shape.half_h + other.half_h
        raise SceneError(f"{where}.center", f"lens overlaps the lens of lamps[{j}] by {-gap:.4g} mm (centres "
                         f"{abs(dx):g} mm apart in x, {abs(dz):g} mm in z); allowed at least {need_x:g} mm apart "
                         f"in x or {need_z:g} mm in z")


def _check_cylinder(lamp: dict, where: str) -> None:
    """A cylindrical lens: the cut apexes' cylinder reaches round the whole lens (less than a half
    turn), the caps cover their cells' corners and stay inside the lens thickness."""
    cyl = lens_cylinder(lamp)
    if cyl is None:
        return
    lens, cuts = lamp["lens"], lamp["cuts"]
    if cuts["type"] != "fisheye":  # the curved base's cell walk is the fish-eye grid's (docs/model.md)
        raise SceneError(f"{where}.cuts.type", f'"{cuts["type"]}" cuts are not made on a cylindrical lens; '
                         'allowed "fisheye" (or lens.shape "flat")')
    R, t, h = -cyl["side"] * cyl["axis_x"], lens["thickness"], cuts["height"]
    need = 2 * R + t + h
    if cyl["apex"] <= 2 * R:
        raise SceneError(f"{where}.lens.wrap_radius",
                         f"{cyl['radius']:g} is too small for a lens {2 * R:g} mm wide with thickness {t:g} and "
                         f"cut height {h:g} mm; allowed ({rounded(need, True)}, "
                         f"{rounded(S.LENS.fields['wrap_radius'].hi, False)}] mm")
    if h > 0 and not cyl["corner"] < cyl["radius"]:
        h_max = _deepest_cylinder_cut(lamp)
        raise SceneError(f"{where}.cuts.height",
                         f"{h:g} is too deep for the pitch {cuts['pitch']:g} mm on a cylindrical lens of radius "
                         f"{cyl['radius']:g} mm (the caps would not cover their cells within the thickness); "
                         f"allowed [0, {rounded(h_max, False)}] mm")


def _deepest_cylinder_cut(lamp: dict) -> float:
    """The largest cut height whose caps still cover their cells' corners inside the lens."""
    lo, hi = 0.0, lamp["cuts"]["pitch"] / math.sqrt(2.0)
    for _ in range(HALVINGS):
        mid = (lo + hi) / 2
        trial = {**lamp, "cuts": {**lamp["cuts"], "height": mid}}
        cyl = lens_cylinder(trial)
        lo, hi = (mid, hi) if cyl["corner"] < cyl["radius"] else (lo, mid)
    return lo


def _check_wraps(scene: dict) -> None:
    """The body's front follows one cylinder per wrap side (docs/model.md, "cylindrical lens"): the
    cylindrical lamps of a side share it, the flat lenses lie on the flat part, the body's side
    ends before the cylinder turns a quarter, in front of the body's back."""
    body = scene["body"]
    half_w = body["size"][0] / 2
    wraps = body_wraps(scene)
    for i, lamp in enumerate(scene["lamps"]):
        cyl = lens_cylinder(lamp)
        R, cx = Outline.of_lens(lamp["lens"]).half_w, lamp["center"][0]
        for side, x_t, radius in wraps:
            if cyl is not None and cyl["side"] == side:
                mine = cx + cyl["axis_x"]
                if abs(mine - x_t) > 1e-9 or cyl["radius"] != radius:
                    raise SceneError(f"lamps[{i}].center",
                                     f"the cylindrical lens must share the body's curved front with the other lamps "
                                     f"wrapping toward {lamp['lens']['wrap_toward']}; allowed x = "
                                     f"{x_t + side * R:.6g} mm and lens.wrap_radius = {radius:g} mm")
            elif side * (cx - x_t) + R > 1e-9 and (cyl is None or cyl["side"] != side):
                raise SceneError(f"lamps[{i}].center",
                                 f"{show_value(lamp['center'])} puts the lens on the body's curved front (it starts at "
                                 f"x = {x_t:.6g} mm); allowed x {'<=' if side > 0 else '>='} "
                                 f"{x_t - side * R:.6g} mm, or make this lens cylindrical too")
    if len(wraps) == 2 and wraps[0][1] > wraps[1][1] + 1e-9:
        raise SceneError("lamps", "the lenses wrapping toward -x and +x overlap on the body's front; allowed "
                                  "a -x wrap starting left of the +x wrap")
    for side, x_t, radius in wraps:
        edge = body["center"][0] + side * half_w
        u = side * (edge - x_t)
        if u >= radius:
            raise SceneError("body.size", f"{show_value(body['size'])} reaches past the quarter turn of the curved "
                                          f"front (radius {radius:g} mm from x = {x_t:.6g}); allowed width below "
                                          f"{rounded(2 * (half_w - (u - radius)), False)} mm")
        y_edge = radius - math.sqrt(radius * radius - u * u)
        if y_edge >= body["depth"]:
            allowed = interval(y_edge * 1.0001, S.BODY.fields["depth"].hi)
            raise SceneError("body.depth", f"{body['depth']:g} is shallower than the curved front at the body's side "
                                           f"({y_edge:.4g} mm); allowed {allowed} mm")


def max_tooth_angle(pitch: float) -> float:
    """The steepest tooth angle (deg) whose ridges stand at most ``MAX_TOOTH_HEIGHT`` high."""
    return min(S.CUTS.fields["tooth_angle"].hi, math.degrees(math.atan2(S.MAX_TOOTH_HEIGHT, pitch)))


def _check_teeth(cuts: dict, where: str) -> None:
    """Saw-tooth ridges stand pitch x tan(tooth angle) high, at most ``MAX_TOOTH_HEIGHT``."""
    pitch, angle = cuts["pitch"], cuts["tooth_angle"]
    if tooth_height(pitch, angle) > S.MAX_TOOTH_HEIGHT:
        raise SceneError(f"{where}.cuts.tooth_angle",
                         f"{angle:g} makes ridges {tooth_height(pitch, angle):.4g} mm high at pitch {pitch:g} mm; "
                         f"allowed [0, {rounded(max_tooth_angle(pitch), False)}] deg (ridges at most "
                         f"{S.MAX_TOOTH_HEIGHT:g} mm high)")


def _lens_outside_body(scene: dict, i: int) -> None:
    """Raise for lamps[i]'s lens reaching outside the body: blame its centre when the lens fits
    the body somewhere, else the body's size (the size that holds every lens where it is), else
    the lens's own size."""
    body = scene["body"]
    (bx, bz), (w, h) = body["center"], body["size"]
    lamp = scene["lamps"][i]
    lens = lamp["lens"]
    if lens.get("outline", "round") == "round":
        R = lens["radius"]
        fits = 2 * R <= w + 1e-9 and 2 * R <= h + 1e-9
        x_range, z_range = (bx - w / 2 + R, bx + w / 2 - R), (bz - h / 2 + R, bz + h / 2 - R)
        what, held = f"lens radius {R:g} mm", f"radius {R:g} mm"
        smaller = f", or a smaller lamps[{i}].lens.radius, at most {rounded(min(w, h) / 2, False)} mm"
        key, size, room = "radius", R, min(w, h) / 2
    else:
        lw, lh = lens["width"], lens["height"]
        fits = lw <= w + 1e-9 and lh <= h + 1e-9
        x_range, z_range = (bx - (w - lw) / 2, bx + (w - lw) / 2), (bz - (h - lh) / 2, bz + (h - lh) / 2)
        what, held, smaller = f"a {lw:g} x {lh:g} mm lens", f"{lw:g} x {lh:g} mm", ""
        key, size, room = ("width", lw, w) if lw > w else ("height", lh, h)
    if fits:
        raise SceneError(f"lamps[{i}].center", f"{show_value(lamp['center'])} with {what} puts the lens outside the "
                         f"body; allowed x in {interval(*x_range)}, z in {interval(*z_range)} mm")
    need_w, need_h = _body_needs(scene)
    hi = S.BODY.fields["size"].hi
    if need_w <= hi and need_h <= hi:
        raise SceneError("body.size", f"{show_value(body['size'])} cannot hold the lens of lamps[{i}] ({held}); "
                         f"allowed width in {interval(need_w, hi)} and height in {interval(need_h, hi)} mm{smaller}")
    raise SceneError(f"lamps[{i}].lens.{key}", f"{size:g} does not fit in the body {w:g} x {h:g} mm; allowed "
                     f"(0, {rounded(room, False)}] mm")


def _body_needs(scene: dict) -> tuple[float, float]:
    """The body width and height that hold every lens where it is."""
    (bx, bz), shapes = scene["body"]["center"], [Outline.of_lens(lp["lens"]) for lp in scene["lamps"]]
    need_w = max(2 * (abs(lp["center"][0] - bx) + o.half_w) for lp, o in zip(scene["lamps"], shapes, strict=True))
    need_h = max(2 * (abs(lp["center"][1] - bz) + o.half_h) for lp, o in zip(scene["lamps"], shapes, strict=True))
    return need_w, need_h


def _reflector_too_deep(scene: dict, i: int, g: dict) -> None:
    """Raise for lamps[i]'s reflector reaching behind the body: blame the focal length when a longer
    one fits (a shallower bowl), else the body's depth."""
    depth, lamp = scene["body"]["depth"], scene["lamps"][i]
    R, f = Outline.of_lens(lamp["lens"]).reach, lamp["reflector"]["focal_length"]
    f_hi = S.REFLECTOR.fields["focal_length"].hi
    d_hi = S.BODY.fields["depth"].hi
    f_lo = R * R / (4 * (depth - g["rim"])) if depth > g["rim"] else math.inf
    if f_lo <= f_hi:
        raise SceneError(f"lamps[{i}].reflector.focal_length",
                         f"{f:g} makes the reflector {g['vertex']:.4g} mm deep, deeper than the body ({depth:g} mm); "
                         f"allowed {interval(f_lo, f_hi)} mm, or body.depth at least "
                         f"{rounded(g['vertex'], True)} mm")
    raise SceneError("body.depth", f"{depth:g} is shallower than the reflector of lamps[{i}] ({g['vertex']:.4g} mm "
                     f"deep); allowed {interval(g['vertex'], d_hi)} mm")

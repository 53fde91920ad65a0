"""Validating and normalising ``lamp-scene/1`` documents (read by ``reading``).

A *scene* is the normalised document: a plain JSON-compatible dict in which every field of
``spec.SCENE`` is present (defaults filled in, the default camera computed), numbers are
floats, vectors are lists. The one exception is the lens colour, kept in the form the designer
gave it: ``absorption`` or ``transmitted_color`` with ``reference_thickness``.

Every problem raises ``SceneError`` whose text names the field, the value and the allowed
range, e.g. ``lamps[0].lens.radius: -3 is out of range; allowed (0, 1000] mm``.
"""

from __future__ import annotations

import copy
import json
import math
import os
from typing import Any

from ..raytrace.outline import Outline
from . import spec as S
from .derived import default_camera, default_value, fill_alternative, lamp_geometry
from .reading import HugeNumber, SceneError, read_json
from .safe_text import has_surrogate, printable, show_key


def load_scene(path: str | os.PathLike) -> dict:
    """Read, validate and normalise a scene file."""
    return parse_scene(read_json(path))


# ---------------------------------------------------------------------------------------------
# Validation


def parse_scene(doc: Any) -> dict:
    """Validate a decoded JSON document and return the normalised scene."""
    if not isinstance(doc, dict):
        raise SceneError("", f"a lamp-scene/1 document is a JSON object, not {_kind(doc)}")
    schema = doc.get("schema")
    if schema != S.SCHEMA:
        if isinstance(schema, str) and schema.startswith("lamp-scene/"):
            raise SceneError("schema", f'"{schema}" is not supported; this version reads "{S.SCHEMA}"')
        raise SceneError("schema", f"{_show(schema)} is missing or wrong; allowed \"{S.SCHEMA}\"")
    scene = _section(doc, S.SCENE, "")
    if "camera" not in scene:
        scene["camera"] = default_camera(scene)
    check_geometry(scene)
    return scene


def normalize(scene: dict) -> dict:
    """Validate an already-normalised (or hand-edited) scene again; returns a fresh copy."""
    return parse_scene(copy.deepcopy(scene))


def _section(doc: Any, sec: S.Section, path: str) -> dict:
    if not isinstance(doc, dict):
        raise SceneError(path.rstrip("."), f"expected an object, got {_kind(doc)}; allowed an object with "
                                           f"the keys {', '.join(sec.fields)}")
    for key in doc:
        if key not in sec.fields:
            allowed = ", ".join(sec.fields)
            raise SceneError(f"{path}{show_key(str(key))}", f"unknown key; allowed keys here: {allowed}")
    out: dict = {}
    for key, spec in sec.fields.items():
        where = f"{path}{key}"
        if key not in doc:
            if sec.may_be_absent(key):
                continue
            out[key] = _default(spec, where)
            continue
        out[key] = _value(doc[key], spec, where)
    _either_or(out, sec, path)
    return out


def _default(spec: S.Spec, where: str) -> Any:
    if isinstance(spec, S.ListOf):
        raise SceneError(where, f"is required; {spec.range_text()}")
    return default_value(spec)


def _value(v: Any, spec: S.Spec, where: str) -> Any:
    if isinstance(spec, S.Section):
        return _section(v, spec, where + ".")
    if isinstance(spec, S.ListOf):
        if not isinstance(v, list):
            raise SceneError(where, f"expected a list, got {_kind(v)}; allowed {spec.range_text()}")
        if not spec.min_items <= len(v) <= spec.max_items:
            raise SceneError(where, f"has {len(v)} items; allowed {spec.min_items} to {spec.max_items}")
        return [_section(item, spec.item, f"{where}[{i}].") for i, item in enumerate(v)]
    if isinstance(spec, S.Num):
        return _num(v, spec, where)
    if isinstance(spec, S.Choice):
        if v not in spec.choices:
            raise SceneError(where, f"{_show(v)} is not allowed; allowed {spec.range_text()}")
        return v
    if isinstance(spec, S.Text):
        if not isinstance(v, str):
            raise SceneError(where, f"expected a string, got {_kind(v)}; allowed {spec.range_text()}")
        if len(v) > spec.max_len:
            raise SceneError(where, f"has {len(v)} characters; allowed at most {spec.max_len}")
        _check_characters(v, where, spec.range_text())
        return v
    if isinstance(spec, S.Flag):
        if not isinstance(v, bool):
            raise SceneError(where, f"{_show(v)} is not allowed; allowed true or false")
        return v
    if isinstance(spec, S.Tags):
        if not isinstance(v, list) or not all(isinstance(t, str) for t in v):
            raise SceneError(where, f"expected a list of strings, got {_show(v)}; allowed {spec.range_text()}")
        if len(v) > spec.max_items or any(len(t) > spec.max_len for t in v):
            raise SceneError(where, f"too long; allowed {spec.range_text()}")
        for i, t in enumerate(v):
            _check_characters(t, f"{where}[{i}]", spec.range_text())
        return list(v)
    raise AssertionError(spec)  # pragma: no cover - every spec kind is handled above


def _num(v: Any, spec: S.Num, where: str) -> Any:
    if spec.size > 1:
        if not isinstance(v, list) or len(v) != spec.size:
            raise SceneError(where, f"expected a list of {spec.size} numbers, got {_show(v)}; "
                                    f"allowed {spec.range_text()}")
        items = [_scalar(x, spec, f"{where}[{i}]") for i, x in enumerate(v)]
        if spec.too_short(items):
            raise SceneError(where, f"{_show(v)} is too short to give a direction; allowed {spec.range_text()}")
        return items
    return _scalar(v, spec, where)


def _scalar(x: Any, spec: S.Num, where: str) -> float | int:
    return check_number(x, spec, where, spec.range_text())


def check_number(x: Any, spec: S.Num, where: str, allowed: str) -> float | int:
    """One number checked against ``spec``'s range (``allowed`` is that range as the message says it).

    A JSON integer may have thousands of digits; it is compared exactly and never converted to a
    float before it is known to be in range (the conversion would overflow)."""
    if isinstance(x, bool) or not isinstance(x, (int, float)):
        raise SceneError(where, f"expected a number, got {_show(x)}; allowed {allowed}")
    if isinstance(x, HugeNumber):
        raise SceneError(where, f"{x.shown()} is out of range; allowed {allowed}")
    if isinstance(x, float) and not math.isfinite(x):
        raise SceneError(where, f"{_show(x)} is not a finite number; allowed {allowed}")
    if spec.integer and isinstance(x, float) and not x.is_integer():
        raise SceneError(where, f"{_show(x)} is not a whole number; allowed {allowed}")
    lo_bad = spec.lo is not None and (x < spec.lo or (spec.lo_open and x == spec.lo))
    hi_bad = spec.hi is not None and (x > spec.hi or (spec.hi_open and x == spec.hi))
    if lo_bad or hi_bad or (isinstance(x, int) and abs(x) > _LARGEST_FLOAT):
        raise SceneError(where, f"{_show(x)} is out of range; allowed {allowed}")
    return int(x) if spec.integer else float(x)


_LARGEST_FLOAT = int(1.7976931348623157e308)


def _check_characters(text: str, where: str, allowed: str) -> None:
    if has_surrogate(text):
        raise SceneError(where, f"\"{printable(text, 40)}\" holds a lone surrogate (\\ud800-\\udfff), which is "
                                f"not a character; allowed Unicode text only, {allowed}")


def _either_or(out: dict, sec: S.Section, path: str) -> None:
    """Apply the section's either/or rules (``spec.OneOf``) to the fields read into ``out``:
    one form at most, its selecting field present, its missing fields filled in; no form given
    means the rule's default form with its defaults (what earlier versions wrote)."""
    for rule in sec.one_of:
        given = rule.given(out)
        if len(given) > 1:
            first, other = given[0], given[1]
            raise SceneError(f"{path}{other.name}", f"cannot be given with {first.name}; allowed "
                                                    f"{rule.range_text()}")
        alt = given[0] if given else rule.alternative(rule.default)
        if given and alt.name not in out:
            stray = next(k for k in alt.keys if k in out)
            raise SceneError(f"{path}{stray}", f"only allowed with {alt.name}; allowed {rule.range_text()}")
        fill_alternative(out, sec, alt)




def check_geometry(scene: dict) -> None:
    """The rules that relate several fields; raises ``SceneError`` naming the field to change."""
    cam = scene["camera"]
    if cam["position"][1] >= 0:
        raise SceneError("camera.position", f"y = {_show(cam['position'][1])} is not in front of the "
                                            "lamp; allowed y < 0 mm (the lamp faces -Y)")
    fwd = [b - a for a, b in zip(cam["position"], cam["target"], strict=False)]
    if math.hypot(*fwd) < S.MIN_CAMERA_DISTANCE:
        raise SceneError("camera.target", f"is {math.hypot(*fwd):.3g} mm from camera.position; allowed at least "
                                          f"{S.MIN_CAMERA_DISTANCE:g} mm away (the camera needs a view direction)")
    cross = [fwd[1] * cam["up"][2] - fwd[2] * cam["up"][1], fwd[2] * cam["up"][0] - fwd[0] * cam["up"][2],
             fwd[0] * cam["up"][1] - fwd[1] * cam["up"][0]]
    if math.hypot(*cross) < 1e-9 * math.hypot(*fwd) * math.hypot(*cam["up"]):
        raise SceneError("camera.up", f"{_show(cam['up'])} is parallel to the view direction; "
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
            (_rounded(pitch_lo, True), _rounded(pitch_hi, False))
        pitch_range = f"allowed [{lo_text}, {hi_text}] mm (at most {S.MAX_CUTS_ACROSS} cuts " \
                      f"{across})"
        if pitch > pitch_hi:
            raise SceneError(f"{where}.cuts.pitch", f"{pitch:g} is larger than the lens; {pitch_range}")
        if pitch < pitch_lo:
            raise SceneError(f"{where}.cuts.pitch", f"{pitch:g} is too fine for {fine}; {pitch_range}")
        c = pitch / math.sqrt(2.0)
        if h > c:
            raise SceneError(f"{where}.cuts.height", f"{h:g} is more than a hemisphere for pitch {pitch:g}; "
                             f"allowed [0, {_rounded(c, False)}] mm (pitch / sqrt 2)")
        g = lamp_geometry(lamp)
        if g["vertex"] > body["depth"]:
            _reflector_too_deep(scene, i, g)
        _check_bulb(lamp, g, where)
        rs = lamp["socket"]["radius"]
        rs_hi = min(shape.half_w, shape.half_h)
        if rs >= rs_hi:
            shown = f"{rs_hi:g}" if shape.round else _rounded(rs_hi, False)
            raise SceneError(f"{where}.socket.radius", f"{rs:g} is not inside the lens; allowed (0, {shown}) mm")


def _check_rectangle(lens: dict, where: str) -> None:
    """A rectangular outline's corners fit its sides: corner radius at most half the smaller side."""
    w, h, r = lens["width"], lens["height"], lens["corner_radius"]
    if r > min(w, h) / 2 + 1e-12:
        raise SceneError(f"{where}.lens.corner_radius", f"{r:g} is more than half the lens's smaller side "
                         f"({w:g} x {h:g} mm); allowed [0, {_rounded(min(w, h) / 2, False)}] mm")


def _check_apart(shape: Outline, other: Outline, dx: float, dz: float, where: str, j: int) -> None:
    """Two lens outlines, one rectangular at least, must not overlap."""
    gap = shape.gap_to(other, dx, dz)
    if gap < -1e-9:
        need_x, need_z = shape.half_w + other.half_w, shape.half_h + other.half_h
        raise SceneError(f"{where}.center", f"lens overlaps the lens of lamps[{j}] by {-gap:.4g} mm (centres "
                         f"{abs(dx):g} mm apart in x, {abs(dz):g} mm in z); allowed at least {need_x:g} mm apart "
                         f"in x or {need_z:g} mm in z")


def _lens_outside_body(scene: dict, i: int) -> None:
    """Raise for lamps[i]'s lens reaching outside the body: blame its centre when the lens fits
    the body somewhere, else the body's size (the size that holds every lens where it is)."""
    body = scene["body"]
    (bx, bz), (w, h) = body["center"], body["size"]
    lamp = scene["lamps"][i]
    if lamp["lens"].get("outline", "round") != "round":
        _rectangle_outside_body(scene, i)
    R = lamp["lens"]["radius"]
    if 2 * R <= w + 1e-9 and 2 * R <= h + 1e-9:
        raise SceneError(f"lamps[{i}].center", f"{_show(lamp['center'])} with lens radius {R:g} mm puts "
                         f"the lens outside the body; allowed x in {_interval(bx - w / 2 + R, bx + w / 2 - R)}, "
                         f"z in {_interval(bz - h / 2 + R, bz + h / 2 - R)} mm")
    need_w, need_h = _body_needs(scene)
    hi = S.BODY.fields["size"].hi
    if need_w <= hi and need_h <= hi:
        raise SceneError("body.size", f"{_show(body['size'])} cannot hold the lens of lamps[{i}] (radius {R:g} mm); "
                         f"allowed width in {_interval(need_w, hi)} and height in {_interval(need_h, hi)} mm, or a "
                         f"smaller lamps[{i}].lens.radius, at most {_rounded(min(w, h) / 2, False)} mm")
    raise SceneError(f"lamps[{i}].lens.radius", f"{R:g} does not fit in the body {w:g} x {h:g} mm; allowed "
                     f"(0, {_rounded(min(w, h) / 2, False)}] mm")


def _body_needs(scene: dict) -> tuple[float, float]:
    """The body width and height that hold every lens where it is."""
    (bx, bz), shapes = scene["body"]["center"], [Outline.of_lens(lp["lens"]) for lp in scene["lamps"]]
    need_w = max(2 * (abs(lp["center"][0] - bx) + o.half_w) for lp, o in zip(scene["lamps"], shapes, strict=True))
    need_h = max(2 * (abs(lp["center"][1] - bz) + o.half_h) for lp, o in zip(scene["lamps"], shapes, strict=True))
    return need_w, need_h


def _rectangle_outside_body(scene: dict, i: int) -> None:
    """``_lens_outside_body`` for a rectangular lens: its centre, else the body's size, else its own size."""
    body = scene["body"]
    (bx, bz), (w, h) = body["center"], body["size"]
    lamp = scene["lamps"][i]
    lw, lh = lamp["lens"]["width"], lamp["lens"]["height"]
    if lw <= w + 1e-9 and lh <= h + 1e-9:
        raise SceneError(f"lamps[{i}].center", f"{_show(lamp['center'])} with a {lw:g} x {lh:g} mm lens puts the "
                         f"lens outside the body; allowed x in {_interval(bx - (w - lw) / 2, bx + (w - lw) / 2)}, "
                         f"z in {_interval(bz - (h - lh) / 2, bz + (h - lh) / 2)} mm")
    need_w, need_h = _body_needs(scene)
    hi = S.BODY.fields["size"].hi
    if need_w <= hi and need_h <= hi:
        raise SceneError("body.size", f"{_show(body['size'])} cannot hold the lens of lamps[{i}] ({lw:g} x {lh:g} mm); "
                         f"allowed width in {_interval(need_w, hi)} and height in {_interval(need_h, hi)} mm")
    key, size, room = ("width", lw, w) if lw > w else ("height", lh, h)
    raise SceneError(f"lamps[{i}].lens.{key}", f"{size:g} does not fit in the body {w:g} x {h:g} mm; allowed "
                     f"(0, {_rounded(room, False)}] mm")


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
                         f"allowed {_interval(f_lo, f_hi)} mm, or body.depth at least "
                         f"{_rounded(g['vertex'], True)} mm")
    raise SceneError("body.depth", f"{depth:g} is shallower than the reflector of lamps[{i}] ({g['vertex']:.4g} mm "
                     f"deep); allowed {_interval(g['vertex'], d_hi)} mm")


_HALVINGS = 30  # bisection steps for the bulb's limits: 2^-30 of the span, far below the digits shown


def _wall_distance(lamp: dict, g: dict, rho: float, y: float) -> float:
    """Distance from the point at radius ``rho`` from the axis and depth ``y`` to the reflector's
    paraboloid y = y_vertex - r^2/(4f), r <= R (the closest point lies in the plane through the axis).
    R is the outline's reach: for a rectangular lens this is the whole paraboloid up to the rim plane,
    of which the trimmed reflector is a part; what lies outside the outline's prism is farther than
    the side wall, which ``_bulb_fits`` checks apart."""
    f, R = lamp["reflector"]["focal_length"], Outline.of_lens(lamp["lens"]).reach

    def dist(r: float) -> float:
        return math.hypot(r - rho, g["vertex"] - r * r / (4 * f) - y)

    n = 60
    k = min(range(-n, n + 1), key=lambda j: dist(R * j / n))
    lo, hi = R * max(k - 1, -n) / n, R * min(k + 1, n) / n
    for _ in range(30):  # golden-section refinement around the best sample
        a, b = lo + 0.382 * (hi - lo), lo + 0.618 * (hi - lo)
        if dist(a) < dist(b):
            hi = b
        else:
            lo = a
    return min(dist(R * k / n), dist((lo + hi) / 2))


def _bulb_fits(lamp: dict, g: dict, rho: float, y: float, rb: float, toward: tuple[float, float] = (1.0, 0.0)) -> bool:
    """The bulb sphere (centre at radius ``rho`` from the axis in the unit direction ``toward`` [x, z],
    depth ``y``) lies behind the cut apex plane and inside the paraboloid, and for a rectangular lens
    inside the side wall (the outline's prism)."""
    shape = Outline.of_lens(lamp["lens"])
    f, R = lamp["reflector"]["focal_length"], shape.reach
    inside = y < g["vertex"] - rho * rho / (4 * f) and rho < R
    if inside and not shape.round:
        inside = float(shape.signed_distance(rho * toward[0], rho * toward[1])) <= -rb + 1e-9
    return inside and y - rb >= g["plane_b"] - 1e-9 and _wall_distance(lamp, g, rho, y) >= rb - 1e-9


def _bulb_y_range(lamp: dict, g: dict, rho: float, rb: float,
                  toward: tuple[float, float] = (1.0, 0.0)) -> tuple[float, float] | None:
    """The depths at which the bulb fits at radius ``rho``: from the cut apex plane back to where it
    touches the paraboloid (the clearance shrinks toward the vertex), or None."""
    lo = g["plane_b"] + rb
    if not _bulb_fits(lamp, g, rho, lo, rb, toward):
        return None
    hi = g["vertex"]
    for _ in range(_HALVINGS):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if _bulb_fits(lamp, g, rho, mid, rb, toward) else (lo, mid)
    return g["plane_b"] + rb, lo


def _interval(lo: float, hi: float) -> str:
    """``[lo, hi]`` with both ends rounded inward to 4 significant digits (so the values shown are
    allowed), or to 12 when the interval is too narrow for that."""
    a, b = _rounded(lo, True), _rounded(hi, False)
    return f"[{a}, {b}]" if float(a) <= float(b) else f"[{lo:.12g}, {hi:.12g}]"


def _rounded(x: float, up: bool) -> str:
    """``x`` to 4 significant digits, rounded up or down so that the value shown is allowed."""
    if x == 0:
        return "0"
    step = 10.0 ** (math.floor(math.log10(abs(x))) - 3)
    return f"{(math.ceil(x / step) if up else math.floor(x / step)) * step:.4g}"


def _check_bulb(lamp: dict, g: dict, where: str) -> None:
    """The bulb sphere must lie inside the paraboloid, behind the cut apex plane. The message
    blames the radius when the bulb fits nowhere, else the offset with the depths that fit."""
    rb = lamp["bulb"]["radius"]
    bx, by, bz = g["bulb_center"]
    rho = math.hypot(bx, bz)
    toward = (bx / rho, bz / rho) if rho > 0 else (1.0, 0.0)
    if _bulb_fits(lamp, g, rho, by, rb, toward):
        return
    off = lamp["bulb"]["offset"]
    on_axis = _bulb_y_range(lamp, g, 0.0, rb)
    if on_axis is None:  # too big anywhere: the largest bulb that fits on the axis, found by bisection
        lo, hi = 0.0, rb
        for _ in range(_HALVINGS):
            mid = (lo + hi) / 2
            lo, hi = (mid, hi) if _bulb_y_range(lamp, g, 0.0, mid) is not None else (lo, mid)
        raise SceneError(f"{where}.bulb.radius", f"{rb:g} does not fit inside the reflector (focal length "
                         f"{lamp['reflector']['focal_length']:g} mm, {_lens_size(lamp['lens'])}); "
                         f"allowed (0, {_rounded(lo, False)}] mm")
    ys = _bulb_y_range(lamp, g, rho, rb, toward)
    if ys is not None:
        y_lo, y_hi = (y - g["focus"] for y in ys)
        raise SceneError(f"{where}.bulb.offset", f"{_show(off)} puts the bulb (radius {rb:g} mm) outside the "
                         f"reflector; with x = {off[0]:g} and z = {off[2]:g}, allowed y in {_interval(y_lo, y_hi)} mm")
    y_shown = float(f"{sum(on_axis) / 2 - g['focus']:.4g}")  # mid-depth on the axis, as printed
    if not on_axis[0] <= y_shown + g["focus"] <= on_axis[1]:  # a range too narrow for 4 digits
        y_shown = float(f"{sum(on_axis) / 2 - g['focus']:.12g}")
    y_mid = y_shown + g["focus"]
    lo, hi = 0.0, Outline.of_lens(lamp["lens"]).reach
    for _ in range(_HALVINGS):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if _bulb_fits(lamp, g, mid, y_mid, rb, toward) else (lo, mid)
    along = "" if lamp["lens"].get("outline", "round") == "round" else " in the direction of x, z"
    raise SceneError(f"{where}.bulb.offset", f"{_show(off)} puts the bulb (radius {rb:g} mm) outside the "
                     f"reflector; allowed a distance from the axis sqrt(x^2 + z^2) up to {_rounded(lo, False)} mm"
                     f"{along} (at y = {y_shown:.12g} mm)")


def _lens_size(lens: dict) -> str:
    """The lens's size in words, for messages."""
    if lens.get("outline", "round") == "round":
        return f"lens radius {lens['radius']:g} mm"
    return f"lens {lens['width']:g} x {lens['height']:g} mm"


def lamp_limits(scene: dict, i: int) -> dict[str, str]:
    """The limits of lamps[i]'s fields that depend on other fields, in words with their current
    values (``{"cuts.height": "at most 6.363 mm for pitch 9 mm (pitch / sqrt 2)", ...}``), for a
    panel to show beside the sliders whose fixed range cannot say them. ``scene`` is a checked or
    unchecked document whose fields are present."""
    body, lamp = scene["body"], scene["lamps"][i]
    (bx, bz), (w, h) = body["center"], body["size"]
    R, pitch = lamp["lens"]["radius"], lamp["cuts"]["pitch"]
    shape = Outline.of_lens(lamp["lens"])
    limits = {
        "cuts.height": f"at most {_rounded(pitch / math.sqrt(2.0), False)} mm for pitch {pitch:g} mm "
                       "(pitch / sqrt 2)",
        "cuts.pitch": f"at most {2 * R:g} mm, the lens diameter",
        "socket.radius": f"less than {R:g} mm, the lens radius",
    }
    cx, cz = lamp["center"]
    if shape.round:
        room = min(w / 2 - abs(cx - bx), h / 2 - abs(cz - bz))
        if room > 0:
            limits["lens.radius"] = f"at most {_rounded(room, False)} mm at this centre in the body"
    else:
        side = 2 * min(shape.half_w, shape.half_h)
        limits["cuts.pitch"] = f"at most {side:g} mm, the lens's smaller side"
        limits["socket.radius"] = f"less than {side / 2:g} mm, half the lens's smaller side"
        limits["lens.corner_radius"] = f"at most {side / 2:g} mm, half the lens's smaller side"
        room_w, room_h = w - 2 * abs(cx - bx), h - 2 * abs(cz - bz)
        if room_w > 0:
            limits["lens.width"] = f"at most {_rounded(room_w, False)} mm at this centre in the body"
        if room_h > 0:
            limits["lens.height"] = f"at most {_rounded(room_h, False)} mm at this centre in the body"
    hw, hh = shape.half_w, shape.half_h
    if 2 * hw <= w and 2 * hh <= h:
        limits["center"] = (f"x in {_interval(bx - w / 2 + hw, bx + w / 2 - hw)}, "
                            f"z in {_interval(bz - h / 2 + hh, bz + h / 2 - hh)} mm inside the body")
    limits.update(_bulb_limits(lamp))
    return limits


def _bulb_limits(lamp: dict) -> dict[str, str]:
    """The bulb's radius where it sits and the depths (offset y) at which it fits, in words."""
    g = lamp_geometry(lamp)
    rb, (x, _, z) = lamp["bulb"]["radius"], lamp["bulb"]["offset"]
    by, rho = g["bulb_center"][1], math.hypot(x, z)
    shape = Outline.of_lens(lamp["lens"])
    f, R = lamp["reflector"]["focal_length"], shape.reach
    toward = (x / rho, z / rho) if rho > 0 else (1.0, 0.0)
    out = {}
    if rho < R and by < g["vertex"] - rho * rho / (4 * f):
        room = min(_wall_distance(lamp, g, rho, by), by - g["plane_b"])
        if not shape.round:
            room = min(room, -float(shape.signed_distance(x, z)))
        if room > 0:
            out["bulb.radius"] = f"at most {_rounded(room, False)} mm where the bulb sits"
    ys = _bulb_y_range(lamp, g, rho, rb, toward)
    if ys is not None:
        y_lo, y_hi = (y - g["focus"] for y in ys)
        out["bulb.offset"] = f"y in {_interval(y_lo, y_hi)} mm with x = {x:g} and z = {z:g}"
    return out


def _kind(v: Any) -> str:
    return {dict: "an object", list: "a list", str: "a string", bool: "a boolean",
            type(None): "null"}.get(type(v), "a number" if isinstance(v, (int, float)) else type(v).__name__)


def show_value(v: Any) -> str:
    """A value as a message quotes it: JSON, escaped, at most 60 characters."""
    if isinstance(v, HugeNumber):
        return v.shown()
    if isinstance(v, int) and not isinstance(v, bool) and abs(v) >= 10**60:
        try:
            return f"a number of {len(str(abs(v)))} digits"
        except ValueError:  # str() refuses more than 4300 digits
            return "a number of more than 4300 digits"
    try:
        text = json.dumps(v, allow_nan=True)
    except (TypeError, ValueError, RecursionError):
        text = _kind(v)
    return printable(text, 60)


_show = show_value

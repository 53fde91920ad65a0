"""Quantities derived from a normalised scene and from the field declarations (``spec``).

The positions of a lamp's parts along its axis, the radius of a cut's sphere, the lens's
absorption from either form of its colour, the default camera, and the defaults a new lamp or
section starts with. Nothing here checks a document: ``validate`` does, and uses these.
"""

from __future__ import annotations

import copy
import math
from typing import Any

from ..raytrace.outline import Outline
from . import spec as S


def default_value(spec: S.Spec) -> Any:
    """The normalised default of a field: numbers as floats (or ints), a section with its own
    defaults (``section_defaults``). A list of sections has no default."""
    if isinstance(spec, S.Section):
        return section_defaults(spec)
    if isinstance(spec, S.ListOf):
        raise ValueError("a list of sections has no default")
    if isinstance(spec, S.Num):
        return _num_out(spec.default, spec)
    return copy.deepcopy(spec.default)


def section_defaults(sec: S.Section, preferred: bool = False) -> dict:
    """A normalised ``sec`` holding only defaults: every either/or rule in its default form (what a
    document that says nothing means), or with ``preferred`` in its preferred form (what an editor
    starts a new design with: the colour picker for a lens)."""
    chosen = [rule.alternative(rule.preferred if preferred else rule.default) for rule in sec.one_of]
    named = {alt.name for alt in chosen} if preferred else set()
    out: dict = {}
    for key, spec in sec.fields.items():
        if sec.may_be_absent(key) and key not in named:
            continue
        out[key] = section_defaults(spec, preferred) if isinstance(spec, S.Section) else default_value(spec)
    for alt in chosen:
        fill_alternative(out, sec, alt)
    return out


def new_lamp() -> dict:
    """The normalised lamp a new design starts with: the spec's defaults in the preferred forms."""
    return section_defaults(S.LAMP, preferred=True)


def _num_out(default: Any, spec: S.Num) -> Any:
    if spec.size > 1:
        return [float(x) for x in default]
    return int(default) if spec.integer else float(default)



def fill_alternative(data: dict, sec: S.Section, alt: S.Alternative) -> None:
    """Give ``data`` every field of the form ``alt`` it lacks: the value of its ``same_as``
    field, else its default (in place)."""
    same_as = dict(alt.same_as)
    for key in alt.keys:
        if key not in data:
            if key in same_as:
                data[key] = copy.deepcopy(data[same_as[key]])
            else:
                data[key] = default_value(sec.fields[key])


# ---------------------------------------------------------------------------------------------
# Geometry: derived quantities and the checks that involve several fields


def lens_absorption(lens: dict) -> list[float]:
    """Absorption coefficients per mm (MODEL.md §6: A = -ln(T) / t_ref)."""
    if "absorption" in lens:
        return list(lens["absorption"])
    t_ref = lens["reference_thickness"]
    return [-math.log(c) / t_ref for c in lens["transmitted_color"]]


def without_defaults(data: dict, sec: S.Section = S.SCENE) -> dict:
    """A normalised ``sec`` with every field that holds its default left out (recursively): the
    same design whatever defaulted fields the spec gains later, so a hash of it (a thumbnail's
    name) stays the same when a field is added."""
    out: dict = {}
    for key, value in data.items():
        spec = sec.fields[key]
        if isinstance(spec, S.Section):
            value = without_defaults(value, spec)
            if not value and key not in sec.optional:  # an absent optional section is computed
                continue
        elif isinstance(spec, S.ListOf):
            value = [without_defaults(item, spec.item) for item in value]
        elif sec.rule_of(key) is None and key != "schema" and value == default_value(spec):
            continue  # (a form of an either/or rule is kept: leaving it out would mean the default form)
        out[key] = value
    return out



def use_form(data: dict, sec: S.Section, key: str) -> None:
    """Make ``data`` (a normalised ``sec``) use the form of the either/or rule that writes ``key``
    (in place); nothing changes for a key in no rule or a form already used. The lens colour
    keeps its absorption through the change (MODEL.md §6): a transmitted colour is the one seen
    through the lens's own thickness."""
    rule = sec.rule_of(key)
    if rule is None or rule.chosen(data) is rule.of_key(key):
        return
    alt = rule.of_key(key)
    absorption = lens_absorption(data) if sec is S.LENS else None
    for k in rule.keys:
        data.pop(k, None)
    if absorption is not None and alt.name == "absorption":
        data["absorption"] = absorption
    elif absorption is not None:
        data["transmitted_color"] = [math.exp(-a * data["thickness"]) for a in absorption]
    fill_alternative(data, sec, alt)


def cut_sphere_radius(pitch: float, height: float) -> float:
    """Radius rho of a lenslet sphere (MODEL.md §3.1): (c^2 + h^2) / 2h with c = p / sqrt 2."""
    c = pitch / math.sqrt(2.0)
    return (c * c + height * height) / (2.0 * height)


def lamp_geometry(lamp: dict) -> dict:
    """Derived y positions (mm) of one lamp's parts along its axis (MODEL.md §3). The paraboloid meets
    the rim plane at the outline's reach (its farthest point from the axis, R for a round lens), so
    that, trimmed to the outline's prism, it lies behind the rim plane everywhere."""
    R = lens_reach(lamp["lens"])
    t = lamp["lens"]["thickness"]
    h = lamp["cuts"]["height"]
    f = lamp["reflector"]["focal_length"]
    y_apex = t + h
    y_rim = y_apex + lamp["reflector"]["gap"]
    y_vertex = y_rim + R * R / (4.0 * f)
    y_focus = y_vertex - f
    off = lamp["bulb"]["offset"]
    return {
        "plane_a": t, "plane_b": y_apex, "rim": y_rim, "vertex": y_vertex, "focus": y_focus,
        "bulb_center": (off[0], y_focus + off[1], off[2]),
    }



def lens_reach(lens: dict) -> float:
    """Largest distance from the lamp axis to the lens outline (``Outline.reach``: R for a round lens)."""
    return Outline.of_lens(lens).reach


def default_camera(scene: dict) -> dict:
    """A perspective camera on the -Y side that frames the whole body (16 degree lens)."""
    cam = section_defaults(S.CAMERA)
    body = scene["body"]
    bx, bz = body["center"]
    w, h = body["size"]
    img = scene["image"]
    aspect = img["width"] / img["height"]
    half_fov = math.radians(cam["fov_deg"]) / 2
    # The fov spans the larger image side (sensor fit auto); fit both body sides with a 10 % margin.
    if aspect >= 1:
        half_x, half_z = math.tan(half_fov), math.tan(half_fov) / aspect
    else:
        half_x, half_z = math.tan(half_fov) * aspect, math.tan(half_fov)
    dist = 1.1 * max(w / 2 / half_x, h / 2 / half_z)
    cam["position"] = [float(bx), -round(dist, 3), float(bz)]
    cam["target"] = [float(bx), 0.0, float(bz)]
    return cam


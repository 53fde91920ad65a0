"""Quantities derived from a normalised scene and from the field declarations (``spec``).

The positions of a lamp's parts along its axis, the radius of a cut's sphere, the lens's
absorption from either form of its colour, the default camera, and the defaults a new lamp or
section starts with. Nothing here checks a document: ``validate`` does, and uses these.
"""

from __future__ import annotations

import copy
import math
from typing import Any

from . import spec as S
from .outline import Outline
from .prism_profile import ring_slopes


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
    missing = [key for key in alt.keys if key not in data]
    for key in missing:
        if key in same_as:
            data[key] = copy.deepcopy(data[same_as[key]])
        else:
            data[key] = default_value(sec.fields[key])
    if missing:
        # in the section's order, as the same document read back from its normalised JSON: the
        # hash that names a thumbnail is of the ordered text (``library.presets.digest``)
        ordered = {key: data[key] for key in sec.fields if key in data}
        ordered.update(data)
        data.clear()
        data.update(ordered)


# ---------------------------------------------------------------------------------------------
# Geometry: derived quantities and the checks that involve several fields


def lens_absorption(lens: dict) -> list[float]:
    """Absorption coefficients per mm (docs/model.md §6: A = -ln(T) / t_ref)."""
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
    keeps its absorption through the change (docs/model.md §6): a transmitted colour is the one seen
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
    """Radius rho of a lenslet sphere (docs/model.md §3.1): (c^2 + h^2) / 2h with c = p / sqrt 2."""
    c = pitch / math.sqrt(2.0)
    return (c * c + height * height) / (2.0 * height)


def tooth_height(pitch: float, tooth_angle_deg: float) -> float:
    """Height of a saw-tooth ridge: its inclined facet rises at the tooth angle across one pitch
    to a return facet perpendicular to the lens plane (docs/model.md, model: where the paper is silent)."""
    return pitch * math.tan(math.radians(tooth_angle_deg))


def flute_radius(pitch: float, height: float) -> float:
    """Radius of a flute's cylinder: a circular arc of sag h across the pitch, (p^2/4 + h^2) / 2h."""
    return (pitch * pitch / 4.0 + height * height) / (2.0 * height)


def cut_depth(cuts: dict) -> float:
    """Distance from plane A (the cut base) to plane B (the apexes) for either cut type."""
    if cuts.get("type", "fisheye") == "sawtooth":
        return tooth_height(cuts["pitch"], cuts["tooth_angle"])
    return cuts["height"]


def lamp_geometry(lamp: dict) -> dict:
    """Derived y positions (mm) of one lamp's parts along its axis (docs/model.md §3). The paraboloid meets
    the rim plane at the outline's reach (its farthest point from the axis, R for a round lens), so
    that, trimmed to the outline's prism, it lies behind the rim plane everywhere. For a cylindrical
    lens ``plane_b`` is the deepest point of the cut apexes (at the lens's wrap-side edge), so the
    reflector's rim and the bulb stay behind the whole lens."""
    R = lens_reach(lamp["lens"])
    t = lamp["lens"]["thickness"]
    h = cut_depth(lamp["cuts"])
    if lamp.get("collection", "reflector") == "prism_plate":
        return _prism_plate_geometry(lamp, t + h)
    f = lamp["reflector"]["focal_length"]
    cyl = lens_cylinder(lamp)
    y_apex = t + h if cyl is None else cyl["deepest_apex"]
    y_rim = y_apex + lamp["reflector"]["gap"]
    y_vertex = y_rim + R * R / (4.0 * f)
    y_focus = y_vertex - f
    off = lamp["bulb"]["offset"]
    return {
        "plane_a": t, "plane_b": y_apex, "rim": y_rim, "vertex": y_vertex, "focus": y_focus,
        "bulb_center": (off[0], y_focus + off[1], off[2]),
    }


def _prism_plate_geometry(lamp: dict, y_apex: float) -> dict:
    """Derived y positions of a prism-plate lamp (docs/model.md, the prism plate): the plate's flat front
    face ``plate_front``, its ring bottoms ``plate_base`` and ring tops ``plate_peak``, the focus f
    behind the ring bottoms, and the housing's back (``vertex``: where the socket ends, as for the
    reflector). ``rim`` is where the lens side wall gives way to the housing: the plate's front."""
    plate = lamp["prism_plate"]
    front = y_apex + plate["gap"]
    base = front + plate["thickness"]
    slopes = ring_slopes(lamp["lens"]["radius"], plate["pitch"], plate["focal_length"], plate["ior"])
    focus = base + plate["focal_length"]
    off = lamp["bulb"]["offset"]
    return {
        "plane_a": lamp["lens"]["thickness"], "plane_b": y_apex, "rim": front, "plate_front": front,
        "plate_base": base, "plate_peak": base + float(slopes.max()) * plate["pitch"],
        "vertex": base + plate["housing_depth"], "focus": focus,
        "bulb_center": (off[0], focus + off[1], off[2]),
    }



def lens_cylinder(lamp: dict) -> dict | None:
    """A cylindrical lens's geometry in the lamp's frame (docs/model.md, "cylindrical lens"), or None for
    a flat one.

    The outer face is the cylinder of radius ``radius`` about the vertical line x = ``axis_x``,
    y = ``radius``: it touches the plane y = 0 at the lens outline's edge opposite the wrap side
    (x = -side * half width) and curves
    away toward ``side`` (+1: +x). The cut base lies on the concentric cylinder ``base`` = radius -
    t, the cut apexes on ``apex`` = base - h. Angles ``phi`` are measured about the axis from the
    tangent line (phi = 0 at y = 0), growing toward the wrap side; ``phi_center`` is where the
    lamp axis (x = 0) meets the base, the centre of the cell column i = 0. ``corner`` is the
    radius at which a cap meets its cell's corner edge: the cuts lie between ``apex`` and it."""
    lens = lamp["lens"]
    if lens.get("shape", "flat") != "cylindrical":
        return None
    # the lens's half width: the tangent line is its edge opposite the wrap side
    R = Outline.of_lens(lens).half_w
    t, h, p = lens["thickness"], lamp["cuts"]["height"], lamp["cuts"]["pitch"]
    rc = lens["wrap_radius"]
    side = 1.0 if lens["wrap_toward"] == "+x" else -1.0
    base, apex = rc - t, rc - t - h
    out = {"radius": rc, "side": side, "axis_x": -side * R, "base": base, "apex": apex,
           "phi_center": math.asin(min(1.0, R / base)) if base > 0 else math.nan,
           "deepest_apex": rc - math.sqrt(max(apex * apex - 4 * R * R, 0.0)), "corner": base}
    if h > 0:
        out["corner"] = cap_corner_radius(base, apex, p, cut_sphere_radius(p, h))
    return out


def cap_corner_radius(base: float, apex: float, pitch: float, rho: float) -> float:
    """Radius (from the cylinder axis) where a cell's cap meets the cell's corner edge on a
    cylindrical base: the cap is the fish-eye sphere of the cell's tangent plane (docs/model.md §3.1),
    centred on the cell's radial line at apex + rho; the corner edge is the radial line at the
    half-cell angle p / 2 base, a half-pitch above or below. NaN if the sphere misses it (the cap
    would leave a hole at the corner: validation refuses such cuts)."""
    delta = pitch / (2.0 * base)
    dist = apex + rho
    disc = rho * rho - (pitch / 2) ** 2 - (dist * math.sin(delta)) ** 2
    return dist * math.cos(delta) - math.sqrt(disc) if disc >= 0 else math.nan


def body_wraps(scene: dict) -> list[tuple[float, float, float]]:
    """The curved ends of the body's front (docs/model.md, "cylindrical lens"): per wrap side, (side,
    x of the tangent line in the world, radius). The front is the plane y = 0 between the tangent
    lines and follows each cylindrical lens's outer cylinder beyond its line. Several cylindrical
    lamps curving to one side share one cylinder (validation checks it)."""
    wraps: dict[float, tuple[float, float, float]] = {}
    for lamp in scene["lamps"]:
        cyl = lens_cylinder(lamp)
        if cyl is not None and cyl["side"] not in wraps:
            wraps[cyl["side"]] = (cyl["side"], lamp["center"][0] + cyl["axis_x"], cyl["radius"])
    return [wraps[k] for k in sorted(wraps)]


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


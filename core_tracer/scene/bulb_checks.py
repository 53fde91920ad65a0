"""The bulb of a reflector lamp (docs/model.md §3): the sphere must lie inside the paraboloid (and a
rectangular lens's side wall), behind the cut apex plane. Where it does not, the message names
the radius or the offset that fits, found by bisection; ``bulb_limits`` says the same in words
for the panel."""

from __future__ import annotations

import math

from .messages import interval, lens_size, rounded, show_value
from .outline import Outline
from .reading import SceneError

HALVINGS = 30  # bisection steps for the bulb's limits: 2^-30 of the span, far below the digits shown


def wall_distance(lamp: dict, g: dict, rho: float, y: float) -> float:
    """Distance from the point at radius ``rho`` from the axis and depth ``y`` to the reflector's
    paraboloid y = y_vertex - r^2/(4f), r <= R (the closest point lies in the plane through the axis).
    R is the outline's reach: for a rectangular lens this is the whole paraboloid up to the rim plane,
    of which the trimmed reflector is a part; what lies outside the outline's prism is farther than
    the side wall, which ``bulb_fits`` checks apart."""
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


def bulb_fits(lamp: dict, g: dict, rho: float, y: float, rb: float, toward: tuple[float, float] = (1.0, 0.0)) -> bool:
    """The bulb sphere (centre at radius ``rho`` from the axis in the unit direction ``toward`` [x, z],
    depth ``y``) lies behind the cut apex plane and inside the paraboloid, and for a rectangular lens
    inside the side wall (the outline's prism)."""
    shape = Outline.of_lens(lamp["lens"])
    f, R = lamp["reflector"]["focal_length"], shape.reach
    inside = y < g["vertex"] - rho * rho / (4 * f) and rho < R
    if inside and not shape.round:
        inside = float(shape.signed_distance(rho * toward[0], rho * toward[1])) <= -rb + 1e-9
    return inside and y - rb >= g["plane_b"] - 1e-9 and wall_distance(lamp, g, rho, y) >= rb - 1e-9


def bulb_y_range(lamp: dict, g: dict, rho: float, rb: float,
                  toward: tuple[float, float] = (1.0, 0.0)) -> tuple[float, float] | None:
    """The depths at which the bulb fits at radius ``rho``: from the cut apex plane back to where it
    touches the paraboloid (the clearance shrinks toward the vertex), or None."""
    lo = g["plane_b"] + rb
    if not bulb_fits(lamp, g, rho, lo, rb, toward):
        return None
    hi = g["vertex"]
    for _ in range(HALVINGS):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if bulb_fits(lamp, g, rho, mid, rb, toward) else (lo, mid)
    return g["plane_b"] + rb, lo


def check_bulb(lamp: dict, g: dict, where: str) -> None:
    """The bulb sphere must lie inside the paraboloid, behind the cut apex plane. The message
    blames the radius when the bulb fits nowhere, else the offset with the depths that fit."""
    rb = lamp["bulb"]["radius"]
    bx, by, bz = g["bulb_center"]
    rho = math.hypot(bx, bz)
    toward = (bx / rho, bz / rho) if rho > 0 else (1.0, 0.0)
    if bulb_fits(lamp, g, rho, by, rb, toward):
        return
    off = lamp["bulb"]["offset"]
    on_axis = bulb_y_range(lamp, g, 0.0, rb)
    if on_axis is None:  # too big anywhere: the largest bulb that fits on the axis, found by bisection
        lo, hi = 0.0, rb
        for _ in range(HALVINGS):
            mid = (lo + hi) / 2
            lo, hi = (mid, hi) if bulb_y_range(lamp, g, 0.0, mid) is not None else (lo, mid)
        raise SceneError(f"{where}.bulb.radius", f"{rb:g} does not fit inside the reflector (focal length "
                         f"{lamp['reflector']['focal_length']:g} mm, {lens_size(lamp['lens'])}); "
                         f"allowed (0, {rounded(lo, False)}] mm")
    ys = bulb_y_range(lamp, g, rho, rb, toward)
    if ys is not None:
        y_lo, y_hi = (y - g["focus"] for y in ys)
        raise SceneError(f"{where}.bulb.offset", f"{show_value(off)} puts the bulb (radius {rb:g} mm) outside the "
                         f"reflector; with x = {off[0]:g} and z = {off[2]:g}, allowed y in {interval(y_lo, y_hi)} mm")
    y_shown = float(f"{sum(on_axis) / 2 - g['focus']:.4g}")  # mid-depth on the axis, as printed
    if not on_axis[0] <= y_shown + g["focus"] <= on_axis[1]:  # a range too narrow for 4 digits
        y_shown = float(f"{sum(on_axis) / 2 - g['focus']:.12g}")
    y_mid = y_shown + g["focus"]
    lo, hi = 0.0, Outline.of_lens(lamp["lens"]).reach
    for _ in range(HALVINGS):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if bulb_fits(lamp, g, mid, y_mid, rb, toward) else (lo, mid)
    along = "" if lamp["lens"].get("outline", "round") == "round" else " in the direction of x, z"
    raise SceneError(f"{where}.bulb.offset", f"{show_value(off)} puts the bulb (radius {rb:g} mm) outside the "
                     f"reflector; allowed a distance from the axis sqrt(x^2 + z^2) up to {rounded(lo, False)} mm"
                     f"{along} (at y = {y_shown:.12g} mm)")


def bulb_limits(lamp: dict, g: dict) -> dict[str, str]:
    """The bulb's radius where it sits and the depths (offset y) at which it fits, in words; ``g`` is
    the lamp's ``lamp_geometry``."""
    rb, (x, _, z) = lamp["bulb"]["radius"], lamp["bulb"]["offset"]
    by, rho = g["bulb_center"][1], math.hypot(x, z)
    shape = Outline.of_lens(lamp["lens"])
    f, R = lamp["reflector"]["focal_length"], shape.reach
    toward = (x / rho, z / rho) if rho > 0 else (1.0, 0.0)
    out = {}
    if rho < R and by < g["vertex"] - rho * rho / (4 * f):
        room = min(wall_distance(lamp, g, rho, by), by - g["plane_b"])
        if not shape.round:
            room = min(room, -float(shape.signed_distance(x, z)))
        if room > 0:
            out["bulb.radius"] = f"at most {rounded(room, False)} mm where the bulb sits"
    ys = bulb_y_range(lamp, g, rho, rb, toward)
    if ys is not None:
        y_lo, y_hi = (y - g["focus"] for y in ys)
        out["bulb.offset"] = f"y in {interval(y_lo, y_hi)} mm with x = {x:g} and z = {z:g}"
    return out

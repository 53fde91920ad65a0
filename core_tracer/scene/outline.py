"""The lens outline (docs/model.md "Where the paper is silent": the lens outline): round, a circle of the
lens radius R (the paper's lamp), or rectangular, a rectangle of width w and height h whose
corners are quarter circles of radius r (a square lamp).

Everything that follows the outline asks this module: the eye rays' lens test (``outer_face.lens_at``),
the side wall (the outline extruded along the lamp axis, ``side_wall``), the reflector (the
paraboloid trimmed to that prism), the cut grid (clipped by the wall), validation and the Blender
meshes. Coordinates are the lamp's local x (right) and z (up) from its axis, in mm.

A rounded rectangle is the rectangle [-(w/2 - r), w/2 - r] x [-(h/2 - r), h/2 - r] (its *core*)
grown by r in every direction; a round outline is the same with an empty core and r = R, which is
how the distances between outlines are measured. The tracer keeps the round lens on its own
formulas (the circle's) so that round lamps render bit for bit as before.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

ROUND, RECTANGULAR = "round", "rectangular"


@dataclass(frozen=True)
class Outline:
    """One lamp's lens outline: half width and half height of its bounding box and corner radius, mm
    (a round lens of radius R is ``Outline(R, R, R, round=True)``)."""

    half_w: float
    half_h: float
    corner: float
    round: bool = False

    @classmethod
    def of_lens(cls, lens: dict) -> Outline:
        """The outline of a normalised ``lens`` section."""
        if lens.get("outline", ROUND) == ROUND:
            R = lens["radius"]
            return cls(R, R, R, round=True)
        return cls(lens["width"] / 2.0, lens["height"] / 2.0, lens["corner_radius"])

    @property
    def core(self) -> tuple[float, float]:
        """Half sizes of the core rectangle (the centres of the corner circles)."""
        return self.half_w - self.corner, self.half_h - self.corner

    @property
    def reach(self) -> float:
        """Largest distance from the axis to the outline (the radius of the circle round it): the
        reflector's paraboloid meets the rim plane there."""
        if self.round:
            return self.half_w
        a, b = self.core
        return math.hypot(a, b) + self.corner

    @property
    def area(self) -> float:
        """Area inside the outline, mm^2: w h - (4 - pi) r^2 (pi R^2 for a round lens)."""
        if self.round:
            return math.pi * self.half_w ** 2
        return 4.0 * self.half_w * self.half_h - (4.0 - math.pi) * self.corner ** 2

    def signed_distance(self, x: np.ndarray, z: np.ndarray) -> np.ndarray:
        """Distance from (x, z) to the outline, negative inside."""
        return signed_distance(np.asarray(x, dtype=np.float64), np.asarray(z, dtype=np.float64),
                               *self.core, self.corner)

    def inside(self, x: np.ndarray, z: np.ndarray) -> np.ndarray:
        """Whether each point (x, z) lies inside or on the outline."""
        if self.round:
            return np.asarray(x) ** 2 + np.asarray(z) ** 2 <= self.half_w ** 2
        return self.signed_distance(x, z) <= 0.0

    def gap_to(self, other: Outline, dx: float, dz: float) -> float:
        """Distance between this outline and ``other`` centred (dx, dz) away (negative: overlap)."""
        a1, b1 = self.core
        a2, b2 = other.core
        gx = max(0.0, abs(dx) - a1 - a2)
        gz = max(0.0, abs(dz) - b1 - b2)
        return math.hypot(gx, gz) - self.corner - other.corner

    def perimeter(self, tol: float, max_edge: float = math.inf, round_segments: int | None = None) -> np.ndarray:
        """(n, 2) [x, z] points on the outline, counter-clockwise seen from the front (-y), starting at
        (w/2, 0): a polygon within ``tol`` of the outline (sagitta of each corner arc) whose edges are
        at most ``max_edge`` long. A round outline gives the regular ``round_segments``-gon."""
        if self.round:
            n = round_segments or circle_segment_count(self.half_w, tol)
            a = 2.0 * math.pi * np.arange(n) / n
            return np.column_stack([self.half_w * np.cos(a), self.half_w * np.sin(a)])
        a, b, r = *self.core, self.corner
        hw, hh = self.half_w, self.half_h
        arc = 0
        if r > 0:  # segments per quarter circle: the sagitta within tol, no edge longer than max_edge
            arc = max(circle_segment_count(r, tol, multiple=4) // 4, math.ceil(0.5 * math.pi * r / max_edge - 1e-9))
        points: list[tuple[float, float]] = []

        def line(x0: float, z0: float, x1: float, z1: float) -> None:  # without its end point
            length = math.hypot(x1 - x0, z1 - z0)
            if length > 1e-12:
                pieces = max(1, math.ceil(length / max_edge - 1e-9))
                points.extend((x0 + (x1 - x0) * i / pieces, z0 + (z1 - z0) * i / pieces) for i in range(pieces))

        def corner(cx: float, cz: float, quarter: int) -> None:  # without its end point (none when r = 0)
            for s in range(arc):
                t = 0.5 * math.pi * (quarter + s / arc)
                points.append((cx + r * math.cos(t), cz + r * math.sin(t)))

        line(hw, 0.0, hw, b)
        corner(a, b, 0)
        line(a, hh, -a, hh)
        corner(-a, b, 1)
        line(-hw, b, -hw, -b)
        corner(-a, -b, 2)
        line(-a, -hh, a, -hh)
        corner(a, -b, 3)
        line(hw, -b, hw, 0.0)
        return np.array(points)


def circle_segment_count(radius: float, tol: float, multiple: int = 4, minimum: int = 16) -> int:
    """Segments of a regular polygon in a circle whose sagitta r(1 - cos(pi/n)) is at most tol."""
    if radius <= 0:
        return minimum
    n = minimum if tol >= radius else math.ceil(math.pi / math.acos(1.0 - tol / radius) - 1e-9)
    return max(minimum, -(-n // multiple) * multiple)


def signed_distance(x: np.ndarray, z: np.ndarray, core_x, core_z, corner) -> np.ndarray:
    """Signed distance to the rounded rectangle with core half sizes (core_x, core_z) and corner
    radius ``corner`` (arrays broadcast, per point), negative inside."""
    qx = np.abs(x) - core_x
    qz = np.abs(z) - core_z
    outside = np.hypot(np.maximum(qx, 0.0), np.maximum(qz, 0.0))
    inside = np.minimum(np.maximum(qx, qz), 0.0)
    return outside + inside - corner


def wall_exit(o: np.ndarray, d: np.ndarray, half_w: np.ndarray, half_h: np.ndarray,
              corner: np.ndarray) -> np.ndarray:
    """Per ray from inside the outline's prism (the wall extruded along y), where it leaves it: the
    parameter of its hit on the wall (``inf`` for a ray parallel to the axis; the caller drops
    hits behind the origin).

    The prism is convex, so the exit is where the ray leaves the bounding box unless that point lies
    in a corner square outside the corner's circle; then the ray left through that corner's quarter
    cylinder, at the far root of that circle (a convex set is left once, and the stretch outside it
    but inside the box lies in one corner square)."""
    ox, oz, dx, dz = o[:, 0], o[:, 2], d[:, 0], d[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):  # one for all: d = 0 divides by zero, on purpose
        tx = np.copysign(half_w, dx)
        tx -= ox
        tx /= dx
        tz = np.copysign(half_h, dz)
        tz -= oz
        tz /= dz
        t = np.minimum(tx, tz)
        # (a ray parallel to a pair of sides never meets them: patched, not a select over every ray)
        across_x, across_z = np.nonzero(dx == 0)[0], np.nonzero(dz == 0)[0]
        if len(across_x) or len(across_z):
            tx[across_x] = np.inf
            tz[across_z] = np.inf
            np.minimum(tx, tz, out=t)
        px, pz = t * dx, t * dz  # inf * 0 for a ray along the axis: no corner, no hit
        px += ox
        pz += oz
        core_x, core_z = half_w - corner, half_h - corner
        np.abs(px, out=tx)
        np.abs(pz, out=tz)
        in_corner = tx > core_x
        in_corner &= tz > core_z
        in_corner &= np.isfinite(t)
        k = np.nonzero(in_corner)[0]
        if len(k):
            cx = np.copysign(core_x[k], px[k])
            cz = np.copysign(core_z[k], pz[k])
            ax, az = ox[k] - cx, oz[k] - cz
            a = dx[k] ** 2 + dz[k] ** 2
            b = ax * dx[k] + az * dz[k]
            c = ax * ax + az * az - corner[k] ** 2
            far = (-b + np.sqrt(np.maximum(b * b - a * c, 0.0))) / a
            t[k] = far
    return t

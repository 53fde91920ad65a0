"""The lens solid of a saw-tooth lamp (numpy; no Blender data): the same ridges as the tracer's
``core_tracer/raytrace/parts/sawtooth.py`` (docs/model.md, model: where the paper is silent).

Strip k covers (k - 1/2) p <= s <= (k + 1/2) p across the ridges (s = a . (x, z), a the unit vector
across them, ``ridge_across``); its inclined facet is the plane y = t + tan(alpha) (s - (k - 1/2) p)
and its return facet the plane s = (k + 1/2) p between y = t and y = t + h. Both are planar, so
each facet is one polygon, exact: the band of its strip cut out of the rim polygon (the same rim
polygon as the fish-eye lens, whose sagitta is within the chord tolerance). The rim loop is walked
once, counter-clockwise, with a point wherever a strip border crosses it; every facet, return
facet and side-wall face is made of those points, so the glass is closed.
"""

from __future__ import annotations

import math

import numpy as np

from ....core_tracer.scene.derived import tooth_height
from . import builder
from .builder import MeshBuilder, MeshData, chord_tolerance, collar_top, fan_triangles, rim_polygon, triangle_deviation

ON_BORDER = 1e-9  # mm: a rim vertex this close to a strip border is where the border crosses the rim


def ridge_across(orientation_deg: float) -> tuple[float, float]:
    """[x, z] unit vector across the ridges, the way the facets rise (as the tracer's lamp table)."""
    th = math.radians(orientation_deg)
    return -math.sin(th), math.cos(th)


class _Loop:
    """The rim polygon walked counter-clockwise (seen from -y) with the strip-border crossings
    inserted: per point its [x, z], s, and the surface heights on arrival and on leaving (they
    differ only where a border crosses: the foot and the top of a return facet)."""

    def __init__(self, rim: np.ndarray, across: tuple[float, float], t: float, p: float, h: float):
        self.t, self.p, self.h = t, p, h
        s = rim @ np.array(across)
        self.s_lo, self.s_hi = float(s.min()), float(s.max())
        self.points: list[tuple[float, float, float, float, float]] = []  # x, z, s, y arriving, y leaving
        n = len(rim)
        for i in range(n):
            j = (i + 1) % n
            self._vertex(rim[i], s[i], s[i - 1], s[j])
            lo, hi = sorted((s[i], s[j]))
            ks = [k for k in range(math.ceil(lo / p - 0.5), math.floor(hi / p - 0.5) + 1)
                  if lo + ON_BORDER < (k + 0.5) * p < hi - ON_BORDER]
            for k in ks if s[j] > s[i] else reversed(ks):
                b = (k + 0.5) * p
                f = (b - s[i]) / (s[j] - s[i])
                x, z = rim[i] + f * (rim[j] - rim[i])
                self._crossing(float(x), float(z), b, rising=s[j] > s[i])

    def height(self, s: float, k: int) -> float:
        """The inclined facet of strip k at s, exact at the strip's borders."""
        u = s - (k - 0.5) * self.p
        if abs(u) <= ON_BORDER:
            return self.t
        if abs(u - self.p) <= ON_BORDER:
            return self.t + self.h
        return self.t + self.h * u / self.p

    def strip(self, s: float) -> int:
        return math.floor(s / self.p + 0.5)

    def _vertex(self, xz: np.ndarray, s: float, s_prev: float, s_next: float) -> None:
        k = self.strip(s)
        b = next((c for c in ((k - 0.5) * self.p, (k + 0.5) * self.p) if abs(c - s) <= ON_BORDER), None)
        if b is None:
            y = self.height(s, k)
        elif (s_prev < b < s_next or s_prev > b > s_next) and self.s_lo + ON_BORDER < b < self.s_hi - ON_BORDER:
            self._crossing(float(xz[0]), float(xz[1]), b, rising=s_next > s_prev)
            return
        else:  # the rim touches the border here from one side: the vertex belongs to that side's strip
            kb = round(b / self.p - 0.5)  # the border between strips kb and kb + 1
            # (a point along a side lying on the border has the lens on one side only: above the
            # lowest border, below the highest)
            above = max(s_prev, s_next) > b + ON_BORDER or (min(s_prev, s_next) >= b - ON_BORDER
                                                             and b <= self.s_lo + ON_BORDER)
            y = self.height(b, kb + 1 if above else kb)
        self.points.append((float(xz[0]), float(xz[1]), float(s), y, y))

    def _crossing(self, x: float, z: float, b: float, rising: bool) -> None:
        top, foot = self.t + self.h, self.t
        self.points.append((x, z, b, top, foot) if rising else (x, z, b, foot, top))


def sawtooth_lens_mesh(lamp: dict, segments: int, tol: float | None = None,
                       rim: np.ndarray | None = None) -> MeshData:
    """The lens solid of a saw-tooth lamp, relative to its axis: outer disk at y = 0, one flat
    polygon per inclined facet and per return facet, the side wall from y = 0 to the cut surface
    and the open collar above it up to the apex plane (material ``LENS_SIDE_WALL``), as
    ``fisheye.fisheye_lens_mesh`` for fish-eye cuts. ``rim`` is the lens outline, any convex polygon
    counter-clockwise seen from -y (default: the round lens's ``rim_polygon(R, segments)``).
    ``max_deviation`` is the measured distance of the facets' vertices from their analytic planes
    and of the side wall from the cylinder of the round lens."""
    tol = chord_tolerance(tol)
    R, t = lamp["lens"]["radius"], lamp["lens"]["thickness"]
    cuts = lamp["cuts"]
    p, across = cuts["pitch"], ridge_across(cuts["orientation"])
    h = tooth_height(p, cuts["tooth_angle"])
    loop = _Loop(rim_polygon(R, segments) if rim is None else rim, across, t, p, h)
    mb = MeshBuilder()
    ids = [(mb.vertex(x, ya, z), mb.vertex(x, yl, z)) for x, z, _, ya, yl in loop.points]
    n = len(ids)

    # Inclined facets: each strip's points of the loop in loop order (at a border the top for the
    # strip below it, the foot for the strip above), reversed to face +y, out of the glass.
    for k in range(loop.strip(loop.s_lo), loop.strip(loop.s_hi) + 1):
        lo, hi = (k - 0.5) * p, (k + 0.5) * p
        face, span = [], []
        for (_, _, s, ya, _), (arrive, leave) in zip(loop.points, ids, strict=True):
            if lo - ON_BORDER <= s <= hi + ON_BORDER:
                on_hi, on_lo = abs(s - hi) <= ON_BORDER, abs(s - lo) <= ON_BORDER
                want = t + h if on_hi else t if on_lo else None
                face.append(arrive if want is None or ya == want else leave)
                span.append(s)
        if not span or max(span) - min(span) <= 2 * ON_BORDER:
            continue  # no facet: the rim only touches the strip's border (a side lying on it)
        mb.face(face[::-1], builder.FLAT, builder.LENS_GLASS)
    facets = len(mb.faces)

    # Return facets: the two crossings of each border, foot to top, wound to face +a (the air).
    crossings: dict[float, list[int]] = {}
    for j, (_, _, s, ya, yl) in enumerate(loop.points):
        if ya != yl:
            crossings.setdefault(s, []).append(j)
    for _, pair in sorted(crossings.items()):
        j1, j2 = pair  # a border line crosses the convex rim twice
        feet = [ids[j][loop.points[j][3] != t] for j in (j1, j2)]  # arriving at the top: the foot leaves
        tops = [ids[j][loop.points[j][3] == t] for j in (j1, j2)]
        quad = [feet[0], feet[1], tops[1], tops[0]]
        v = np.array([mb.verts[i] for i in quad[:3]])
        normal = np.cross(v[1] - v[0], v[2] - v[1])
        facing = normal[0] * across[0] + normal[2] * across[1] > 0
        mb.face(quad if facing else quad[::-1], builder.FLAT, builder.LENS_GLASS)
    walls = len(mb.faces)

    # Side wall below the cut surface, collar above it: between consecutive rim points, taking in
    # the other vertex of a crossing where it lies on the face's vertical edge (no T-junctions).
    top = collar_top(lamp)
    bottom = []
    for j in range(n):
        x, z, _, _, _ = loop.points[j]
        bottom.append(mb.vertex(x, 0.0, z))
    for j in range(n):
        j1 = (j + 1) % n
        (xa, za, _, ya_a, yl_a), (xb, zb, _, ya_b, yl_b) = loop.points[j], loop.points[j1]
        left_used, left_other = ids[j][1], ids[j][0]  # leave point j, arrive at point j1
        right_used, right_other = ids[j1][0], ids[j1][1]
        left_mid = [left_other] if ya_a < yl_a else []  # under the used (higher) vertex
        right_mid = [right_other] if yl_b < ya_b else []
        mb.face([bottom[j], *left_mid, left_used, right_used, *right_mid, bottom[j1]], 1, builder.LENS_SIDE_WALL)
        top_a = mb.vertex(xa, top(xa, za) if callable(top) else top, za)
        top_b = mb.vertex(xb, top(xb, zb) if callable(top) else top, zb)
        left_up = [left_other] if ya_a > yl_a else []  # between the used (lower) vertex and the top
        right_up = [right_other] if yl_b > ya_b else []
        mb.face([left_used, *left_up, top_a, top_b, *right_up, right_used], 1, builder.LENS_SIDE_WALL)
    side = mb.faces[walls:]
    mb.face(bottom, builder.FLAT, builder.LENS_GLASS)  # outer face, counter-clockwise seen from -y

    data = mb.result()
    data.max_deviation = max(facet_deviation(data, facets, walls, lamp),
                             triangle_deviation(data.verts, fan_triangles(side),
                                                lambda q: np.abs(np.hypot(q[:, 0], q[:, 2]) - R)))
    return data


def facet_deviation(data: MeshData, facets: int, walls: int, lamp: dict) -> float:
    """Largest distance of a facet polygon's vertices from its analytic plane: the inclined facet
    of the strip holding the polygon's centroid, the return facet's border plane."""
    t, p = lamp["lens"]["thickness"], lamp["cuts"]["pitch"]
    a = np.array(ridge_across(lamp["cuts"]["orientation"]))
    m = math.tan(math.radians(lamp["cuts"]["tooth_angle"]))
    worst = 0.0
    for f, face in enumerate(data.faces[:walls]):
        v = data.verts[list(face)]
        s = v[:, [0, 2]] @ a
        if f < facets:
            k = math.floor(float(s.mean()) / p + 0.5)
            worst = max(worst, float(np.max(np.abs(v[:, 1] - t - m * (s - (k - 0.5) * p)))) / math.hypot(1, m))
        else:
            worst = max(worst, float(np.max(np.abs(s - s.mean()))))
    return worst

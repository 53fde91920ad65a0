"""The lens solid of a lamp with cylindrical flutes (numpy; no Blender data): the same flutes as the
tracer's ``core_tracer/raytrace/parts/flutes.py``.

Each flute is cut into bands along the ridges, between lines evenly spaced in angle on its
cylinder (x = rho sin(theta) across it), as many as keep the chord's sagitta within the tolerance;
a band is planar (two parallel lines on the cylinder), so it is one polygon, the band cut out of the
rim polygon. The rim loop is walked once with a point wherever a band line crosses it, and every
band and side-wall face is made of those points, so the glass is closed. One smoothing group per
flute: smooth across its bands, sharp at the creases between flutes.
"""

from __future__ import annotations

import math

import numpy as np

from ....core_tracer.scene.derived import flute_radius
from .builder import (
    FLAT,
    LENS_GLASS,
    SAMPLED_MARGIN,
    MeshBuilder,
    MeshData,
    chord_tolerance,
    collar_top,
    fan_triangles,
    rim_polygon,
    side_wall,
    triangle_deviation,
)
from .sawtooth import ridge_across

ON_LINE = 1e-9  # mm
# The flutes' own tolerance, finer than the caps' (``CUT_TOLERANCE_MM``): a band is one polygon, so the
# paper's lens has 2,300 triangles at it, and its light is within 0.15 % of the parametric lamp's
# (0.5 % at 0.0075 mm, where the bands' creases alias with the pixels: benchmarks/bench_freeform_agreement.py).
FLUTE_TOLERANCE_MM = 0.0025


def bands_per_flute(pitch: float, rho: float, tol: float) -> int:
    """Bands across one flute so that each chord's sagitta rho (1 - cos(phi / 2)) is within tol."""
    half = math.asin(min(1.0, pitch / 2.0 / rho))
    phi = 2.0 * math.acos(max(-1.0, 1.0 - SAMPLED_MARGIN * tol / rho))
    return max(1, math.ceil(2.0 * half / phi - 1e-9))


def flutes_lens_mesh(lamp: dict, segments: int, tol: float | None = None,
                     rim: np.ndarray | None = None) -> MeshData:
    """The lens solid of a fluted lamp, relative to its axis, as ``fisheye.fisheye_lens_mesh`` for fish-eye
    cuts (outer face, cut surface, side wall and open collar up to the apex plane). ``rim``: the
    lens outline, any convex polygon counter-clockwise seen from -y (default: the round lens's)."""
    tol = chord_tolerance(tol)
    R, t = lamp["lens"]["radius"], lamp["lens"]["thickness"]
    p, h = lamp["cuts"]["pitch"], lamp["cuts"]["height"]
    a = np.array(ridge_across(lamp["cuts"]["orientation"]))
    rim = rim_polygon(R, segments) if rim is None else rim
    s_rim = rim @ a
    k_lo, k_hi = math.floor(s_rim.min() / p + 0.5), math.floor(s_rim.max() / p + 0.5)
    if h == 0:
        per, rho = 1, math.inf
        across = np.array([-p / 2, p / 2])
    else:
        rho = flute_radius(p, h)
        per = bands_per_flute(p, rho, min(tol, FLUTE_TOLERANCE_MM))
        half = math.asin(min(1.0, p / 2.0 / rho))
        across = rho * np.sin(np.linspace(-half, half, per + 1))
        across[0], across[-1] = -p / 2, p / 2
    lines = (np.arange(k_lo, k_hi + 1)[:, None] * p + across[None, :-1]).ravel()
    lines = np.append(lines, (k_hi + 0.5) * p)
    offsets = np.append(np.tile(across[:-1], k_hi - k_lo + 1), across[-1])
    heights = np.full(len(lines), t) if h == 0 else \
        t + h - offsets ** 2 / (rho + np.sqrt(np.maximum(rho * rho - offsets ** 2, 0.0)))
    heights[np.abs(np.abs(offsets) - p / 2) <= ON_LINE] = t  # the creases lie on plane A exactly

    # The rim loop with the band lines' crossings.
    points: list[tuple[float, float, float]] = []  # x, z, s
    n = len(rim)
    for i in range(n):
        j = (i + 1) % n
        points.append((float(rim[i, 0]), float(rim[i, 1]), float(s_rim[i])))
        lo, hi = sorted((s_rim[i], s_rim[j]))
        inside = lines[(lines > lo + ON_LINE) & (lines < hi - ON_LINE)]
        for line in (inside if s_rim[j] > s_rim[i] else inside[::-1]):
            f = (line - s_rim[i]) / (s_rim[j] - s_rim[i])
            x, z = rim[i] + f * (rim[j] - rim[i])
            points.append((float(x), float(z), float(line)))
    mb = MeshBuilder()
    s_pts = np.array([q[2] for q in points])
    y_pts = np.interp(s_pts, lines, heights)  # exact on the lines, the band's plane between them
    ring = [mb.vertex(x, y, z) for (x, z, _), y in zip(points, y_pts, strict=True)]

    for m in range(len(lines) - 1):
        inside = np.flatnonzero((s_pts >= lines[m] - ON_LINE) & (s_pts <= lines[m + 1] + ON_LINE))
        if len(inside) == 0 or np.ptp(s_pts[inside]) <= 2 * ON_LINE:
            continue  # no band: the rim only touches its line (a side lying on a crease between flutes)
        face = [ring[i] for i in inside]
        flute = math.floor((lines[m] + lines[m + 1]) / 2 / p + 0.5)
        mb.face(face[::-1], FLAT if h == 0 else 4096 + flute - k_lo, LENS_GLASS)
    cut_faces = list(mb.faces)
    bottom = side_wall(mb, ring, collar_top(lamp))
    side = mb.faces[len(cut_faces):]
    mb.face(bottom, FLAT, LENS_GLASS)

    data = mb.result()

    def distance(q: np.ndarray) -> np.ndarray:
        s = q[:, [0, 2]] @ a
        if h == 0:
            return np.abs(q[:, 1] - t)
        u = s - np.floor(s / p + 0.5) * p
        return np.abs(np.hypot(u, q[:, 1] - (t + h - rho)) - rho)

    data.max_deviation = max(triangle_deviation(data.verts, fan_triangles(cut_faces), distance),
                             triangle_deviation(data.verts, fan_triangles(side),
                                                lambda q: np.abs(np.hypot(q[:, 0], q[:, 2]) - R)))
    return data

"""The lamp's parts other than the lens: the reflector (whole, or trimmed to a rectangular lens's
outline), the bulb, the socket and the body with its openings (docs/model.md §3.2; numpy, no Blender data).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from ....core_tracer.scene.derived import lamp_geometry
from .builder import (
    FLAT,
    MAX_SEGMENTS,
    SAMPLED_MARGIN,
    MeshBuilder,
    MeshData,
    chord_tolerance,
    circle_segments,
    fan_triangles,
    triangle_deviation,
)

# ---------------------------------------------------------------------------------------------
# Reflector (docs/model.md §3.2)


def paraboloid_distance(vertex_y: float, focal_length: float) -> Callable[[np.ndarray], np.ndarray]:
    """Distance to y = y_v - r^2 / 4f, to first order (vertical offset times the cosine of the slope)."""

    def distance(points: np.ndarray) -> np.ndarray:
        r = np.hypot(points[:, 0], points[:, 2])
        dy = points[:, 1] - (vertex_y - r * r / (4.0 * focal_length))
        return np.abs(dy) / np.sqrt(1.0 + (r / (2.0 * focal_length)) ** 2)

    return distance


def reflector_mesh(lamp: dict, segments: int, tol: float | None = None) -> MeshData:
    """The paraboloid from the rim (radius R, y = rim) to the vertex, normals toward the lamp interior.

    Rings are spaced evenly in arc length along the profile. ``segments`` (shared with the lens rim and
    the body opening) is raised if the measured deviation needs it; ``MeshData.group`` is one smooth
    group.
    """
    tol = chord_tolerance(tol)
    R = lamp["lens"]["radius"]
    f = lamp["reflector"]["focal_length"]
    yv = lamp_geometry(lamp)["vertex"]
    distance = paraboloid_distance(yv, f)
    # Every principal radius of curvature is >= 2f: a chord of length L sags at most L^2 / (16 f).
    chord = math.sqrt(16.0 * f * tol)
    r_dense = np.linspace(0.0, R, 2049)
    s_dense = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(r_dense), np.diff(r_dense ** 2) / (4 * f)))])
    rings = max(2, math.ceil(s_dense[-1] / (chord / math.sqrt(2.0))))
    n = segments
    while True:
        data = _revolve(np.interp(np.linspace(0.0, s_dense[-1], rings + 1), s_dense, r_dense),
                        lambda r: yv - r * r / (4.0 * f), n, inward=True)
        dev = triangle_deviation(data.verts, fan_triangles(data.faces), distance)
        if dev <= SAMPLED_MARGIN * tol or n >= MAX_SEGMENTS:
            data.max_deviation = dev
            return data
        rings = math.ceil(rings * 1.25)
        n = min(MAX_SEGMENTS, n + 4 * max(1, n // 16))



def trimmed_reflector_mesh(lamp: dict, rim: np.ndarray, tol: float | None = None) -> MeshData:
    """The paraboloid trimmed to a rectangular lens's prism (docs/model.md: the lens outline): rows of points
    s P_k for the rim polygon's vertices P_k and fractions s from 0 (the vertex) to 1 (the rim, on the
    side wall), spaced evenly in arc length along the longest profile; refined until measured."""
    tol = chord_tolerance(tol)
    f = lamp["reflector"]["focal_length"]
    yv = lamp_geometry(lamp)["vertex"]
    distance = paraboloid_distance(yv, f)
    reach = float(np.hypot(rim[:, 0], rim[:, 1]).max())
    chord = math.sqrt(16.0 * f * tol)
    r_dense = np.linspace(0.0, reach, 2049)
    s_dense = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(r_dense), np.diff(r_dense ** 2) / (4 * f)))])
    rings = max(2, math.ceil(s_dense[-1] / (chord / math.sqrt(2.0))))
    for _ in range(12):
        fractions = np.interp(np.linspace(0.0, s_dense[-1], rings + 1), s_dense, r_dense) / reach
        data = _fan(rim, fractions, lambda x, z: yv - (x * x + z * z) / (4.0 * f))
        data.max_deviation = triangle_deviation(data.verts, fan_triangles(data.faces), distance)
        if data.max_deviation <= SAMPLED_MARGIN * tol:
            break
        rings = math.ceil(rings * 1.25)
    return data


def _fan(rim: np.ndarray, fractions: np.ndarray, height: Callable) -> MeshData:
    """The surface y = height(x, z) over a star-shaped polygon: rows fractions[j] * rim from the pole
    (fractions[0] = 0) out to the rim, wound as ``_revolve(inward=True)``: normals toward the lamp interior."""
    mb = MeshBuilder()
    pole = mb.vertex(0.0, float(height(0.0, 0.0)), 0.0)
    rows = [[mb.vertex(s * x, float(height(s * x, s * z)), s * z) for x, z in rim.tolist()] for s in fractions[1:]]
    n = len(rim)
    for k in range(n):
        k1 = (k + 1) % n
        mb.face([pole, rows[0][k], rows[0][k1]], 0)
        for j in range(len(rows) - 1):
            mb.face([rows[j][k], rows[j + 1][k], rows[j + 1][k1], rows[j][k1]], 0)
    return mb.result()


def _revolve(radii: np.ndarray, profile: Callable[[np.ndarray], np.ndarray], segments: int,
             inward: bool) -> MeshData:
    """A surface of revolution about the y axis through radii[0] = 0 (a pole) ... radii[-1]."""
    mb = MeshBuilder()
    a = 2.0 * math.pi * np.arange(segments) / segments
    ys = profile(radii)
    pole = mb.vertex(0.0, float(ys[0]), 0.0)
    rows = [[mb.vertex(r * math.cos(t), float(y), r * math.sin(t)) for t in a]
            for r, y in zip(radii[1:], ys[1:], strict=True)]
    for k in range(segments):
        k1 = (k + 1) % segments
        tri = [pole, rows[0][k], rows[0][k1]]
        mb.face(tri if inward else tri[::-1], 0)
        for j in range(len(rows) - 1):
            quad = [rows[j][k], rows[j + 1][k], rows[j + 1][k1], rows[j][k1]]
            mb.face(quad if inward else quad[::-1], 0)
    return mb.result()


# ---------------------------------------------------------------------------------------------
# Bulb and socket


def sphere_mesh(radius: float, tol: float | None = None) -> MeshData:
    """A UV sphere about the origin (poles on the z axis), outward normals, smooth; measured like the rest."""
    tol = chord_tolerance(tol)
    n = circle_segments(radius, tol / 2.0, multiple=4, minimum=16)
    center = np.zeros(3)

    def distance(points: np.ndarray) -> np.ndarray:
        return np.abs(np.linalg.norm(points - center, axis=1) - radius)

    while True:
        data = _uv_sphere(radius, n)
        dev = triangle_deviation(data.verts, fan_triangles(data.faces), distance)
        if dev <= SAMPLED_MARGIN * tol or n >= MAX_SEGMENTS:
            data.max_deviation = dev
            return data
        n = min(MAX_SEGMENTS, n + 4 * max(1, n // 16))


def _uv_sphere(radius: float, segments: int) -> MeshData:
    mb = MeshBuilder()
    rings = segments // 2
    lon = 2.0 * math.pi * np.arange(segments) / segments
    south = mb.vertex(0.0, 0.0, -radius)
    north = mb.vertex(0.0, 0.0, radius)
    rows = []
    for i in range(1, rings):
        lat = -math.pi / 2 + math.pi * i / rings
        rows.append([mb.vertex(radius * math.cos(lat) * math.cos(t), radius * math.cos(lat) * math.sin(t),
                               radius * math.sin(lat)) for t in lon])
    for k in range(segments):
        k1 = (k + 1) % segments
        mb.face([south, rows[0][k1], rows[0][k]], 0)
        for j in range(len(rows) - 1):
            mb.face([rows[j][k], rows[j][k1], rows[j + 1][k1], rows[j + 1][k]], 0)
        mb.face([north, rows[-1][k], rows[-1][k1]], 0)
    return mb.result()


def socket_mesh(radius: float, y0: float, y1: float, tol: float | None = None) -> MeshData:
    """A capped cylinder on the lamp axis from y0 to y1 (y0 > y1 allowed); smooth side, flat caps."""
    tol = chord_tolerance(tol)
    n = circle_segments(radius, tol, multiple=4, minimum=16)
    lo, hi = min(y0, y1), max(y0, y1)
    mb = MeshBuilder()
    a = 2.0 * math.pi * np.arange(n) / n
    ring_lo = [mb.vertex(radius * math.cos(t), lo, radius * math.sin(t)) for t in a]
    ring_hi = [mb.vertex(radius * math.cos(t), hi, radius * math.sin(t)) for t in a]
    for k in range(n):
        k1 = (k + 1) % n
        mb.face([ring_lo[k], ring_hi[k], ring_hi[k1], ring_lo[k1]], 0)
    mb.face(ring_lo, FLAT)  # faces -y
    mb.face(ring_hi[::-1], FLAT)  # faces +y
    data = mb.result()
    side = [f for f, g in zip(data.faces, data.group, strict=True) if g == 0]
    data.max_deviation = triangle_deviation(data.verts, fan_triangles(side),
                                            lambda q: np.abs(np.hypot(q[:, 0], q[:, 2]) - radius))
    return data


def led_mesh(*arrays) -> MeshData:
    """The dies of ``LedArray``s (a lamp's, and its mirror image for a guide lit at both ends) as flat
    rectangles in the lamp's frame, each wound so that its normal is the dies' (across × up = normal)."""
    mb = MeshBuilder()
    for leds in arrays:
        a, b = leds.half_size[0] * leds.across, leds.half_size[1] * leds.up
        for centre in leds.die_centres():
            corners = [centre - a - b, centre + a - b, centre + a + b, centre - a + b]
            mb.face([mb.vertex(*map(float, c)) for c in corners], FLAT)
    data = mb.result()
    data.max_deviation = 0.0  # flat: exact
    return data


# ---------------------------------------------------------------------------------------------
# Body


def body_mesh(scene: dict, rims: Sequence[np.ndarray], bores: Sequence[tuple[float, float]],
              triangulate: Callable[[list], list]) -> MeshData:
    """The body box with one opening per lamp in its front face (y = 0), in scene coordinates.

    ``rims[i]`` is lamp i's rim polygon in scene [x, z] (the lens rim, counter-clockwise from -y);
    ``bores[i]`` = (y_from, y_to) is the cylindrical wall of the opening between the lens side wall
    and the reflector rim (the reflector gap; empty when the gap is 0). ``triangulate`` fills a polygon
    with holes (``mathutils.geometry.tessellate_polygon``).
    """
    body = scene["body"]
    bx, bz = body["center"]
    w, hgt = body["size"]
    depth = body["depth"]
    x0, x1, z0, z1 = bx - w / 2, bx + w / 2, bz - hgt / 2, bz + hgt / 2
    mb = MeshBuilder()
    outline = [(x0, z0), (x1, z0), (x1, z1), (x0, z1)]
    loops = [outline] + [[(float(x), float(z)) for x, z in rim] for rim in rims]
    points = [p for loop in loops for p in loop]
    index = [mb.vertex(x, 0.0, z) for x, z in points]
    for tri in triangulate([[(x, z, 0.0) for x, z in loop] for loop in loops]):
        face = [index[i] for i in tri]
        (ax, az), (bx_, bz_), (cx, cz) = (points[i] for i in tri)
        if (bx_ - ax) * (cz - az) - (bz_ - az) * (cx - ax) < 0:  # counter-clockwise in [x, z] faces -y
            face.reverse()
        mb.face(face, FLAT)
    corners = {(i, j, k): mb.vertex((x0, x1)[i], (0.0, depth)[j], (z0, z1)[k])
               for i in (0, 1) for j in (0, 1) for k in (0, 1)}
    c = corners
    mb.face([c[0, 1, 0], c[0, 1, 1], c[1, 1, 1], c[1, 1, 0]], FLAT)  # back, +y
    mb.face([c[0, 0, 0], c[0, 0, 1], c[0, 1, 1], c[0, 1, 0]], FLAT)  # left, -x
    mb.face([c[1, 0, 0], c[1, 1, 0], c[1, 1, 1], c[1, 0, 1]], FLAT)  # right, +x
    mb.face([c[0, 0, 0], c[0, 1, 0], c[1, 1, 0], c[1, 0, 0]], FLAT)  # bottom, -z
    mb.face([c[0, 0, 1], c[1, 0, 1], c[1, 1, 1], c[0, 1, 1]], FLAT)  # top, +z
    add_bores(mb, rims, bores)
    return mb.result()


def add_bores(mb: MeshBuilder, rims: Sequence[np.ndarray], bores: Sequence[tuple[float, float]]) -> None:
    """The body's bore around each lens: a tube along y from y_a to y_b through the rim's [x, z]
    polygon, material slot 2 + i (none where the bore has no length)."""
    for i, (rim, (y_a, y_b)) in enumerate(zip(rims, bores, strict=True)):
        if y_b - y_a <= 1e-9:
            continue
        front = [mb.vertex(float(x), y_a, float(z)) for x, z in rim]
        back = [mb.vertex(float(x), y_b, float(z)) for x, z in rim]
        for k in range(len(rim)):
            k1 = (k + 1) % len(rim)
            mb.face([front[k], front[k1], back[k1], back[k]], 2 + i)  # normals toward the lamp axis

"""Meshes of a cylindrical lens and of a body whose front curves round to the side (docs/model.md, "the
cylindrical lens"), numpy only, in the conventions of the package (mm, x right, y into the lamp, z
up; faces wound so that normals point out of the solid).

The lens is built as the tracer sees it (``core_tracer.scene.derived.lens_cylinder``): the cut
surface is the flat lens's grid of k x k quads per cell laid out by arc length on the base
cylinder, every grid point put on its cell's cap along the cell's radial line (neighbouring
caps meet there, so shared points agree); the quads are clipped by the lens outline seen along
the lamp axis (the tracer's side wall, a prism along y), the points where the outline cuts them
put on their cap along y. The outer face is the outer cylinder inside the outline, cut into
strips along the cylinder's axis narrow enough for the chord tolerance; the side wall joins the
two along the outline and continues as the open collar to the deepest cut apex. Every part is
measured against its analytic surface (``MeshData.max_deviation``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from ....core_tracer.scene.derived import cut_sphere_radius, lamp_geometry, lens_cylinder
from ....core_tracer.scene.outline import Outline
from .builder import (
    FLAT,
    LENS_GLASS,
    LENS_SIDE_WALL,
    SAMPLED_MARGIN,
    MeshBuilder,
    MeshData,
    chord_tolerance,
    clip_convex,
    fan_triangles,
    triangle_deviation,
)
from .fisheye import CutSurface, cell_lines
from .parts import add_bores


def strip_lines(x_t: float, stop: float, radius: float, tol: float | None = None) -> np.ndarray:
    """Lines x = const from the tangent line ``x_t`` of a cylinder of ``radius`` (axis at x_t)
    toward ``stop`` (either side), ``stop`` included, evenly spaced in angle about the axis so
    that the chord across each strip, radius (1 - cos(dphi / 2)) off the cylinder, stays within
    ``tol`` (with the measuring margin)."""
    tol = chord_tolerance(tol)
    u = min(abs(stop - x_t) / radius, 1.0)
    phi_end = math.asin(u)
    step = 2.0 * math.acos(1.0 - SAMPLED_MARGIN * tol / radius)
    n = max(1, math.ceil(phi_end / step - 1e-9))
    x = x_t + math.copysign(radius, stop - x_t) * np.sin(phi_end * np.arange(n + 1) / n)
    x[-1] = stop
    return x


class _Cuts:
    """The cut surface of a cylindrical lens in the lamp's frame."""

    def __init__(self, lamp: dict):
        self.cyl = cyl = lens_cylinder(lamp)
        self.p, h = lamp["cuts"]["pitch"], lamp["cuts"]["height"]
        self.rho = None if h == 0 else cut_sphere_radius(self.p, h)
        self.side, self.ax, self.rc = cyl["side"], cyl["axis_x"], cyl["radius"]
        self.base, self.apex, self.phi_c = cyl["base"], cyl["apex"], cyl["phi_center"]

    def phi(self, u: np.ndarray) -> np.ndarray:
        return self.phi_c + u / self.base

    def centre(self, i, j) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Centre (x, y, z) of the cap sphere of cell (i, j)."""
        phi_i = self.phi(np.asarray(i, dtype=np.float64) * self.p)
        dist = self.apex + self.rho
        return self.ax + self.side * dist * np.sin(phi_i), self.rc - dist * np.cos(phi_i), np.asarray(j) * self.p

    def point(self, u: np.ndarray, z: np.ndarray, i: np.ndarray, j: np.ndarray) -> np.ndarray:
        """The cut surface of cell (i, j) on the radial line at arc length u, height z."""
        phi = self.phi(u)
        if self.rho is None:
            r = np.full(np.shape(u), self.base)
        else:
            dist = self.apex + self.rho
            delta = phi - self.phi(np.asarray(i, dtype=np.float64) * self.p)
            dz = z - np.asarray(j) * self.p
            r = dist * np.cos(delta) - np.sqrt(np.maximum(self.rho ** 2 - dz * dz - (dist * np.sin(delta)) ** 2, 0.0))
        return np.stack([self.ax + self.side * r * np.sin(phi), self.rc - r * np.cos(phi), np.asarray(z, float)], -1)

    def y_at(self, x: float, z: float, i: int, j: int) -> float:
        """Depth y of the cell's cap above (x, z): the root of its sphere on the cap (axis) side."""
        if self.rho is None:
            return self.rc - math.sqrt(max(self.base ** 2 - (x - self.ax) ** 2, 0.0))
        cx, cy, cz = (float(v) for v in self.centre(i, j))
        return cy + math.sqrt(max(self.rho ** 2 - (x - cx) ** 2 - (z - cz) ** 2, 0.0))

    def distance(self, q: np.ndarray) -> np.ndarray:
        """Distance of points near the cut surface to the cap sphere of their cell."""
        X, Y = q[:, 0] - self.ax, q[:, 1] - self.rc
        if self.rho is None:
            return np.abs(np.hypot(X, Y) - self.base)
        phi = np.arctan2(self.side * X, -Y)
        i = np.floor((phi - self.phi_c) * self.base / self.p + 0.5)
        j = np.floor(q[:, 2] / self.p + 0.5)
        cx, cy, cz = self.centre(i, j)
        return np.abs(np.sqrt((q[:, 0] - cx) ** 2 + (q[:, 1] - cy) ** 2 + (q[:, 2] - cz) ** 2) - self.rho)


def _ccw(poly: Sequence[tuple[float, float]]) -> bool:
    return sum(poly[i - 1][0] * poly[i][1] - poly[i][0] * poly[i - 1][1] for i in range(len(poly))) > 0


def cylindrical_lens_mesh(lamp: dict, rim: np.ndarray, k: int, tol: float | None = None) -> MeshData:
    """The lens solid of a lamp with a cylindrical lens, relative to its axis; ``rim`` is the
    outline polygon in [x, z], convex, counter-clockwise seen from -y; ``k`` quads per cell side."""
    tol = chord_tolerance(tol)
    cuts = _Cuts(lamp)
    cyl, p = cuts.cyl, cuts.p
    surface = CutSurface(lamp["lens"]["thickness"], p, lamp["cuts"]["height"], cuts.rho)
    across = cell_lines(surface, k)[:-1]
    half_w = float(np.max(np.abs(rim[:, 0])))
    # arc lengths reached inside the outline, down to the apex cylinder (the deepest the cuts go)
    u_far = cuts.base * (math.asin(min(1.0, 2 * half_w / cyl["apex"])) - cuts.phi_c)
    u_near = -cuts.base * cuts.phi_c
    i_lo, i_hi = math.floor(u_near / p - 0.5) - 1, math.ceil(u_far / p + 0.5) + 1
    j_max = math.ceil(float(np.max(np.abs(rim[:, 1]))) / p + 0.5)
    u_lines = np.append((np.arange(i_lo, i_hi + 1)[:, None] * p + across[None, :]).ravel(), (i_hi + 0.5) * p)
    z_lines = np.append((np.arange(-j_max, j_max + 1)[:, None] * p + across[None, :]).ravel(), (j_max + 0.5) * p)
    u_cell = np.arange(len(u_lines) - 1) // k + i_lo
    z_cell = np.arange(len(z_lines) - 1) // k - j_max

    edges = np.roll(rim, -1, axis=0) - rim

    # every quad's corners on its cell's cap, at once: (quads, 4, 3)
    qa, qb = (g.ravel() for g in np.meshgrid(np.arange(len(u_lines) - 1), np.arange(len(z_lines) - 1), indexing="ij"))
    corner_u = np.stack([u_lines[qa], u_lines[qa + 1], u_lines[qa + 1], u_lines[qa]], axis=1)
    corner_z = np.stack([z_lines[qb], z_lines[qb], z_lines[qb + 1], z_lines[qb + 1]], axis=1)
    qi, qj = u_cell[qa], z_cell[qb]
    all_pts = cuts.point(corner_u, corner_z, qi[:, None], qj[:, None])
    rel = all_pts[:, :, None, :][..., [0, 2]] - rim[None, None, :, :]
    cross = edges[None, None, :, 0] * rel[..., 1] - edges[None, None, :, 1] * rel[..., 0]  # (quads, 4, edges)
    outside = (cross < 0).all(axis=1).any(axis=1)  # wholly outside one edge of the outline
    inside = (cross >= -1e-9 * np.hypot(edges[:, 0], edges[:, 1])[None, None, :]).all(axis=(1, 2))

    mb = MeshBuilder()
    cut_faces: list[list[int]] = []
    for q_index in np.flatnonzero(~outside).tolist():
        i, j = int(qi[q_index]), int(qj[q_index])
        pts = all_pts[q_index]
        if inside[q_index]:
            poly3 = [tuple(q) for q in pts.tolist()]
        else:
            xz = pts[:, [0, 2]]
            corners_uz = list(zip(corner_u[q_index].tolist(), corner_z[q_index].tolist(), strict=True))
            poly = [tuple(q) for q in xz.tolist()]
            flip = not _ccw(poly)
            clipped = clip_convex(poly[::-1] if flip else poly, rim, range(len(rim)))
            if len(clipped) < 3:
                continue
            lookup = {(round(x * 1e9), round(z * 1e9)): q for (x, z), q in zip(poly, pts.tolist(), strict=True)}
            poly3 = []
            for x, z in clipped:
                q = lookup.get((round(x * 1e9), round(z * 1e9)))
                if q is None:
                    # a point where the outline crosses a quad edge: on a border between cells both
                    # neighbours must make the same point, so the lower cell's cap decides
                    ci, cj = _edge_cell(x, z, xz, corners_uz, p)
                    q = (x, cuts.y_at(x, z, min(i, ci), min(j, cj)), z)
                poly3.append(tuple(q))
        face = [mb.vertex(*q) for q in poly3]
        face = [v for n, v in enumerate(face) if v != face[n - 1]]
        if len(face) < 3:
            continue
        # wound so that the normal (Newell's, of the polygon) points out of the glass, toward the
        # cylinder axis (the air)
        vs = [mb.verts[v] for v in face]
        nx = sum((a[1] - b[1]) * (a[2] + b[2]) for a, b in zip(vs, vs[1:] + vs[:1], strict=True))
        ny = sum((a[2] - b[2]) * (a[0] + b[0]) for a, b in zip(vs, vs[1:] + vs[:1], strict=True))
        mx = sum(v[0] for v in vs) / len(vs) - cuts.ax
        my = sum(v[1] for v in vs) / len(vs) - cuts.rc
        if nx * mx + ny * my > 0:
            face.reverse()
        cut_faces.append(face)
        mb.face(face, int((i + 1000) * 4096 + j + 1000), LENS_GLASS)

    # the cut surface's boundary: its points on the outline, counter-clockwise about the axis
    verts = np.array(mb.verts)
    on_rim = np.flatnonzero(_on_polygon(verts[:, [0, 2]], rim))
    ring = on_rim[np.argsort(np.arctan2(verts[on_rim, 2], verts[on_rim, 0]), kind="stable")].tolist()

    def y_outer(x: float) -> float:
        return cuts.rc - math.sqrt(cuts.rc ** 2 - (x - cuts.ax) ** 2)

    lines = strip_lines(cuts.ax, -cuts.ax, cuts.rc, tol)
    ring_xz = [(mb.verts[v][0], mb.verts[v][2]) for v in ring]
    outer_xz: list[tuple[float, float]] = []
    between: list[list[tuple[float, float]]] = []  # strip-line crossings on each ring edge
    for n_, (x0, z0) in enumerate(ring_xz):
        x1, z1 = ring_xz[(n_ + 1) % len(ring_xz)]
        outer_xz.append((x0, z0))
        lo, hi = min(x0, x1), max(x0, x1)
        xs = sorted((x for x in lines if lo + 1e-9 < x < hi - 1e-9), reverse=x1 < x0)
        cross = [(x, z0 + (z1 - z0) * (x - x0) / (x1 - x0)) for x in xs]
        outer_xz += cross
        between.append(cross)

    bottom = [mb.vertex(x, y_outer(x), z) for x, z in ring_xz]
    y_top = lamp_geometry(lamp)["plane_b"]
    top = [mb.vertex(x, y_top, z) for x, z in ring_xz]
    side_faces, collar = [], []
    for n_ in range(len(ring)):
        n1 = (n_ + 1) % len(ring)
        extra = [mb.vertex(x, y_outer(x), z) for x, z in reversed(between[n_])]
        side_faces.append([bottom[n_], ring[n_], ring[n1], bottom[n1], *extra])
        mb.face(side_faces[-1], 1, LENS_SIDE_WALL)
        collar.append([ring[n_], top[n_], top[n1], ring[n1]])
        mb.face(collar[-1], 1, LENS_SIDE_WALL)

    outer_faces = []
    poly = np.array(outer_xz)
    for x0, x1 in zip(lines[:-1], lines[1:], strict=True):
        lo, hi = min(x0, x1), max(x0, x1)
        strip = np.array([(lo, -1e9), (hi, -1e9), (hi, 1e9), (lo, 1e9)])
        piece = clip_convex([tuple(q) for q in poly], strip, range(4))
        face = [mb.vertex(x, y_outer(x), z) for x, z in piece]
        face = [v for n_, v in enumerate(face) if v != face[n_ - 1]]
        if len(face) >= 3:
            outer_faces.append(face)
            mb.face(face, FLAT, LENS_GLASS)  # counter-clockwise seen from -y: out of the glass

    data = mb.result()
    outline = Outline.of_lens(lamp["lens"])
    data.max_deviation = max(
        triangle_deviation(data.verts, fan_triangles(cut_faces), cuts.distance),
        triangle_deviation(data.verts, fan_triangles(outer_faces),
                           lambda q: np.abs(np.hypot(q[:, 0] - cuts.ax, q[:, 1] - cuts.rc) - cuts.rc)),
        triangle_deviation(data.verts, fan_triangles(side_faces + collar),
                           lambda q: np.abs(outline.signed_distance(q[:, 0], q[:, 2]))))
    return data


def _edge_cell(x: float, z: float, xz: np.ndarray, corners_uz: list, pitch: float) -> tuple[int, int]:
    """The cell (i, j) of the quad's edge through (x, z), the lower one on a border between cells
    ((10^9, 10^9) for a point on no edge: an outline corner inside the quad)."""
    best, cell = 1e-7, (10 ** 9, 10 ** 9)
    for e in range(4):
        a, b = xz[e], xz[(e + 1) % 4]
        ab = b - a
        f = min(1.0, max(0.0, float(np.dot((x, z) - a, ab) / max(np.dot(ab, ab), 1e-300))))
        dist = math.hypot(*((a + f * ab) - (x, z)))
        if dist < best:
            u = corners_uz[e][0] + f * (corners_uz[(e + 1) % 4][0] - corners_uz[e][0])
            w = corners_uz[e][1] + f * (corners_uz[(e + 1) % 4][1] - corners_uz[e][1])
            best, cell = dist, (math.floor(u / pitch + 0.5 - 1e-9), math.floor(w / pitch + 0.5 - 1e-9))
    return cell


def _on_polygon(xz: np.ndarray, poly: np.ndarray, eps: float = 1e-6) -> np.ndarray:
    """Points within ``eps`` of the boundary of polygon ``poly``."""
    a = poly[None, :, :]
    e = (np.roll(poly, -1, axis=0) - poly)[None, :, :]
    rel = xz[:, None, :] - a
    f = np.clip((rel * e).sum(-1) / (e * e).sum(-1), 0.0, 1.0)
    dist = np.hypot(*(rel - f[..., None] * e).transpose(2, 0, 1))
    return dist.min(axis=1) <= eps


def outer_rim(data: MeshData, lamp: dict) -> np.ndarray:
    """The [x, z] loop where the lens's outer face meets its side wall (for the body's opening),
    counter-clockwise seen from -y: the outer face's boundary vertices."""
    cyl = lens_cylinder(lamp)
    v = data.verts
    on = np.abs(np.hypot(v[:, 0] - cyl["axis_x"], v[:, 1] - cyl["radius"]) - cyl["radius"]) < 1e-6
    outline = Outline.of_lens(lamp["lens"])
    on &= np.abs(outline.signed_distance(v[:, 0], v[:, 2])) < 0.5
    pts = v[on][:, [0, 2]]
    keep = _on_polygon(pts, _hull(pts))
    pts = pts[keep]
    return pts[np.argsort(np.arctan2(pts[:, 1], pts[:, 0]), kind="stable")]


def _hull(pts: np.ndarray) -> np.ndarray:
    """Convex hull of [x, z] points, counter-clockwise (monotone chain)."""
    order = sorted(map(tuple, pts.tolist()))

    def half(seq):
        out: list = []
        for q in seq:
            while len(out) >= 2 and ((out[-1][0] - out[-2][0]) * (q[1] - out[-2][1])
                                     - (out[-1][1] - out[-2][1]) * (q[0] - out[-2][0])) <= 0:
                out.pop()
            out.append(q)
        return out

    return np.array(half(order)[:-1] + half(order[::-1])[:-1])


# ---------------------------------------------------------------------------------------------
# Body


def front_depth(wraps: Sequence[tuple[float, float, float]]) -> Callable[[float], float]:
    """y of the body's front at x (``core_tracer.scene.derived.body_wraps``)."""
    def f(x: float) -> float:
        for side, x_t, radius in wraps:
            u = side * (x - x_t)
            if u > 0:
                return radius - math.sqrt(max(radius * radius - u * u, 0.0))
        return 0.0
    return f


def body_mesh_wrapped(scene: dict, rims: Sequence[np.ndarray], bores: Sequence[tuple[float, float]],
                      wraps: Sequence[tuple[float, float, float]], triangulate: Callable[[list], list],
                      tol: float | None = None) -> MeshData:
    """``parts.body_mesh`` for a front that curves round to the side: the front triangulated with
    its openings in [x, z], cut along the strip lines of each curved end and lifted onto the front."""
    tol = chord_tolerance(tol)
    body = scene["body"]
    bx, bz = body["center"]
    w, hgt = body["size"]
    depth = body["depth"]
    x0, x1, z0, z1 = bx - w / 2, bx + w / 2, bz - hgt / 2, bz + hgt / 2
    f = front_depth(wraps)
    lines = [x0, x1]
    for side, x_t, radius in wraps:
        edge = x1 if side > 0 else x0
        lines += strip_lines(x_t, edge, radius, tol).tolist()
    lines = sorted({round(x, 9) for x in lines if x0 - 1e-9 <= x <= x1 + 1e-9})

    mb = MeshBuilder()
    outline = [(x0, z0), (x1, z0), (x1, z1), (x0, z1)]
    loops = [outline] + [[(float(x), float(z)) for x, z in rim] for rim in rims]
    points = [q for loop in loops for q in loop]
    front_faces = []
    for tri in triangulate([[(x, z, 0.0) for x, z in loop] for loop in loops]):
        poly = [points[i] for i in tri]
        if not _ccw(poly):
            poly.reverse()  # counter-clockwise in [x, z] faces -y
        lo, hi = min(q[0] for q in poly), max(q[0] for q in poly)
        cuts = [x for x in lines if lo < x < hi]
        for a, b in zip([lo, *cuts], [*cuts, hi], strict=True):
            strip = np.array([(a, -1e9), (b, -1e9), (b, 1e9), (a, 1e9)])
            piece = clip_convex(poly, strip, range(4)) if cuts else poly
            face = [mb.vertex(x, f(x), z) for x, z in piece]
            face = [v for n, v in enumerate(face) if v != face[n - 1]]
            if len(face) >= 3:
                front_faces.append(face)
                mb.face(face, FLAT)
    edge_x = [x for x in lines if x0 - 1e-9 <= x <= x1 + 1e-9]
    bottom_front = [mb.vertex(x, f(x), z0) for x in edge_x]
    top_front = [mb.vertex(x, f(x), z1) for x in edge_x]
    c = {(i, k): mb.vertex((x0, x1)[i], depth, (z0, z1)[k]) for i in (0, 1) for k in (0, 1)}
    mb.face([c[0, 0], c[0, 1], c[1, 1], c[1, 0]], FLAT)  # back, +y
    mb.face([bottom_front[0], top_front[0], c[0, 1], c[0, 0]], FLAT)  # left, -x
    mb.face([bottom_front[-1], c[1, 0], c[1, 1], top_front[-1]], FLAT)  # right, +x
    mb.face([*bottom_front, c[1, 0], c[0, 0]][::-1], FLAT)  # bottom, -z
    mb.face([*top_front, c[1, 1], c[0, 1]], FLAT)  # top, +z
    add_bores(mb, rims, bores)
    data = mb.result()

    def distance(q: np.ndarray) -> np.ndarray:
        return np.abs(q[:, 1] - np.array([f(x) for x in q[:, 0]]))

    data.max_deviation = triangle_deviation(data.verts, fan_triangles(front_faces), distance)
    return data

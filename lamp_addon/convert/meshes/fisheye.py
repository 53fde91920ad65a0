"""The lens solid of a lamp with spherical lenslet cuts (docs/model.md §3, §3.1; numpy, no Blender data):
the outer disk, the cut surface (a grid of quads per lenslet cell clipped by the rim polygon) and the
side wall with its collar. Also the cut surface's grid for the cylindrical lens (``wrap``).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Sequence

import numpy as np

from ....core_tracer.scene.derived import cut_sphere_radius
from ....core_tracer.scene.outline import Outline
from .builder import (
    FLAT,
    LENS_GLASS,
    MAX_CELL_SUBDIVISION,
    SAMPLED_MARGIN,
    SNAP_MM,
    MeshBuilder,
    MeshData,
    chord_tolerance,
    clip_convex,
    collar_top,
    cut_tolerance,
    fan_triangles,
    outline_rim,
    polygon_area,
    rim_polygon,
    side_wall,
    triangle_deviation,
)


class CutSurface:
    """The inner face of the lens: y(x, z) over the square lenslet grid (docs/model.md §3.1)."""

    def __init__(self, thickness: float, pitch: float, height: float, sphere_radius: float | None):
        self.t, self.p, self.h = thickness, pitch, height
        self.rho = sphere_radius  # None when h = 0 (a flat inner face)

    def cell_center(self, x: np.ndarray, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Centre [x, z] of the cell holding each point (one cell is centred on the axis)."""
        return np.round(x / self.p) * self.p, np.round(z / self.p) * self.p

    def height(self, x: np.ndarray, z: np.ndarray) -> np.ndarray:
        x, z = np.asarray(x, dtype=np.float64), np.asarray(z, dtype=np.float64)
        if self.rho is None:
            return np.full(np.broadcast(x, z).shape, self.t)
        cx, cz = self.cell_center(x, z)
        d2 = (x - cx) ** 2 + (z - cz) ** 2
        return self.t + self.h - self.rho + np.sqrt(np.maximum(self.rho * self.rho - d2, 0.0))

    def distance(self, points: np.ndarray) -> np.ndarray:
        """Distance of points (on or near the surface) to the cap sphere of their cell, mm."""
        x, y, z = points[:, 0], points[:, 1], points[:, 2]
        if self.rho is None:
            return np.abs(y - self.t)
        cx, cz = self.cell_center(x, z)
        cy = self.t + self.h - self.rho
        return np.abs(np.sqrt((x - cx) ** 2 + (y - cy) ** 2 + (z - cz) ** 2) - self.rho)


def cell_lines(surface: CutSurface, k: int) -> np.ndarray:
    """The k + 1 grid lines across one cell, offsets from its centre, -p/2 ... p/2.

    Evenly spaced in angle on the cap sphere (x = rho sin(theta)), i.e. in arc length along the cell's
    axes, so the quads are smaller where the cap is steep; evenly spaced on a flat face.
    """
    half = surface.p / 2.0
    if surface.rho is None:
        lines = np.linspace(-half, half, k + 1)
    else:
        edge = math.asin(min(1.0, half / surface.rho))
        lines = surface.rho * np.sin(np.linspace(-edge, edge, k + 1))
    lines[0], lines[-1] = -half, half
    return lines


def cut_subdivision(surface: CutSurface, tol: float | None = None,
                    most: int = MAX_CELL_SUBDIVISION) -> tuple[int, float]:
    """Quads per side of a cell so that one whole cell is within ``tol``, at most ``most``; returns
    (k, deviation)."""
    tol = chord_tolerance(tol)
    if surface.rho is None:
        return 1, 0.0
    # Start from the sagitta estimate L^2 / (8 rho) along the cell's axes, then measure.
    arc = 2.0 * surface.rho * math.asin(min(1.0, surface.p / 2.0 / surface.rho))
    k = min(most, max(1, math.ceil(arc / math.sqrt(8.0 * surface.rho * tol))))
    while True:
        u = cell_lines(surface, k)
        gx, gz = np.meshgrid(u, u, indexing="ij")
        verts = np.column_stack([gx.ravel(), surface.height(gx, gz).ravel(), gz.ravel()])
        idx = np.arange((k + 1) ** 2).reshape(k + 1, k + 1)
        quads = np.column_stack([idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(),
                                 idx[:-1, 1:].ravel()])
        dev = triangle_deviation(verts, fan_triangles(quads.tolist()), surface.distance)
        if dev <= SAMPLED_MARGIN * tol or k >= most:
            return k, dev
        k = min(most, k + max(1, k // 4))


def _rim_edges_near(quad: list[tuple[float, float]], rim: np.ndarray, holds_axis: bool) -> list[int]:
    """The rim polygon's edges whose angular sector (seen from the axis) overlaps the quad's.

    The rim polygon is convex around the axis, so a point is inside it exactly when it is inside the
    edge whose sector holds the point's angle: clipping by these few edges is clipping by all.
    """
    n = len(rim)
    if holds_axis:
        return list(range(n))
    mid = math.atan2(sum(z for _, z in quad), sum(x for x, _ in quad))
    rel = [math.remainder(math.atan2(z, x) - mid, 2.0 * math.pi) for x, z in quad]
    step = 2.0 * math.pi / n
    first = math.floor((mid + min(rel)) / step)
    last = math.floor((mid + max(rel)) / step)
    return [e % n for e in range(first, last + 1)]


def _sector_edges(rim: np.ndarray) -> Callable[[list[tuple[float, float]], bool], list[int]]:
    """``_rim_edges_near`` for any convex rim polygon around the axis starting at angle 0 (a
    rectangular outline's): the edges whose angular sectors overlap the quad's, one more each side
    (a further edge's half-plane holds the whole rim, so clipping by it too changes nothing)."""
    n = len(rim)
    angles = np.mod(np.arctan2(rim[:, 1], rim[:, 0]), 2.0 * math.pi)
    angles[0] = 0.0

    def edges(quad: list[tuple[float, float]], holds_axis: bool) -> list[int]:
        if holds_axis:
            return list(range(n))
        mid = math.atan2(sum(z for _, z in quad), sum(x for x, _ in quad))
        rel = [math.remainder(math.atan2(z, x) - mid, 2.0 * math.pi) for x, z in quad]
        lo = (mid + min(rel)) % (2.0 * math.pi)
        hi = lo + max(rel) - min(rel)
        first = int(np.searchsorted(angles, lo, side="right")) - 1
        if hi >= 2.0 * math.pi:
            last = int(np.searchsorted(angles, hi - 2.0 * math.pi, side="right")) - 1 + n
        else:
            last = int(np.searchsorted(angles, hi, side="right")) - 1
        return sorted({e % n for e in range(first - 1, last + 2)})

    return edges


def _with_rim_vertices(poly: list, rim: np.ndarray, edge_list: Sequence[int]) -> list:
    """``poly`` (clipped by ``rim``) with the rim's vertices that lie inside its edges added: clipping
    by two collinear rim edges (a straight side split in pieces) leaves out the vertex between them,
    which the side wall and the reflector's edge share."""
    n = len(rim)
    candidates = {tuple(rim[e]) for e in edge_list} | {tuple(rim[(e + 1) % n]) for e in edge_list}
    out = []
    for i, p in enumerate(poly):
        out.append(p)
        q = poly[(i + 1) % len(poly)]
        ex, ez = q[0] - p[0], q[1] - p[1]
        length2 = ex * ex + ez * ez
        if length2 < 1e-18:
            continue
        between = []
        for v in candidates:
            u = ((v[0] - p[0]) * ex + (v[1] - p[1]) * ez) / length2
            if 1e-9 < u < 1 - 1e-9 and abs((v[0] - p[0]) * ez - (v[1] - p[1]) * ex) < 1e-9 * math.sqrt(length2):
                between.append((u, v))
        out += [v for _, v in sorted(between)]
    return out


def fisheye_lens_mesh(lamp: dict, segments: int, tol: float | None = None,
                      max_subdivision: int = MAX_CELL_SUBDIVISION, rim: np.ndarray | None = None) -> MeshData:
    """The lens solid of one lamp with spherical lenslet cuts, relative to its axis.

    Outer disk at y = 0 (flat), the cut surface (a grid of k x k quads per lenslet cell, clipped by the
    rim polygon; smooth within a cell, sharp creases between cells), and the side wall of radius R
    from y = 0 up to the cut apex plane y = t + h (material ``LENS_SIDE_WALL``; the part above the cut
    surface is the open collar the tracer also has). The glass is closed (watertight). At most
    ``max_subdivision`` quads per cell side (a lighter preview when smaller than the tolerance needs);
    when it is at least what ``tol`` needs, the cut surface is built to ``CUT_TOLERANCE_MM`` instead.

    A rectangular lens (``outline``) is clipped by its rim polygon ``rim`` (``outline_rim``, shared with
    the reflector and the body) instead of the regular ``segments``-gon, and its side wall's collar
    stands up to the reflector's edge, which lies behind the rim plane along the straight sides (docs/model.md:
    the lens outline).
    """
    tol = chord_tolerance(tol)
    R, t = lamp["lens"]["radius"], lamp["lens"]["thickness"]
    p, h = lamp["cuts"]["pitch"], lamp["cuts"]["height"]
    shape = Outline.of_lens(lamp["lens"])
    surface = CutSurface(t, p, h, None if h == 0 else cut_sphere_radius(p, h))
    if max_subdivision >= cut_subdivision(surface, tol)[0]:  # not a preview: to the cuts' own tolerance
        k, dev_cell = cut_subdivision(surface, min(tol, cut_tolerance()))
    else:
        k, dev_cell = cut_subdivision(surface, tol, max_subdivision)
    if shape.round:
        grid = _CutGrid(surface, k, R)
        rim = rim_polygon(R, segments)
        cut = grid.polygons(rim, R * math.cos(math.pi / segments))
    else:
        rim = outline_rim(lamp, tol) if rim is None else rim
        grid = _CutGrid(surface, k, max(shape.half_w, shape.half_h))
        cut = grid.polygons_in(rim, shape, tol)
    xz, cut_faces, cut_groups = cut.welded()
    verts = np.column_stack([xz[:, 0], surface.height(xz[:, 0], xz[:, 1]), xz[:, 1]])
    ring = _rim_ring(verts, R, segments) if shape.round else _polygon_ring(verts, rim, shape, tol)

    mb = MeshBuilder()
    mb.add_vertices(verts, weld=ring)  # the side wall welds to the rim ring (a cell apex on the rim is its top)
    mb.faces += cut_faces
    mb.material += [LENS_GLASS] * len(cut_faces)
    mb.group += cut_groups
    bottom = side_wall(mb, ring, collar_top(lamp), group=1 if shape.round or shape.corner > 0 else FLAT)
    side_faces = mb.faces[len(cut_faces):]
    mb.face(bottom, FLAT, LENS_GLASS)  # outer face, counter-clockwise seen from -y

    data = mb.result()
    # Whole quads are copies of the cell measured by cut_subdivision; measure the faces on the rim here.
    on_rim = np.zeros(len(verts), dtype=bool)
    on_rim[ring] = True
    sizes = np.fromiter(map(len, cut_faces), dtype=np.int64, count=len(cut_faces))
    flat = np.fromiter(itertools.chain.from_iterable(cut_faces), dtype=np.int64, count=int(sizes.sum()))
    touches = np.logical_or.reduceat(on_rim[flat], np.concatenate([[0], np.cumsum(sizes)[:-1]]))
    clipped = [cut_faces[i] for i in np.flatnonzero(touches)]
    dev_cut = max(dev_cell, triangle_deviation(data.verts, fan_triangles(clipped), surface.distance))
    if shape.round:
        dev_side = triangle_deviation(data.verts, fan_triangles(side_faces),
                                      lambda q: np.abs(np.hypot(q[:, 0], q[:, 2]) - R))
    else:
        dev_side = triangle_deviation(data.verts, fan_triangles(side_faces),
                                      lambda q: np.abs(shape.signed_distance(q[:, 0], q[:, 2])))
    data.max_deviation = max(dev_cut, dev_side)
    return data


class _CutGrid:
    """The grid of the cut surface over the lens: the same k + 1 lines across every cell (``cell_lines``),
    for cells -c ... c around the axis, in x and in z alike.

    Grid vertex (a, b) is the point (lines[a], lines[b]) with index ``a * size + b``; quad (a, b) lies
    between lines a, a + 1 and b, b + 1, in cell (cell[a], cell[b]), one smoothing group per cell.
    """

    def __init__(self, surface: CutSurface, k: int, radius: float):
        p = surface.p
        cells = math.ceil(radius / p + 0.5)
        across = cell_lines(surface, k)[:-1]  # the last line of a cell is the first of the next
        self.lines = np.append((np.arange(-cells, cells + 1)[:, None] * p + across[None, :]).ravel(),
                               cells * p + p / 2)
        self.size = len(self.lines)
        self.cell = np.arange(self.size - 1) // k - cells
        lo, hi = self.lines[:-1], self.lines[1:]
        self.near = np.where((lo <= 0) & (hi >= 0), 0.0, np.minimum(np.abs(lo), np.abs(hi)))
        self.far = np.maximum(np.abs(lo), np.abs(hi))

    def group(self, a, b):
        """Smoothing group of quad (a, b): its cell (>= 4096, clear of the side wall's group 1)."""
        return (self.cell[a] + 1000) * 4096 + self.cell[b] + 1000

    def polygons(self, rim: np.ndarray, apothem: float) -> _CutPolygons:
        """The quads inside the rim polygon, and the quads across it clipped by it."""
        near2 = self.near[:, None] ** 2 + self.near[None, :] ** 2
        far2 = self.far[:, None] ** 2 + self.far[None, :] ** 2
        a_idx, b_idx = np.meshgrid(np.arange(self.size - 1), np.arange(self.size - 1), indexing="ij")
        inside = far2 <= apothem * apothem
        across = ~inside & (near2 < rim[0, 0] ** 2)  # rim[0] = (R, 0)

        # Reversed counter-clockwise order in [x, z] makes the normal point +y, out of the glass.
        a, b, s = a_idx[inside], b_idx[inside], self.size
        quads = np.column_stack([a * s + b + 1, (a + 1) * s + b + 1, (a + 1) * s + b, a * s + b])
        out = _CutPolygons(self, quads, self.group(a, b).tolist())
        for a, b in zip(a_idx[across].tolist(), b_idx[across].tolist(), strict=True):
            out.add_clipped(a, b, rim, holds_axis=self.near[a] == 0.0 and self.near[b] == 0.0)
        return out


    def polygons_in(self, rim: np.ndarray, shape: Outline, tol: float) -> _CutPolygons:
        """``polygons`` for any convex rim polygon inscribed in ``shape`` within ``tol``: quads whose
        corners lie deeper inside the outline than ``tol`` are whole, those that reach its bounding
        box otherwise are clipped (one still whole comes back unchanged)."""
        gx, gz = np.meshgrid(self.lines, self.lines, indexing="ij")
        deep = shape.signed_distance(gx, gz) < -1.01 * tol
        inside = deep[:-1, :-1] & deep[1:, :-1] & deep[1:, 1:] & deep[:-1, 1:]
        lo, hi = self.lines[:-1], self.lines[1:]
        reach_x, reach_z = (hi > -shape.half_w) & (lo < shape.half_w), (hi > -shape.half_h) & (lo < shape.half_h)
        across = ~inside & reach_x[:, None] & reach_z[None, :]
        a_idx, b_idx = np.meshgrid(np.arange(self.size - 1), np.arange(self.size - 1), indexing="ij")
        a, b, s = a_idx[inside], b_idx[inside], self.size
        quads = np.column_stack([a * s + b + 1, (a + 1) * s + b + 1, (a + 1) * s + b, a * s + b])
        out = _CutPolygons(self, quads, self.group(a, b).tolist())
        edges = _sector_edges(rim)
        for a, b in zip(a_idx[across].tolist(), b_idx[across].tolist(), strict=True):
            out.add_clipped(a, b, rim, holds_axis=self.near[a] == 0.0 and self.near[b] == 0.0, edges_near=edges)
        return out


class _CutPolygons:
    """Cut-surface polygons over grid vertices and, after them, the points where the rim cuts the grid:
    the whole quads (an (n, 4) array), then the clipped polygons (a list)."""

    def __init__(self, grid: _CutGrid, quads: np.ndarray, groups: list[int]):
        self.grid, self.quads, self.groups = grid, quads, groups
        self.polygons: list[tuple[int, ...]] = []
        self.rim_points: list[tuple[float, float]] = []
        self._rim_index: dict[tuple[int, int], int] = {}
        self._near: dict[tuple[int, int], list[int]] = {}  # rim points by SNAP_MM square
        self.moved: dict[int, tuple[float, float]] = {}  # grid vertices moved onto a rim point
        self._corners: dict[tuple[int, int], tuple[float, float]] = {}  # the rim polygon's vertices (by 1e-6 mm)

    def add_clipped(self, a: int, b: int, rim: np.ndarray, holds_axis: bool,
                    edges_near: Callable | None = None) -> None:
        """Quad (a, b) clipped by the rim polygon, if anything of it is left (``edges_near``: the rim
        edges that can cut a quad, ``_rim_edges_near`` of a regular rim by default)."""
        if not self._corners:
            self._corners = {(round(x * 1e6), round(z * 1e6)): (x, z) for x, z in rim.tolist()}
        x, s = self.grid.lines, self.grid.size
        corners = {(x[a], x[b]): a * s + b, (x[a + 1], x[b]): (a + 1) * s + b,
                   (x[a + 1], x[b + 1]): (a + 1) * s + b + 1, (x[a], x[b + 1]): a * s + b + 1}
        near = edges_near(list(corners), holds_axis) if edges_near is not None else \
            _rim_edges_near(list(corners), rim, holds_axis)
        poly = clip_convex(list(corners), rim, near)
        if edges_near is not None:
            poly = _with_rim_vertices(poly, rim, near)
        if len(poly) < 3 or polygon_area(poly) < 1e-9:
            return
        face: list[int] = []
        for point in reversed(poly):
            i = corners.get(point)
            if i is None:
                i = self._rim_point(point)
            if not face or (i != face[-1] and i != face[0]):
                face.append(i)
        if len(face) >= 3:
            self.polygons.append(tuple(face))
            self.groups.append(int(self.grid.group(a, b)))  # the cell: one smooth cap

    def _rim_point(self, point: tuple[float, float]) -> int:
        """The vertex of a point on the rim: a grid vertex within ``SNAP_MM`` (moved onto the rim), an
        earlier rim point within ``SNAP_MM``, or a new one; a vertex of the rim polygon (which the side
        wall and the reflector's edge share) is where such a vertex ends up."""
        key = (round(point[0] * 1e6), round(point[1] * 1e6))
        i = self._rim_index.get(key)
        if i is not None:
            return i
        corner = key in self._corners
        point = self._corners.get(key, point)
        lines, size = self.grid.lines, self.grid.size
        a, b = (min(max(int(np.searchsorted(lines, c)), 1), size - 1) for c in point)
        a -= abs(lines[a - 1] - point[0]) < abs(lines[a] - point[0])
        b -= abs(lines[b - 1] - point[1]) < abs(lines[b] - point[1])
        if abs(lines[a] - point[0]) <= SNAP_MM and abs(lines[b] - point[1]) <= SNAP_MM:
            i = a * size + b
            if corner or i not in self.moved:
                self.moved[i] = point
            return i
        cx, cz = math.floor(point[0] / SNAP_MM), math.floor(point[1] / SNAP_MM)
        for dx, dz in itertools.product((-1, 0, 1), repeat=2):
            for j in self._near.get((cx + dx, cz + dz), ()):
                q = self.rim_points[j - size ** 2]
                if math.hypot(q[0] - point[0], q[1] - point[1]) <= SNAP_MM:
                    if corner:
                        self.rim_points[j - size ** 2] = point
                    return j
        i = self._rim_index[key] = size ** 2 + len(self.rim_points)
        self.rim_points.append(point)
        self._near.setdefault((cx, cz), []).append(i)
        return i

    def welded(self) -> tuple[np.ndarray, list[tuple[int, ...]], list[int]]:
        """([x, z] of the vertices in use, faces over them, their groups): unused grid vertices dropped,
        a rim point that falls on a grid vertex (to 1e-6 mm) welded to it, repeats left by welding dropped."""
        grid_count = self.grid.size ** 2
        flat = np.concatenate([self.quads.ravel(), np.fromiter(itertools.chain.from_iterable(self.polygons),
                                                               dtype=np.int64)])
        used = np.unique(flat)
        on_grid = used < grid_count
        xz = np.empty((len(used), 2))
        xz[on_grid, 0] = self.grid.lines[used[on_grid] // self.grid.size]
        xz[on_grid, 1] = self.grid.lines[used[on_grid] % self.grid.size]
        if self.rim_points:
            xz[~on_grid] = np.array(self.rim_points)[used[~on_grid] - grid_count]
        for i, point in self.moved.items():
            at = np.searchsorted(used, i)
            if at < len(used) and used[at] == i:
                xz[at] = point
        keys = np.round(xz * 1e6).astype(np.int64)
        _, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
        order = np.argsort(first)  # vertices in the order they were first used
        rank = np.empty_like(order)
        rank[order] = np.arange(len(order))
        new_index = np.full(grid_count + len(self.rim_points), -1, dtype=np.int64)
        new_index[used] = rank[inverse.ravel()]
        flat = new_index[flat]
        quads = flat[:self.quads.size].reshape(-1, 4)
        ordered = np.sort(quads, axis=1)
        welded = (ordered[:, 1:] == ordered[:, :-1]).any(axis=1)  # rare: a rim point on a corner
        polygons = [*map(tuple, quads.tolist()), *self._split(flat[self.quads.size:].tolist())]
        for i in np.flatnonzero(welded).tolist() + list(range(len(quads), len(polygons))):
            polygons[i] = _drop_repeats(polygons[i])
        keep = [i for i, face in enumerate(polygons) if len(face) >= 3]
        return xz[first[order]], [polygons[i] for i in keep], [self.groups[i] for i in keep]

    def _split(self, flat: list[int]) -> list[list[int]]:
        """``flat`` cut back into the clipped polygons' sizes."""
        out, start = [], 0
        for polygon in self.polygons:
            out.append(flat[start:start + len(polygon)])
            start += len(polygon)
        return out


def _drop_repeats(face) -> tuple[int, ...]:
    """A polygon without the repeats welding left (a corner welded to its neighbour)."""
    if len(set(face)) < len(face):
        face = [v for n, v in enumerate(face) if v != face[n - 1]]
    return tuple(face)


def _rim_ring(verts: np.ndarray, radius: float, segments: int) -> list[int]:
    """The cut-surface vertices on the rim polygon, counter-clockwise seen from -y."""
    angle = np.arctan2(verts[:, 2], verts[:, 0])
    step = 2.0 * math.pi / segments
    boundary = radius * math.cos(math.pi / segments) / np.cos(angle - (np.floor(angle / step) + 0.5) * step)
    on_rim = np.abs(np.hypot(verts[:, 0], verts[:, 2]) - boundary) < 1e-6
    return np.flatnonzero(on_rim)[np.argsort(angle[on_rim], kind="stable")].tolist()


def _polygon_ring(verts: np.ndarray, rim: np.ndarray, shape: Outline, tol: float) -> list[int]:
    """``_rim_ring`` for any convex rim polygon: the cut-surface vertices on it, counter-clockwise."""
    x, z = verts[:, 0], verts[:, 2]
    near = np.flatnonzero(shape.signed_distance(x, z) > -1.01 * tol - 1e-6)  # the polygon is within tol
    px, pz = x[near], z[near]
    dist = np.full(len(near), np.inf)
    for (ax, az), (bx, bz) in zip(rim, np.roll(rim, -1, axis=0), strict=True):
        ex, ez = bx - ax, bz - az
        u = np.clip(((px - ax) * ex + (pz - az) * ez) / (ex * ex + ez * ez), 0.0, 1.0)
        np.minimum(dist, np.hypot(px - ax - u * ex, pz - az - u * ez), out=dist)
    on_rim = near[dist < 1e-6]
    angle = np.arctan2(z[on_rim], x[on_rim])
    return on_rim[np.argsort(angle, kind="stable")].tolist()



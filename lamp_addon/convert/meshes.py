"""Tessellated lamp parts: vertices in mm, faces, smoothing groups (numpy; no Blender data).

Every part is built to a chord tolerance: no point of any triangle of the mesh lies further than
``CHORD_TOLERANCE_MM`` (0.05 mm; the curved cut surfaces ``CUT_TOLERANCE_MM``, 0.0075 mm) from the
analytic surface the tracer uses (MODEL.md §3). The tessellation is chosen from that tolerance and
then *measured* (``MeshData.max_deviation``: the largest distance to the analytic surface over 28
sample points on every triangle of both diagonal splits of every quad); curved surfaces are refined
until the measurement is within ``SAMPLED_MARGIN`` times the tolerance (cylinders follow the exact
sagitta r(1 - cos(pi/n))), up to a cap (``MAX_CELL_SUBDIVISION``, ``MAX_SEGMENTS``) that only extreme
designs reach (cut caps close to hemispheres) — then ``max_deviation`` reports what was achieved and
the build operator says so.

Coordinates are the model's (MODEL.md §2): x right, y into the lamp (the lens front face is y = 0),
z up, millimetres. Lamp parts are given relative to their lamp's axis (x = z = 0 on the axis); the
body in scene coordinates. Faces are wound so that normals point out of the solid: out of the lens
glass, out of the bulb, socket and body, and from the reflector toward the lamp interior.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from ...core_tracer.raytrace.outline import Outline
from ...core_tracer.scene.derived import cut_sphere_radius, lamp_geometry

CHORD_TOLERANCE_MM = 0.05
# The fish-eye cut surfaces are built finer than the rest (flutes: ``flutes_mesh.FLUTE_TOLERANCE_MM``):
# the eye sees the lamp through them, and a faceted cap's shading normals (Blender's, averaged from
# its faces) are flatter than the cap's near the creases between cells, by up to half a face's angle.
# At 0.05 mm the lens lets through 0.5-4 % more light than the analytic caps do; at 0.0075 mm every preset
# without a sky is within 0.3 % (benchmarks/bench_freeform_agreement.py). A preview lens (Auto Build
# while the edits go on) keeps the chord tolerance's quads or fewer; the cylindrical lens, made a quad
# at a time, keeps them too (its preset within 0.3 % all the same).
CUT_TOLERANCE_MM = 0.0075
MAX_CELL_SUBDIVISION = 48  # quads per side of one lenslet cell
MAX_SEGMENTS = 1024  # around a circle
# Curved surfaces measured by sampling are refined to this fraction of the tolerance, so that the
# largest deviation between the samples (a few percent more, at 28 samples per triangle) stays within it.
SAMPLED_MARGIN = 0.95
FLAT = -1  # smoothing group of flat-shaded faces
# Where the rim cuts the cut grid, points closer than this are made one (a grid line crossing the rim
# next to a rim corner or a grid vertex): the free-form checks weld vertices to about a millionth
# of a mesh's size, and would take two such vertices for one, the glass for open.
SNAP_MM = 1e-3

# Material slots of the lens mesh.
LENS_GLASS = 0
LENS_SIDE_WALL = 1


@dataclass
class MeshData:
    """A polygon mesh: ``verts`` (N, 3) in mm, ``faces`` vertex index tuples, per face a material slot
    and a smoothing ``group`` (``FLAT`` = flat shaded; edges between faces of different groups are
    sharp), and the measured ``max_deviation`` (mm) from the analytic surface."""

    verts: np.ndarray
    faces: list[tuple[int, ...]]
    material: np.ndarray
    group: np.ndarray
    max_deviation: float = 0.0


class _MeshBuilder:
    """Collects vertices (welded by position to 1e-6 mm) and faces."""

    def __init__(self) -> None:
        self._index: dict[tuple[int, int, int], int] = {}
        self.verts: list[tuple[float, float, float]] = []
        self.faces: list[tuple[int, ...]] = []
        self.material: list[int] = []
        self.group: list[int] = []

    def vertex(self, x: float, y: float, z: float) -> int:
        key = (round(x * 1e6), round(y * 1e6), round(z * 1e6))
        i = self._index.get(key)
        if i is None:
            i = self._index[key] = len(self.verts)
            self.verts.append((float(x), float(y), float(z)))
        return i

    def add_vertices(self, verts: np.ndarray, weld: Sequence[int] = ()) -> None:
        """Append ``verts`` as they are; later ``vertex`` calls weld to those listed in ``weld``."""
        start = len(self.verts)
        self.verts.extend(tuple(v) for v in verts.tolist())
        for i in weld:
            x, y, z = self.verts[start + i]
            self._index[(round(x * 1e6), round(y * 1e6), round(z * 1e6))] = start + i

    def face(self, indices: Sequence[int], group: int = FLAT, material: int = 0) -> None:
        out: list[int] = []
        for i in indices:  # drop repeats made by welding (a collar of zero height, a sliver)
            if not out or (i != out[-1] and i != out[0]):
                out.append(i)
        if len(out) >= 3:
            self.faces.append(tuple(out))
            self.material.append(material)
            self.group.append(group)

    def result(self, max_deviation: float = 0.0) -> MeshData:
        return MeshData(np.array(self.verts, dtype=np.float64).reshape(-1, 3), self.faces,
                        np.array(self.material, dtype=np.int32), np.array(self.group, dtype=np.int32),
                        max_deviation)


# ---------------------------------------------------------------------------------------------
# Measuring


def _barycentric(samples: int) -> np.ndarray:
    pts = [(i / samples, j / samples) for i in range(samples + 1) for j in range(samples + 1 - i)]
    a = np.array(pts)
    return np.column_stack([1.0 - a.sum(axis=1), a[:, 0], a[:, 1]])


def triangle_deviation(verts: np.ndarray, tris: np.ndarray, distance: Callable[[np.ndarray], np.ndarray],
                       samples: int = 6) -> float:
    """Largest ``distance`` (to an analytic surface) over a barycentric grid of points on each triangle."""
    if len(tris) == 0:
        return 0.0
    w = _barycentric(samples)  # (S, 3)
    corners = verts[np.asarray(tris)]  # (T, 3, 3)
    points = np.matmul(w, corners).reshape(-1, 3)  # (T, S, 3)
    return float(np.max(distance(points)))


def fan_triangles(faces: Sequence[Sequence[int]]) -> np.ndarray:
    """Triangles of every polygon: both diagonal splits of a quad, a fan of anything larger."""
    tris: list[tuple[int, int, int]] = []
    for f in faces:
        if len(f) == 4:
            a, b, c, d = f
            tris += [(a, b, c), (a, c, d), (a, b, d), (b, c, d)]
        else:
            tris += [(f[0], f[i], f[i + 1]) for i in range(1, len(f) - 1)]
    return np.array(tris, dtype=np.int64).reshape(-1, 3)


def circle_segments(radius: float, tol: float = CHORD_TOLERANCE_MM, multiple: int = 4, minimum: int = 16) -> int:
    """Segments of a regular polygon inscribed in a circle whose sagitta r(1 - cos(pi/n)) is <= tol."""
    if tol >= radius:
        n = minimum
    else:
        n = math.ceil(math.pi / math.acos(1.0 - tol / radius) - 1e-9)
    n = max(minimum, -(-n // multiple) * multiple)
    return min(n, MAX_SEGMENTS)


def rim_polygon(radius: float, segments: int) -> np.ndarray:
    """(n, 2) [x, z] vertices of the rim polygon, counter-clockwise seen from the front (-y)."""
    a = 2.0 * math.pi * np.arange(segments) / segments
    return np.column_stack([radius * np.cos(a), radius * np.sin(a)])


# ---------------------------------------------------------------------------------------------
# Lens: outer disk, spherical cut surface, side wall (MODEL.md §3, §3.1)


class CutSurface:
    """The inner face of the lens: y(x, z) over the square lenslet grid (MODEL.md §3.1)."""

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


def cut_subdivision(surface: CutSurface, tol: float = CHORD_TOLERANCE_MM,
                    most: int = MAX_CELL_SUBDIVISION) -> tuple[int, float]:
    """Quads per side of a cell so that one whole cell is within ``tol``, at most ``most``; returns
    (k, deviation)."""
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


def _clip_convex(poly: list[tuple[float, float]], clip: np.ndarray, edge_list: Sequence[int]) -> list:
    """Sutherland-Hodgman: the part of convex polygon ``poly`` inside edges ``edge_list`` of CCW polygon ``clip``."""
    out = poly
    n = len(clip)
    for e in edge_list:
        if not out:
            break
        ax, az = clip[e]
        bx, bz = clip[(e + 1) % n]
        ex, ez = bx - ax, bz - az

        def side(p, ax=ax, az=az, ex=ex, ez=ez):
            return ex * (p[1] - az) - ez * (p[0] - ax)  # > 0: left of the edge, inside

        src, out = out, []
        for i, cur in enumerate(src):
            prev = src[i - 1]
            s_cur, s_prev = side(cur), side(prev)
            if s_cur >= 0:
                if s_prev < 0:
                    out.append(_lerp(prev, cur, s_prev / (s_prev - s_cur)))
                out.append(cur)
            elif s_prev >= 0:
                out.append(_lerp(prev, cur, s_prev / (s_prev - s_cur)))
    return out


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


def _lerp(a, b, f):
    return (a[0] + (b[0] - a[0]) * f, a[1] + (b[1] - a[1]) * f)


def lens_mesh(lamp: dict, segments: int, tol: float = CHORD_TOLERANCE_MM,
              max_subdivision: int = MAX_CELL_SUBDIVISION, rim: np.ndarray | None = None) -> MeshData:
    """The lens solid of one lamp, relative to its axis.

    Outer disk at y = 0 (flat), the cut surface (a grid of k x k quads per lenslet cell, clipped by the
    rim polygon; smooth within a cell, sharp creases between cells), and the side wall of radius R
    from y = 0 up to the cut apex plane y = t + h (material ``LENS_SIDE_WALL``; the part above the cut
    surface is the open collar the tracer also has). The glass is closed (watertight). At most
    ``max_subdivision`` quads per cell side (a lighter preview when smaller than the tolerance needs);
    when it is at least what ``tol`` needs, the cut surface is built to ``CUT_TOLERANCE_MM`` instead.

    A rectangular lens (``outline``) is clipped by its rim polygon ``rim`` (``outline_rim``, shared with
    the reflector and the body) instead of the regular ``segments``-gon, and its side wall's collar
    stands up to the reflector's edge, which lies behind the rim plane along the straight sides (README:
    the lens outline).
    """
    if lamp["cuts"].get("type", "fisheye") == "sawtooth":  # planar facets, exact: a module of their own
        from .sawtooth_mesh import sawtooth_lens_mesh

        return sawtooth_lens_mesh(lamp, segments, tol, rim)
    if lamp["cuts"].get("type", "fisheye") == "flutes":
        from .flutes_mesh import flutes_lens_mesh

        return flutes_lens_mesh(lamp, segments, tol, rim)
    R, t = lamp["lens"]["radius"], lamp["lens"]["thickness"]
    p, h = lamp["cuts"]["pitch"], lamp["cuts"]["height"]
    shape = Outline.of_lens(lamp["lens"])
    surface = CutSurface(t, p, h, None if h == 0 else cut_sphere_radius(p, h))
    if max_subdivision >= cut_subdivision(surface, tol)[0]:  # not a preview: to the cuts' own tolerance
        k, dev_cell = cut_subdivision(surface, min(tol, CUT_TOLERANCE_MM))
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

    mb = _MeshBuilder()
    mb.add_vertices(verts, weld=ring)  # the side wall welds to the rim ring (a cell apex on the rim is its top)
    mb.faces += cut_faces
    mb.material += [LENS_GLASS] * len(cut_faces)
    mb.group += cut_groups
    bottom = _side_wall(mb, ring, collar_top(lamp), group=1 if shape.round or shape.corner > 0 else FLAT)
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
        poly = _clip_convex(list(corners), rim, near)
        if edges_near is not None:
            poly = _with_rim_vertices(poly, rim, near)
        if len(poly) < 3 or _area(poly) < 1e-9:
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


def collar_top(lamp: dict) -> float | Callable[[float, float], float]:
    """Where the lens side wall's collar ends behind the cuts: the apex plane y = t + h of a round
    lens; for a rectangular one the reflector's edge at (x, z), which lies behind the apex plane
    along the straight sides (README: the lens outline), so that no gap opens between them."""
    g = lamp_geometry(lamp)
    if Outline.of_lens(lamp["lens"]).round:
        return g["plane_b"]
    f = lamp["reflector"]["focal_length"]
    return lambda x, z: g["vertex"] - (x * x + z * z) / (4.0 * f)


def _side_wall(mb: _MeshBuilder, ring: list[int], y_top: float | Callable[[float, float], float],
               group: int = 1) -> list[int]:
    """The side wall from the outer face (y = 0) to the cut surface's rim ``ring``, and the open collar
    from there up to ``y_top`` (the apex plane, or a function of x and z: the reflector's edge); returns
    the outer face's rim vertices."""
    def top_of(x: float, z: float) -> float:
        return y_top(x, z) if callable(y_top) else y_top

    bottom = [mb.vertex(mb.verts[i][0], 0.0, mb.verts[i][2]) for i in ring]
    top = [mb.vertex(mb.verts[i][0], top_of(mb.verts[i][0], mb.verts[i][2]), mb.verts[i][2]) for i in ring]
    side_group = group  # smooth around (flat when its corners are sharp); cut cells use groups >= 4096
    for j in range(len(ring)):
        j1 = (j + 1) % len(ring)
        mb.face([bottom[j], ring[j], ring[j1], bottom[j1]], side_group, LENS_SIDE_WALL)  # glass side
        mb.face([ring[j], top[j], top[j1], ring[j1]], side_group, LENS_SIDE_WALL)  # collar above the cuts
    return bottom


def _area(poly: Sequence[tuple[float, float]]) -> float:
    return 0.5 * abs(sum(poly[i - 1][0] * poly[i][1] - poly[i][0] * poly[i - 1][1] for i in range(len(poly))))


# ---------------------------------------------------------------------------------------------
# Reflector (MODEL.md §3.2)


def paraboloid_distance(vertex_y: float, focal_length: float) -> Callable[[np.ndarray], np.ndarray]:
    """Distance to y = y_v - r^2 / 4f, to first order (vertical offset times the cosine of the slope)."""

    def distance(points: np.ndarray) -> np.ndarray:
        r = np.hypot(points[:, 0], points[:, 2])
        dy = points[:, 1] - (vertex_y - r * r / (4.0 * focal_length))
        return np.abs(dy) / np.sqrt(1.0 + (r / (2.0 * focal_length)) ** 2)

    return distance


def reflector_mesh(lamp: dict, segments: int, tol: float = CHORD_TOLERANCE_MM) -> MeshData:
    """The paraboloid from the rim (radius R, y = rim) to the vertex, normals toward the lamp interior.

    Rings are spaced evenly in arc length along the profile. ``segments`` (shared with the lens rim and
    the body opening) is raised if the measured deviation needs it; ``MeshData.group`` is one smooth
    group.
    """
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


def outline_rim(lamp: dict, tol: float = CHORD_TOLERANCE_MM) -> np.ndarray:
    """The rim polygon of a rectangular lens (``Outline.perimeter``), shared by its lens, reflector and
    body opening: corners within ``tol``, and no edge longer than the chord of the reflector's edge that
    sags ``tol`` (along a straight side the edge is the parabola y = y_v - (x^2 + z^2) / 4f, whose chord
    of length L sags L^2 / 16f), over sqrt 2 so that a quad's diagonal is no longer than that chord."""
    f = lamp["reflector"]["focal_length"]
    return Outline.of_lens(lamp["lens"]).perimeter(tol, max_edge=math.sqrt(16.0 * f * tol) / math.sqrt(2.0))


def trimmed_reflector_mesh(lamp: dict, rim: np.ndarray, tol: float = CHORD_TOLERANCE_MM) -> MeshData:
    """The paraboloid trimmed to a rectangular lens's prism (README: the lens outline): rows of points
    s P_k for the rim polygon's vertices P_k and fractions s from 0 (the vertex) to 1 (the rim, on the
    side wall), spaced evenly in arc length along the longest profile; refined until measured."""
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
    mb = _MeshBuilder()
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
    mb = _MeshBuilder()
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


def sphere_mesh(radius: float, tol: float = CHORD_TOLERANCE_MM) -> MeshData:
    """A UV sphere about the origin (poles on the z axis), outward normals, smooth; measured like the rest."""
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
    mb = _MeshBuilder()
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


def socket_mesh(radius: float, y0: float, y1: float, tol: float = CHORD_TOLERANCE_MM) -> MeshData:
    """A capped cylinder on the lamp axis from y0 to y1 (y0 > y1 allowed); smooth side, flat caps."""
    n = circle_segments(radius, tol, multiple=4, minimum=16)
    lo, hi = min(y0, y1), max(y0, y1)
    mb = _MeshBuilder()
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
    mb = _MeshBuilder()
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


def add_bores(mb: _MeshBuilder, rims: Sequence[np.ndarray], bores: Sequence[tuple[float, float]]) -> None:
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

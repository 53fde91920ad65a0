"""The mesh builder and what every part's mesh shares: the chord tolerance, ``MeshData``,
``MeshBuilder`` (vertices welded by position, faces with material and smoothing group), measuring a
mesh against its analytic surface, rim polygons, convex clipping, and the lens side wall with its
collar (see the package's docstring for the conventions).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass

import numpy as np

from ....core_tracer.scene.derived import lamp_geometry
from ....core_tracer.scene.outline import Outline

CHORD_TOLERANCE_MM = 0.05
# The fish-eye cut surfaces are built finer than the rest (flutes: ``flutes.FLUTE_TOLERANCE_MM``):
# the eye sees the lamp through them, and a faceted cap's shading normals (Blender's, averaged from
# its faces) are flatter than the cap's near the creases between cells, by up to half a face's angle.
# At 0.05 mm the lens lets through 0.5-4 % more light than the analytic caps do; at 0.0075 mm every preset
# without a sky is within 0.3 % (benchmarks/bench_freeform_agreement.py). A preview lens (Auto Build
# while the edits go on) keeps the chord tolerance's quads or fewer; the cylindrical lens, made a quad
# at a time, keeps them too (its preset within 0.3 % all the same).
CUT_TOLERANCE_MM = 0.0075
# Convert to Free-form builds its meshes finer still (issue 32): the photometric stop lamp's lit lens as
# meshes is then +0.39 % off the parametric (+0.52 % at the tolerances above) and its R148 grid within
# 0.51 % (1.15-1.45 % at H = ±20°, V = ±10°), benchmarks/RESULTS.md; 2-3x the triangles. Build and Auto
# Build keep the above.
FREEFORM_CHORD_TOLERANCE_MM = 0.0125
FREEFORM_CUT_TOLERANCE_MM = 0.0025
# (chord, cut surfaces) tolerance of the meshes made in this thread: a context variable, so that
# Convert's finer build leaves Auto Build's worker thread at the defaults.
_tolerances: ContextVar[tuple[float, float]] = ContextVar("mesh tolerances",
                                                         default=(CHORD_TOLERANCE_MM, CUT_TOLERANCE_MM))
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


def chord_tolerance(tol: float | None = None) -> float:
    """``tol``, or when None the chord tolerance meshes are made to here (``CHORD_TOLERANCE_MM`` but in
    ``tolerances``)."""
    return _tolerances.get()[0] if tol is None else tol


def cut_tolerance() -> float:
    """The cut surfaces' tolerance meshes are made to here (``CUT_TOLERANCE_MM`` but in ``tolerances``)."""
    return _tolerances.get()[1]


@contextmanager
def tolerances(chord: float, cut: float) -> Iterator[None]:
    """Make the meshes of this thread to other tolerances within (Convert to Free-form: the finer ones)."""
    token = _tolerances.set((chord, cut))
    try:
        yield
    finally:
        _tolerances.reset(token)


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


class MeshBuilder:
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


# ---------------------------------------------------------------------------------------------
# Rims: regular polygons, a rectangular lens's outline, convex clipping


def circle_segments(radius: float, tol: float | None = None, multiple: int = 4, minimum: int = 16) -> int:
    """Segments of a regular polygon inscribed in a circle whose sagitta r(1 - cos(pi/n)) is <= tol."""
    tol = chord_tolerance(tol)
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


def outline_rim(lamp: dict, tol: float | None = None) -> np.ndarray:
    """The rim polygon of a rectangular lens (``Outline.perimeter``), shared by its lens, reflector and
    body opening: corners within ``tol``, and no edge longer than the chord of the reflector's edge that
    sags ``tol`` (along a straight side the edge is the parabola y = y_v - (x^2 + z^2) / 4f, whose chord
    of length L sags L^2 / 16f), over sqrt 2 so that a quad's diagonal is no longer than that chord."""
    tol = chord_tolerance(tol)
    f = lamp["reflector"]["focal_length"]
    return Outline.of_lens(lamp["lens"]).perimeter(tol, max_edge=math.sqrt(16.0 * f * tol) / math.sqrt(2.0))


def clip_convex(poly: list[tuple[float, float]], clip: np.ndarray, edge_list: Sequence[int]) -> list:
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


def _lerp(a, b, f):
    return (a[0] + (b[0] - a[0]) * f, a[1] + (b[1] - a[1]) * f)


def polygon_area(poly: Sequence[tuple[float, float]]) -> float:
    return 0.5 * abs(sum(poly[i - 1][0] * poly[i][1] - poly[i][0] * poly[i - 1][1] for i in range(len(poly))))


# ---------------------------------------------------------------------------------------------
# The lens side wall and its collar, shared by every kind of lens


def collar_top(lamp: dict) -> float | Callable[[float, float], float]:
    """Where the lens side wall's collar ends behind the cuts: the apex plane y = t + h of a round
    lens; for a rectangular one the reflector's edge at (x, z), which lies behind the apex plane
    along the straight sides (docs/model.md: the lens outline), so that no gap opens between them."""
    g = lamp_geometry(lamp)
    if Outline.of_lens(lamp["lens"]).round:
        return g["plane_b"]
    f = lamp["reflector"]["focal_length"]
    return lambda x, z: g["vertex"] - (x * x + z * z) / (4.0 * f)


def side_wall(mb: MeshBuilder, ring: list[int], y_top: float | Callable[[float, float], float],
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


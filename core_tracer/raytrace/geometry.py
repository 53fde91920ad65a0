"""Ray-surface intersections of the simplified lamp (MODEL.md §3, paper §3.2.4).

Inside a lamp everything is in the lamp's local frame: x and z measured from the lamp axis,
y as in the world (outer lens face y = 0, interior y > 0). Each function takes ray origins
``o`` and unit directions ``d`` (N, 3) and per-ray parameters (N,), and returns the ray
parameter of the first hit beyond ``T_MIN`` (``inf`` for a miss).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np

from ..scene.derived import cut_sphere_radius, lamp_geometry, lens_absorption
from ..scene.spec import MAX_CUTS_ACROSS
from . import optics

T_MIN = 1e-6  # mm: a hit closer than this to the ray's origin is the origin's own surface
# The cell walk's bound: before the side wall a ray's path across the cut slab is at most a
# diameter 2R long in x-z, so it visits at most (|dx| + |dz|) / p + 3 <= sqrt 2 * 2R/p + 3 cells,
# and validation keeps 2R/p <= MAX_CUTS_ACROSS.
MAX_CELL_STEPS = math.ceil(math.sqrt(2.0) * MAX_CUTS_ACROSS) + 3


@dataclass(frozen=True)
class LampTable:
    """Every lamp's parameters as arrays indexed by lamp number (gathered per ray)."""

    center: np.ndarray  # (L, 2) [x, z] of the axis in the world
    radius: np.ndarray
    plane_a: np.ndarray  # y of the cut base (= lens thickness)
    plane_b: np.ndarray  # y of the cut apexes
    pitch: np.ndarray
    cut_radius: np.ndarray  # rho of the lenslet spheres (inf for a flat inner face)
    ior: np.ndarray
    absorption: np.ndarray  # (L, 3) per mm
    wall_color: np.ndarray  # (L, 3)
    lens_diffuse: np.ndarray  # (L, 3)
    lens_specular: np.ndarray
    lens_shininess: np.ndarray
    focal: np.ndarray
    rim: np.ndarray
    vertex: np.ndarray
    reflector_color: np.ndarray  # (L, 3)
    reflectance: np.ndarray
    scatter: np.ndarray
    scatter_shininess: np.ndarray
    bulb_center: np.ndarray  # (L, 3) local
    bulb_radius: np.ndarray
    bulb_intensity: np.ndarray  # (L, 3), zero when the bulb is off
    socket_radius: np.ndarray
    socket_color: np.ndarray  # (L, 3)

    @classmethod
    def from_scene(cls, scene: dict) -> LampTable:
        rows = []
        for lamp in scene["lamps"]:
            g = lamp_geometry(lamp)
            lens, cuts, refl, bulb = lamp["lens"], lamp["cuts"], lamp["reflector"], lamp["bulb"]
            h = cuts["height"]
            rows.append(dict(
                center=lamp["center"], radius=lens["radius"], plane_a=g["plane_a"], plane_b=g["plane_b"],
                pitch=cuts["pitch"], cut_radius=cut_sphere_radius(cuts["pitch"], h) if h > 0 else np.inf,
                ior=lens["ior"], absorption=lens_absorption(lens), wall_color=lens["side_wall_color"],
                lens_diffuse=lens["diffuse_color"], lens_specular=lens["specular"],
                lens_shininess=lens["shininess"], focal=refl["focal_length"], rim=g["rim"], vertex=g["vertex"],
                reflector_color=refl["color"], reflectance=refl["reflectance"], scatter=refl["scatter"],
                scatter_shininess=refl["shininess"], bulb_center=g["bulb_center"], bulb_radius=bulb["radius"],
                bulb_intensity=bulb["intensity"] if bulb["on"] else [0.0, 0.0, 0.0],
                socket_radius=lamp["socket"]["radius"], socket_color=lamp["socket"]["color"],
            ))
        return cls(**{k: np.array([r[k] for r in rows], dtype=np.float64) for k in rows[0]})


def _solve_quadratic(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Roots (small, large) of a t^2 + b t + c = 0 by the stable formula; NaN where none.
    Handles a == 0 (a linear equation) with both roots equal."""
    with np.errstate(invalid="ignore", divide="ignore"):
        disc = b * b - 4.0 * a * c
        sq = np.sqrt(np.where(disc >= 0, disc, np.nan))
        q = -0.5 * (b + np.copysign(sq, b))
        r1 = q / a
        r2 = c / q
        linear = np.abs(a) < 1e-15
        lin = np.where(linear, -c / b, np.nan)
        lo = np.where(linear, lin, np.fmin(r1, r2))
        hi = np.where(linear, lin, np.fmax(r1, r2))
    return lo, hi


def _first_beyond(lo: np.ndarray, hi: np.ndarray, ok_lo: np.ndarray, ok_hi: np.ndarray) -> np.ndarray:
    lo_ok = (lo > T_MIN) & ok_lo
    hi_ok = (hi > T_MIN) & ok_hi
    return np.where(lo_ok, lo, np.where(hi_ok, hi, np.inf))


def hit_outer_face(o: np.ndarray, d: np.ndarray) -> np.ndarray:
    """The plane y = 0, reached from inside the lens (d_y < 0)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        t = -o[:, 1] / d[:, 1]
    return np.where((d[:, 1] < 0) & (t > T_MIN), t, np.inf)


def hit_side_wall(o: np.ndarray, d: np.ndarray, radius: np.ndarray) -> np.ndarray:
    """The cylinder r = R, left from inside (the far root)."""
    a = d[:, 0] ** 2 + d[:, 2] ** 2
    b = 2.0 * (o[:, 0] * d[:, 0] + o[:, 2] * d[:, 2])
    c = o[:, 0] ** 2 + o[:, 2] ** 2 - radius**2
    _, hi = _solve_quadratic(a, b, c)
    return np.where((a > 1e-15) & (hi > T_MIN), hi, np.inf)


def hit_reflector(o: np.ndarray, d: np.ndarray, focal: np.ndarray, vertex: np.ndarray, rim: np.ndarray,
                  leaving: np.ndarray | None = None) -> np.ndarray:
    """The paraboloid y = y_v - (x^2 + z^2) / 4f between the rim and the vertex.

    For rays that start on the reflector (``leaving``) the root nearer 0 is the start itself:
    only the other one can be a hit, whatever its distance (see ``hit_cuts``)."""
    inv4f = 0.25 / focal
    a = (d[:, 0] ** 2 + d[:, 2] ** 2) * inv4f
    b = d[:, 1] + 2.0 * (o[:, 0] * d[:, 0] + o[:, 2] * d[:, 2]) * inv4f
    c = o[:, 1] + (o[:, 0] ** 2 + o[:, 2] ** 2) * inv4f - vertex
    lo, hi = _solve_quadratic(a, b, c)
    if leaving is not None:
        own_is_lo = np.abs(lo) <= np.abs(hi)
        lo = np.where(leaving & own_is_lo, np.nan, lo)
        hi = np.where(leaving & ~own_is_lo, np.nan, hi)
    y_lo = o[:, 1] + lo * d[:, 1]
    y_hi = o[:, 1] + hi * d[:, 1]
    return _first_beyond(lo, hi, y_lo >= rim - 1e-9, y_hi >= rim - 1e-9)


def reflector_normal(p: np.ndarray, focal: np.ndarray) -> np.ndarray:
    """Unit normal of the paraboloid facing the lamp interior."""
    n = np.stack([-p[:, 0] / (2.0 * focal), -np.ones(len(p)), -p[:, 2] / (2.0 * focal)], axis=1)
    return n / np.linalg.norm(n, axis=1, keepdims=True)


def hit_sphere(o: np.ndarray, d: np.ndarray, center: np.ndarray, radius: np.ndarray) -> np.ndarray:
    """A sphere reached from outside (the near root)."""
    oc = o - center
    b = np.einsum("ij,ij->i", oc, d)
    c = np.einsum("ij,ij->i", oc, oc) - radius**2
    with np.errstate(invalid="ignore"):
        t = -b - np.sqrt(b * b - c)
    return np.where(t > T_MIN, t, np.inf)


def hit_socket(o: np.ndarray, d: np.ndarray, radius: np.ndarray, y_start: np.ndarray,
               y_end: np.ndarray) -> np.ndarray:
    """The socket (MODEL.md §3): a solid cylinder of ``radius`` about the axis from the plane of the
    bulb centre ``y_start`` back to the reflector vertex ``y_end``, closed at ``y_start`` by a flat
    disk. Its far end lies behind the reflector, so it needs no cap."""
    a = d[:, 0] ** 2 + d[:, 2] ** 2
    b = 2.0 * (o[:, 0] * d[:, 0] + o[:, 2] * d[:, 2])
    c = o[:, 0] ** 2 + o[:, 2] ** 2 - radius**2
    lo, _ = _solve_quadratic(a, b, c)
    y = o[:, 1] + lo * d[:, 1]
    side = np.where((a > 1e-15) & (lo > T_MIN) & (y >= y_start) & (y <= y_end), lo, np.inf)
    with np.errstate(divide="ignore", invalid="ignore"):  # rays parallel to the disk miss it (NaN, inf)
        t = (y_start - o[:, 1]) / d[:, 1]
        x, z = o[:, 0] + t * d[:, 0], o[:, 2] + t * d[:, 2]
    end = np.where((t > T_MIN) & (x * x + z * z <= radius**2), t, np.inf)
    return np.minimum(side, end)


# How a ray starts relative to the cut surface (the ``on_cap`` argument of ``hit_cuts``).
OFF_CAP, INTO_AIR, INTO_LENS = 0, 1, -1


def hit_cuts(o: np.ndarray, d: np.ndarray, plane_a: np.ndarray, plane_b: np.ndarray, pitch: np.ndarray,
             rho: np.ndarray, t_limit: np.ndarray, on_cap: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The cut surface (MODEL.md §3.1): returns the hit parameter and the unit normal pointing
    out of the lens material (toward the air), for hits nearer than ``t_limit``.

    Intersect the ray with plane A (cut base) and plane B (apexes); the true hit lies on a cell
    crossed between them. Walk those cells from the entry side (a 2-D grid traversal) and test
    each cell's sphere; the first root that lies inside its own cell is the hit (paper Fig. 9).
    Cost: the few cells the ray crosses in the slab, whatever the number of cuts.

    ``on_cap`` (per ray, default ``OFF_CAP``) says that a ray starts on the cut surface itself,
    heading ``INTO_AIR`` or ``INTO_LENS``. Its own surface is then excluded by geometry rather than
    by distance: a ray leaving a sphere outward never meets it again, one leaving it inward only
    at the far root, and a plane is never met again. A distance threshold alone fails for grazing
    rays, whose own cap, met again from a start a rounding error on the wrong side, lies farther
    away than any safe threshold.
    """
    n = len(o)
    t_hit = np.full(n, np.inf)
    normal = np.zeros((n, 3))
    normal[:, 1] = 1.0
    on_cap = np.zeros(n, np.int8) if on_cap is None else on_cap

    flat = np.nonzero(~np.isfinite(rho) & (on_cap == OFF_CAP))[0]
    if len(flat):
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (plane_a[flat] - o[flat, 1]) / d[flat, 1]
        ok = (t > T_MIN) & (t < t_limit[flat])
        t_hit[flat[ok]] = t[ok]

    walk = _CellWalk.enter(o, d, plane_a, plane_b, pitch, rho, t_limit, on_cap)
    for _ in range(MAX_CELL_STEPS):
        if len(walk.ray) == 0:
            break
        t, cap_normal = walk.cap_hits()
        found = np.isfinite(t)
        t_hit[walk.ray[found]] = t[found]
        normal[walk.ray[found]] = cap_normal[found]
        walk.advance()
        walk = walk.take(~found & (walk.t_cell <= walk.t_out))
    return t_hit, normal


@dataclass
class _CellWalk:
    """The rays still walking the cut cells (a 2-D grid traversal), one entry per ray.

    Cell (i, j) covers [(i - 1/2) p, (i + 1/2) p] in x and likewise in z (one cell on the axis);
    its cap's apex is at (i p, plane B, j p)."""

    ray: np.ndarray  # index of the ray in the caller's arrays
    o: np.ndarray  # (K, 3) origin
    d: np.ndarray  # (K, 3) unit direction
    top: np.ndarray  # plane B, the apexes
    p: np.ndarray  # pitch
    rho: np.ndarray  # cap sphere radius
    on_cap: np.ndarray  # how the ray leaves the cap of its first cell (cleared after that cell)
    i: np.ndarray  # current cell
    j: np.ndarray
    t_cell: np.ndarray  # where the ray enters the current cell
    t_out: np.ndarray  # where it leaves the slab (or meets the side wall)
    t_next_i: np.ndarray  # where it crosses the next cell border in x, and in z
    t_next_j: np.ndarray
    dt_i: np.ndarray  # ray length across one cell in x, and in z
    dt_j: np.ndarray

    TOL = 1e-9  # mm of ray parameter: a root on a cell border belongs to both cells

    @classmethod
    def enter(cls, o, d, plane_a, plane_b, pitch, rho, t_limit, on_cap) -> _CellWalk:
        """The rays with curved cuts whose path crosses the slab between planes A and B before
        ``t_limit``, each placed in the cell where it enters the slab."""
        ray = np.nonzero(np.isfinite(rho))[0]
        oy, dy = o[ray, 1], d[ray, 1]
        with np.errstate(divide="ignore", invalid="ignore"):
            ta = (plane_a[ray] - oy) / dy
            tb = (plane_b[ray] - oy) / dy
        in_slab = (oy >= plane_a[ray]) & (oy <= plane_b[ray])
        parallel = dy == 0
        t_in = np.where(parallel, np.where(in_slab, 0.0, np.inf), np.fmin(ta, tb))
        t_out = np.where(parallel, np.where(in_slab, np.inf, -np.inf), np.fmax(ta, tb))
        t_in = np.maximum(t_in, 0.0)
        t_out = np.minimum(t_out, t_limit[ray])
        live = t_in <= t_out
        ray, t_in, t_out = ray[live], t_in[live], t_out[live]

        oo, dd, p = o[ray], d[ray], pitch[ray]
        ox, oz, dx, dz = oo[:, 0], oo[:, 2], dd[:, 0], dd[:, 2]
        i = np.floor((ox + t_in * dx) / p + 0.5)
        j = np.floor((oz + t_in * dz) / p + 0.5)
        si, sj = np.sign(dx), np.sign(dz)
        with np.errstate(divide="ignore", invalid="ignore"):
            t_next_i = np.where(si != 0, ((i + 0.5 * si) * p - ox) / dx, np.inf)
            t_next_j = np.where(sj != 0, ((j + 0.5 * sj) * p - oz) / dz, np.inf)
            dt_i = np.where(si != 0, p / np.abs(dx), np.inf)
            dt_j = np.where(sj != 0, p / np.abs(dz), np.inf)
        return cls(ray, oo, dd, plane_b[ray], p, rho[ray], on_cap[ray], i, j, t_in, t_out, t_next_i, t_next_j,
                   dt_i, dt_j)

    def take(self, keep: np.ndarray) -> _CellWalk:
        if keep.all():
            return self
        return _CellWalk(*(getattr(self, f.name)[keep] for f in fields(self)))

    def cap_hits(self) -> tuple[np.ndarray, np.ndarray]:
        """Each ray's hit on the cap of its current cell within the cell (inf if none), and the
        unit normal there."""
        o, d = self.o, self.d
        ax, ay, az = o[:, 0] - self.i * self.p, o[:, 1] - self.top, o[:, 2] - self.j * self.p
        dx, dy, dz = d[:, 0], d[:, 1], d[:, 2]
        lo, hi = _cap_roots(ax, ay, az, dx, dy, dz, self.rho)
        if self.on_cap.any():  # only in a ray's first cell: the cap it starts on
            lo = np.where(self.on_cap == OFF_CAP, lo, np.nan)  # the near root is the ray's own start
            hi = np.where(self.on_cap == INTO_AIR, np.nan, hi)  # out of a sphere: never back in
        t_end = np.minimum(np.minimum(self.t_next_i, self.t_next_j), self.t_out)
        lo_ok = (lo > T_MIN) & (lo >= self.t_cell - self.TOL) & (lo <= t_end + self.TOL)
        hi_ok = (hi > T_MIN) & (hi >= self.t_cell - self.TOL) & (hi <= t_end + self.TOL)
        t = np.where(lo_ok, lo, np.where(hi_ok, hi, np.inf))
        found = np.isfinite(t)
        normal = np.zeros((len(t), 3))
        if found.any():
            tf = t[found]
            normal[found] = _cap_normal(ax[found] + tf * dx[found], ay[found] + tf * dy[found],
                                        az[found] + tf * dz[found], self.rho[found])
        return t, normal

    def advance(self) -> None:
        """Step every ray to the neighbouring cell it enters next."""
        step_i = self.t_next_i < self.t_next_j
        self.t_cell = np.where(step_i, self.t_next_i, self.t_next_j)
        self.i = np.where(step_i, self.i + np.sign(self.d[:, 0]), self.i)
        self.j = np.where(step_i, self.j, self.j + np.sign(self.d[:, 2]))
        self.t_next_i = np.where(step_i, self.t_next_i + self.dt_i, self.t_next_i)
        self.t_next_j = np.where(step_i, self.t_next_j, self.t_next_j + self.dt_j)
        if self.on_cap.any():
            self.on_cap = np.zeros_like(self.on_cap)


def _cap_roots(ax: np.ndarray, ay: np.ndarray, az: np.ndarray, dx: np.ndarray, dy: np.ndarray, dz: np.ndarray,
               rho: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Both roots (near, far; NaN for a miss) of a ray with a lenslet sphere; the ray's origin
    (ax, ay, az) is given relative to the cap's apex.

    The sphere of radius rho hangs below its apex, so |a + t d + rho y|^2 = rho^2 becomes
    t^2 + 2 (a.d + rho d_y) t + |a|^2 + 2 rho a_y = 0: no rho^2 term left to cancel. For very low
    cuts rho reaches 1e11 mm, and the textbook |o - c|^2 - rho^2 loses every digit. The small root
    is taken as c / q so that it stays exact when the cap is nearly flat (it tends to the plane)."""
    b = ax * dx + ay * dy + az * dz + rho * dy
    c = ax * ax + ay * ay + az * az + 2.0 * rho * ay
    with np.errstate(invalid="ignore", divide="ignore"):
        q = -(b + np.copysign(np.sqrt(b * b - c), b))
        r1, r2 = q, c / q
    return np.fmin(r1, r2), np.fmax(r1, r2)


def _cap_normal(hx: np.ndarray, hy: np.ndarray, hz: np.ndarray, rho: np.ndarray) -> np.ndarray:
    """Unit normal, out of the lens, at a point (hx, hy, hz) given relative to the cap's apex.

    Normalised explicitly: the hit is on the sphere only to rounding, so (hit - centre) / rho is
    not of unit length, and the error would grow at every later bounce."""
    return optics.normalize(np.stack([hx, hy + rho, hz], axis=1))


def cut_surface_height(x: np.ndarray, z: np.ndarray, plane_b: float, pitch: float, rho: float) -> np.ndarray:
    """Height y of the cut surface above (x, z): the cap of the cell containing the point."""
    if not np.isfinite(rho):
        return np.full(np.shape(x), plane_b)
    i = np.floor(np.asarray(x) / pitch + 0.5)
    j = np.floor(np.asarray(z) / pitch + 0.5)
    r2 = (x - i * pitch) ** 2 + (z - j * pitch) ** 2
    # the sag below the apex, rho - sqrt(rho^2 - r^2), written without cancellation for huge rho
    return plane_b - r2 / (rho + np.sqrt(np.maximum(rho * rho - r2, 0.0)))


def body_box(body: dict) -> tuple[np.ndarray, np.ndarray]:
    """The body's box (MODEL.md §3): its lowest and highest corners; the front face lies in y = 0
    and the depth runs into +y."""
    (cx, cz), (sx, sz) = body["center"], body["size"]
    return np.array([cx - sx / 2, 0.0, cz - sz / 2]), np.array([cx + sx / 2, body["depth"], cz + sz / 2])


def hit_box(o: np.ndarray, d: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rays against the axis-aligned box [lo, hi] (the slab test): per ray, the entry distance, the
    exit distance and the axis (0, 1, 2) of the entry face. A ray from outside hits the box where
    ``t_near <= t_far`` and ``t_near > 0``."""
    with np.errstate(divide="ignore", invalid="ignore"):
        t1 = (lo - o) / d
        t2 = (hi - o) / d
    # A ray parallel to a slab is inside it (−inf, inf) or outside it (inf, −inf).
    inside = (o >= lo) & (o <= hi)
    t_lo = np.where(d == 0, np.where(inside, -np.inf, np.inf), np.fmin(t1, t2))
    t_hi = np.where(d == 0, np.where(inside, np.inf, -np.inf), np.fmax(t1, t2))
    face = np.argmax(t_lo, axis=1)
    return t_lo[np.arange(len(o)), face], np.min(t_hi, axis=1), face

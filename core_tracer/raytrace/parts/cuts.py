"""The fish-eye cuts (docs/model.md §3.1, paper §3.2.4, Fig. 9): a square grid of spherical caps on
the lens's inner face, found by walking the cells crossed between plane A (the base) and plane
B (the apexes); a Fresnel surface met from inside the lens and from the air."""

from __future__ import annotations

import math

import numpy as np

from ...scene.spec import MAX_CUTS_ACROSS
from .. import optics
from .. import paths as P
from ..lamp_table import LampTable
from .base import T_MIN, Segments, put_rows, rows, slab_span

SURFACE = P.CUT
MEDIA = (P.IN_LENS, P.IN_AIR)
# The cell walk's bound: before the side wall a ray's path across the cut slab is at most a
# diameter 2R long in x-z, so it visits at most (|dx| + |dz|) / p + 3 <= sqrt 2 * 2R/p + 3 cells,
# and validation keeps 2R/p <= MAX_CUTS_ACROSS.
MAX_CELL_STEPS = math.ceil(math.sqrt(2.0) * MAX_CUTS_ACROSS) + 3


def intersect(rays: Segments, lamps: LampTable, t_limit: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The fish-eye cuts of flat lenses (``cut_surface`` sends a cylindrical lens's rays to its own walk)."""
    # A ray that starts on a cut knows it: its own cap is excluded by geometry, not by distance.
    on_cap = np.where(rays.medium == P.IN_AIR, np.int8(INTO_AIR), np.int8(INTO_LENS))
    on_cap[rays.src != P.CUT] = OFF_CAP
    li = rays.lamp  # (the lamps' values gathered with take: faster than indexing)
    return hit_cuts(rays.o, rays.d, lamps.plane_a.take(li), lamps.plane_b.take(li), lamps.pitch.take(li),
                    lamps.cut_radius.take(li), t_limit, on_cap)


# How a ray starts relative to the cut surface (the ``on_cap`` argument of ``hit_cuts``).
OFF_CAP, INTO_AIR, INTO_LENS = 0, 1, -1
_ABOVE_T_MIN = np.nextafter(T_MIN, np.inf)  # the least t with t > T_MIN


def flat_base_hits(o: np.ndarray, d: np.ndarray, plane_a: np.ndarray, t_limit: np.ndarray, flat: np.ndarray,
                   t_hit: np.ndarray) -> None:
    """The rays ``flat`` of lamps whose inner face is flat (no cuts) meet it as the plane A: their
    hits closer than ``t_limit`` go into ``t_hit`` (the normal is the plane's, +y)."""
    if len(flat):
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (plane_a[flat] - o[flat, 1]) / d[flat, 1]
        ok = (t > T_MIN) & (t < t_limit[flat])
        t_hit[flat[ok]] = t[ok]


def hit_cuts(o: np.ndarray, d: np.ndarray, plane_a: np.ndarray, plane_b: np.ndarray, pitch: np.ndarray,
             rho: np.ndarray, t_limit: np.ndarray, on_cap: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The cut surface (docs/model.md §3.1): returns the hit parameter and the unit normal pointing
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
    on_cap = np.zeros(n, np.int8) if on_cap is None else on_cap

    curved = np.isfinite(rho)
    every_curved = bool(curved.all())
    if not every_curved:
        flat_base_hits(o, d, plane_a, t_limit, np.nonzero(~curved & (on_cap == OFF_CAP))[0], t_hit)

    # The walk keeps only the cell each ray's hit lies in; the normals follow after the walk.
    cell_hit = np.zeros((2, n))
    walk_to_hits(_CellWalk.enter(o, d, plane_a, plane_b, pitch, rho, t_limit, on_cap), MAX_CELL_STEPS, t_hit, cell_hit)
    cell_i, cell_j = cell_hit

    normal = np.zeros((n, 3))
    normal[:, 1] = 1.0
    capped = np.nonzero(np.isfinite(t_hit) if every_curved else np.isfinite(t_hit) & curved)[0]
    if len(capped):
        oc, dc, tc, pc = rows(o, capped), rows(d, capped), t_hit.take(capped), pitch.take(capped)
        ax, ay, az = (oc[:, 0] - cell_i.take(capped) * pc, oc[:, 1] - plane_b.take(capped),
                      oc[:, 2] - cell_j.take(capped) * pc)
        put_rows(normal, capped, _cap_normal(ax + tc * dc[:, 0], ay + tc * dc[:, 1], az + tc * dc[:, 2],
                                             rho.take(capped)))
    return t_hit, normal


def walk_to_hits(walk, steps: int, t_hit: np.ndarray, cell_hit: np.ndarray) -> None:
    """Step ``walk`` (``_CellWalk``, or a cylindrical lens's piece: its ``ray``, ``cap_hits()``,
    ``row(name)`` and ``advance(walking)``) cell after cell, at most ``steps`` times, until each ray
    has hit a cap or left; the hits go into ``t_hit`` and their cells (i, j) into ``cell_hit`` (2, n),
    both indexed by the walk's ``ray``."""
    for _ in range(steps):
        if len(walk.ray) == 0:
            break
        t = walk.cap_hits()
        found = np.isfinite(t)
        hits = np.nonzero(found)[0]
        if len(hits):
            ray = walk.ray.take(hits)
            t_hit[ray] = t.take(hits)
            cell_hit[0, ray], cell_hit[1, ray] = walk.row("i").take(hits), walk.row("j").take(hits)
        walk.advance(~found)


class _CellWalk:
    """The rays still walking the cut cells (a 2-D grid traversal), one column per ray of a
    single (rows, K) array so that dropping the finished rays is one gather.

    Cell (i, j) covers [(i - 1/2) p, (i + 1/2) p] in x and likewise in z (one cell on the axis);
    its cap's apex is at (i p, plane B, j p)."""

    ROWS = (
        "ox", "oz", "dx", "dz", "p",  # origin and direction in x and z, pitch
        "si", "sj",  # sign of dx, dz: the step to the next cell
        # Per-ray constants of the cap roots (``cap_hits``): a_y = o_y - plane B, and the terms
        # of b and c that do not depend on the cell, computed once in the same order.
        "ay_dy", "rho_dy", "ay_ay", "two_rho_ay",
        "i", "j",  # current cell
        "t_cell",  # where the ray enters the current cell
        "t_out",  # where it leaves the slab (or meets the side wall)
        "t_next_i", "t_next_j",  # where it crosses the next cell border in x, and in z
    )
    _ROW = {name: k for k, name in enumerate(ROWS)}

    TOL = 1e-9  # mm of ray parameter: a root on a cell border belongs to both cells

    def __init__(self, ray: np.ndarray, state: np.ndarray, on_cap: np.ndarray):
        self.ray = ray  # index of the ray in the caller's arrays
        self.state = state  # (len(ROWS), K)
        self.on_cap = on_cap  # how the ray leaves the cap of its first cell; None after that cell

    def row(self, name: str) -> np.ndarray:
        return self.state[self._ROW[name]]

    @classmethod
    def enter(cls, o, d, plane_a, plane_b, pitch, rho, t_limit, on_cap) -> _CellWalk:
        """The rays with curved cuts whose path crosses the slab between planes A and B before
        ``t_limit``, each placed in the cell where it enters the slab."""
        # (one errstate for all: rays parallel to a plane or an axis divide by zero, on purpose)
        with np.errstate(divide="ignore", invalid="ignore"):
            return cls._enter(o, d, plane_a, plane_b, pitch, rho, t_limit, on_cap)

    @classmethod
    def _enter(cls, o, d, plane_a, plane_b, pitch, rho, t_limit, on_cap) -> _CellWalk:
        curved = np.isfinite(rho)
        every = bool(curved.all())  # the usual case: no gather needed to find the slab
        ray = np.arange(len(rho)) if every else np.nonzero(curved)[0]
        pick = (lambda a: a) if every else (lambda a: a[ray])
        oy, dy = pick(o[:, 1]), pick(d[:, 1])
        a_plane, b_plane = pick(plane_a), pick(plane_b)
        t_in, t_out = slab_span(oy, dy, a_plane, b_plane, pick(t_limit))
        live = t_in <= t_out
        # A ray leaving a cap into the air never meets that cap again (``cap_hits``): it starts in
        # the next cell it enters, and most leave the slab before, so they are left out here.
        leaving_air = np.nonzero(live & (pick(on_cap) == INTO_AIR))[0]
        if len(leaving_air):
            k = ray.take(leaving_air)
            t_at, p_at = t_in.take(leaving_air), pitch.take(k)  # (1-D gathers by take; a column of o by index)
            t_cross = [_entry_cell(t_at, o[:, axis][k], d[:, axis][k], p_at)[2] for axis in (0, 2)]
            t_second = np.where(t_cross[0] < t_cross[1], t_cross[0], t_cross[1])
            live[leaving_air[~(t_second <= t_out.take(leaving_air))]] = False
        all_live = every and bool(live.all())  # every ray crosses the slab: no gathers at all
        if not all_live:
            live = np.nonzero(live)[0]
            ray, t_in, t_out = ray.take(live), t_in.take(live), t_out.take(live)
        state = np.empty((len(cls.ROWS), len(ray)))
        row = dict(zip(cls.ROWS, state, strict=True))
        # Every row written in place (``out=``): the walk's setup is a fair part of its cost.
        for name, values in (("ox", o[:, 0]), ("oz", o[:, 2]), ("dx", d[:, 0]), ("dz", d[:, 2]), ("p", pitch)):
            if all_live:
                row[name][:] = values
            else:  # mode "clip": the indices are valid, and "raise" would copy through a buffer
                np.take(values, ray, out=row[name], mode="clip")
        ox, oz, dx, dz, p = row["ox"], row["oz"], row["dx"], row["dz"], row["p"]
        # (contiguous arrays gathered by take; take would copy a column of o or d whole first)
        if all_live:
            r, ay, dy = rho, o[:, 1] - plane_b, d[:, 1]
        else:
            r, ay, dy = rho.take(ray), o[:, 1][ray] - plane_b.take(ray), d[:, 1][ray]
        np.multiply(ay, dy, out=row["ay_dy"])
        np.multiply(r, dy, out=row["rho_dy"])
        np.multiply(ay, ay, out=row["ay_ay"])
        np.multiply(2.0 * r, ay, out=row["two_rho_ay"])
        _entry_cell(t_in, ox, dx, p, row["i"], row["si"], row["t_next_i"])
        _entry_cell(t_in, oz, dz, p, row["j"], row["sj"], row["t_next_j"])
        row["t_cell"][:], row["t_out"][:] = t_in, t_out
        walk = cls(ray, state, on_cap.take(ray))
        if len(leaving_air):  # those that stay: into their second cell, where any cap may be met
            moving = np.nonzero(walk.on_cap == INTO_AIR)[0]  # (a few: stepped by index, not by mask)
            walk.step_cells(moving)
            walk.on_cap[moving] = OFF_CAP
        if not walk.on_cap.any():
            walk.on_cap = None
        return walk

    def cap_hits(self) -> np.ndarray:
        """Each ray's hit on the cap of its current cell within the cell (inf if none).

        With the ray's origin a taken relative to the cap's apex, the sphere of radius rho hangs
        below the apex, so |a + t d + rho y|^2 = rho^2 becomes t^2 + 2 (a.d + rho d_y) t + |a|^2 +
        2 rho a_y = 0: no rho^2 term left to cancel. For very low cuts rho reaches 1e11 mm, and the
        textbook |o - c|^2 - rho^2 loses every digit. The small root is taken as c / q so that it
        stays exact when the cap is nearly flat (it tends to the plane)."""
        row = self.row
        p, dx, dz = row("p"), row("dx"), row("dz")
        # a: the ray's origin from the apex of its cell's cap (cell (i, j) of pitch p), across the lens
        a_x = row("ox") - row("i") * p
        a_z = row("oz") - row("j") * p
        # t^2 + 2 b t + c = 0, b = a.d + rho d_y, c = |a|^2 + 2 rho a_y (the terms that do not
        # depend on the cell, a_y d_y, rho d_y, a_y^2 and 2 rho a_y, are the walk's rows)
        b = a_x * dx + row("ay_dy") + a_z * dz + row("rho_dy")
        c = a_x * a_x + row("ay_ay") + a_z * a_z + row("two_rho_ay")
        with np.errstate(invalid="ignore", divide="ignore"):
            # the two roots without cancellation: q = -(b + sign(b) sqrt(b^2 - c)) and c / q
            q = -(np.copysign(np.sqrt(b * b - c), b) + b)
            other_root = c / q
        near, far = np.fmin(q, other_root), np.fmax(q, other_root)
        if self.on_cap is not None:  # only in a ray's first cell: the cap it starts on
            np.copyto(near, np.nan, where=self.on_cap != OFF_CAP)  # the near root is the ray's own start
            np.copyto(far, np.nan, where=self.on_cap == INTO_AIR)  # out of a sphere: never back in
        # A root counts within the cell: from its start (less TOL, and beyond T_MIN: t > T_MIN is
        # t >= the next double above it) to where the ray leaves it or the slab (plus TOL).
        t_from = np.maximum(row("t_cell") - self.TOL, _ABOVE_T_MIN)
        t_end = np.minimum(np.minimum(row("t_next_i"), row("t_next_j")), row("t_out")) + self.TOL
        near_inside = (near >= t_from) & (near <= t_end)
        far_inside = (far >= t_from) & (far <= t_end)
        # the hit: the near root inside the cell, else the far one, else none
        return np.where(near_inside, near, np.where(far_inside, far, np.inf))

    def advance(self, walking: np.ndarray) -> None:
        """Step the rays still ``walking`` (no hit in their cell) to the neighbouring cell they
        enter next; drop the others and those whose next cell lies beyond the slab. (Most rays
        leave after their first cell: they are dropped before any other work.)"""
        row = self.row
        idx = np.nonzero(walking)[0]
        t_next_i, t_next_j = row("t_next_i").take(idx), row("t_next_j").take(idx)
        t_cell = np.where(t_next_i < t_next_j, t_next_i, t_next_j)
        inside = t_cell <= row("t_out").take(idx)
        if not inside.all():
            idx, t_cell = idx[inside], t_cell[inside]
        if len(idx) < len(self.ray):
            self.ray = self.ray[idx]
            self.state = self.state.take(idx, axis=1)
        self.row("t_cell")[:] = t_cell
        self.on_cap = None
        if len(self.ray):
            self.step_cells()

    def step_cells(self, moving: np.ndarray | None = None) -> None:
        """Move the rays (those at the indices ``moving``, default all) out of their cell into the
        neighbouring one they enter next, and on to its far borders. The rays ``moving`` also get
        their ``t_cell``, where they enter it (``advance`` sets it itself for all)."""
        row = self.row
        t_next_i, t_next_j, p = row("t_next_i"), row("t_next_j"), row("p")
        if moving is not None:
            ti, tj = t_next_i.take(moving), t_next_j.take(moving)
            step_i = ti < tj
            row("t_cell")[moving] = np.where(step_i, ti, tj)
            on_i, on_j = moving[step_i], moving[~step_i]
            # (the same operations as below, on the rows of the few rays moving)
            row("i")[on_i] += row("si")[on_i]
            row("j")[on_j] += row("sj")[on_j]
            with np.errstate(divide="ignore"):
                t_next_i[on_i] += p[on_i] / np.abs(row("dx")[on_i])
                t_next_j[on_j] += p[on_j] / np.abs(row("dz")[on_j])
            return
        step_i = t_next_i < t_next_j
        step_j = ~step_i
        # (the sums over every ray, kept where it steps: faster than an add with where=)
        i, j = row("i"), row("j")
        np.putmask(i, step_i, i + row("si"))
        np.putmask(j, step_j, j + row("sj"))
        # The ray length across one cell, p / |d|: where a ray steps in x its t_next_i is finite, so d_x != 0.
        with np.errstate(divide="ignore"):
            np.putmask(t_next_i, step_i, t_next_i + p / np.abs(row("dx")))
            np.putmask(t_next_j, step_j, t_next_j + p / np.abs(row("dz")))


def _entry_cell(t_in: np.ndarray, o_k: np.ndarray, d_k: np.ndarray, p: np.ndarray, cell: np.ndarray | None = None,
                sign: np.ndarray | None = None, t_next: np.ndarray | None = None
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Along one axis (x or z, origin ``o_k``, direction ``d_k``): the cell a ray is in at
    ``t_in``, the way it steps (the sign of d) and where it crosses that cell's far border (inf
    where d = 0); into ``cell``, ``sign`` and ``t_next`` when given. One sequence of operations
    for every caller: the walk and the rays it leaves out must agree to the last bit. Called under
    ``np.errstate(divide="ignore", invalid="ignore")`` (d = 0 divides by zero)."""
    cell = np.empty_like(t_in) if cell is None else cell
    sign = np.empty_like(t_in) if sign is None else sign
    t_next = np.empty_like(t_in) if t_next is None else t_next
    np.multiply(t_in, d_k, out=cell)
    cell += o_k
    cell /= p
    cell += 0.5
    np.floor(cell, out=cell)
    np.sign(d_k, out=sign)
    # ((cell + sign / 2) p - o) / d
    np.multiply(0.5, sign, out=t_next)
    t_next += cell
    t_next *= p
    t_next -= o_k
    t_next /= d_k
    np.copyto(t_next, np.inf, where=sign == 0)
    return cell, sign, t_next


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

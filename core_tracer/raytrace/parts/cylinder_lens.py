"""The cylindrical lens (docs/model.md, "cylindrical lens"): its outer face on a vertical-axis cylinder
and its fish-eye cuts laid out by arc length on the concentric cylinder of the cut base.

Everything is in the lamp's frame (x, z from the lamp axis, y as in the world). The cylinder
axis is the vertical line (x, y) = (``axis_x``, ``radius``); an angle phi about it is measured
from the tangent line (phi = 0 at y = 0) and grows toward the wrap side ``side`` (+1: +x), so
the point at radius r and angle phi is (axis_x + side r sin phi, radius - r cos phi).

The cuts generalise docs/model.md §3.1 to the curved base: cell (i, j) covers the angles
phi_center + (i -/+ 1/2) p / base (arc length p on the base) and z in (j -/+ 1/2) p; its cap is
the fish-eye sphere of the cell's tangent plane, radius rho, centred on the cell's radial line
at radius apex + rho, so its deepest point (the apex) lies at radius ``apex`` = base - h.
Neighbouring caps meet on the radial planes and horizontal planes between the cells (the
bisectors of equally placed spheres), so the surface is continuous with creases, as on a flat
lens. The paper's plane-A/plane-B walk becomes a walk between cylinder A (radius ``corner``, the
caps' outermost points) and cylinder B (radius ``apex``): along a straight line the angle about
the axis changes monotonically, so the cells crossed in the shell follow one another like the
flat grid's, with the angular borders met at radial planes. A ray can cross the shell twice
(out of it into the lamp and back), and the walk covers both pieces.
"""

from __future__ import annotations

import math

import numpy as np

from ...scene.spec import MAX_CUTS_ACROSS
from .. import optics
from .base import T_MIN, put_rows, rows
from .cuts import INTO_AIR, INTO_LENS, OFF_CAP, walk_to_hits

# The lens spans less than half a turn of the cylinder (validation: apex > 2 R), so one shell
# piece inside the side wall crosses at most (pi/2 + 1) * 2R / p angular and vertical cells.
MAX_CELL_STEPS = math.ceil((math.pi / 2 + 1.0) * MAX_CUTS_ACROSS) + 3
TOL = 1e-9  # mm of ray parameter: a root on a cell border belongs to both cells


def _circle_roots(X: np.ndarray, Y: np.ndarray, dX: np.ndarray, dY: np.ndarray,
                  r: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Where the line (X, Y) + t (dX, dY) meets the circle of radius ``r`` about the origin: the
    roots (small, large; NaN where it misses) and the quadratic's leading coefficient."""
    a = dX * dX + dY * dY
    b = X * dX + Y * dY
    with np.errstate(invalid="ignore", divide="ignore"):
        lo, hi = _roots(a, b, X * X + Y * Y - r * r)
    return lo, hi, a


def _roots(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The roots (small, large; NaN for none) of a t^2 + 2 b t + c = 0, by the stable formula.
    Called under ``np.errstate(invalid="ignore", divide="ignore")``."""
    q = -(b + np.copysign(np.sqrt(b * b - a * c), b))
    r1, r2 = q / a, c / q
    return np.fmin(r1, r2), np.fmax(r1, r2)


def hit_outer_cylinder(o: np.ndarray, d: np.ndarray, axis_x: np.ndarray, radius: np.ndarray,
                       on_face: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The outer face, reached from inside the lens (the far root, where the ray leaves the
    cylinder), and the unit normal there out of the lens (away from the axis). For rays that
    start on the face (``on_face``) the root nearer 0 is the start itself."""
    X, Y = o[:, 0] - axis_x, o[:, 1] - radius
    lo, hi, a = _circle_roots(X, Y, d[:, 0], d[:, 1], radius)
    own = on_face & (np.abs(hi) < np.abs(lo))
    with np.errstate(invalid="ignore"):
        t = np.where((a > 1e-15) & (hi > T_MIN) & ~own, hi, np.inf)
    at = np.where(np.isfinite(t), t, 0.0)  # only x and y of the hit point are needed
    return t, _radial(o[:, 0] + at * d[:, 0] - axis_x, o[:, 1] + at * d[:, 1] - radius)


def outward_normal(p: np.ndarray, axis_x: np.ndarray, radius: np.ndarray) -> np.ndarray:
    """Unit normal of the cylinder through ``p`` about the axis, pointing away from the axis."""
    return _radial(p[:, 0] - axis_x, p[:, 1] - radius)


def _radial(nx: np.ndarray, ny: np.ndarray, sign: float = 1.0) -> np.ndarray:
    """The unit vectors sign (nx, ny, 0) / |(nx, ny)| as an (N, 3) array."""
    length = np.sqrt(nx * nx + ny * ny)
    normal = np.zeros((len(nx), 3))
    with np.errstate(invalid="ignore", divide="ignore"):
        np.divide(nx, length, out=normal[:, 0])
        np.divide(ny, length, out=normal[:, 1])
    if sign < 0:
        np.negative(normal, out=normal)
    return normal


def cell_angle(phi_center: np.ndarray, base: np.ndarray, pitch: np.ndarray, i: np.ndarray) -> np.ndarray:
    """Angle of the radial line through the centre of cell column ``i`` (arc length i p on the base)."""
    return phi_center + i * pitch / base


def hit_cylinder_cuts(o: np.ndarray, d: np.ndarray, geo: dict[str, np.ndarray], pitch: np.ndarray, rho: np.ndarray,
                      t_limit: np.ndarray, on_cap: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The cut surface of a cylindrical lens: per ray the hit parameter (inf for none before
    ``t_limit``) and the unit normal out of the lens material (toward the air). ``geo`` holds per
    ray the arrays ``axis_x, radius, side, base, apex, phi_center, corner`` of
    ``scene.derived.lens_cylinder``; ``on_cap`` as in ``cuts.hit_cuts``. ``rho`` = inf is a smooth
    inner face, the base cylinder itself."""
    # (one errstate for all: lines that miss a circle or are parallel to a border divide by zero, on purpose)
    with np.errstate(divide="ignore", invalid="ignore"):
        return _hit_cylinder_cuts(o, d, geo, pitch, rho, t_limit, on_cap)


def _hit_cylinder_cuts(o, d, geo, pitch, rho, t_limit, on_cap) -> tuple[np.ndarray, np.ndarray]:
    smooth = np.nonzero(~np.isfinite(rho))[0]
    if len(smooth) == 0:  # the usual case: every ray's lamp has cuts, no gathers
        return _walk_cells(o, d, geo, pitch, rho, t_limit, on_cap)
    n = len(o)
    t_hit = np.full(n, np.inf)
    normal = np.zeros((n, 3))
    # the base cylinder, left or met from either side
    s = smooth
    os_, ds_ = rows(o, s), rows(d, s)
    axis_x, radius = geo["axis_x"][s], geo["radius"][s]
    lo, hi, _ = _circle_roots(os_[:, 0] - axis_x, os_[:, 1] - radius, ds_[:, 0], ds_[:, 1], geo["base"][s])
    oc = on_cap[s]
    lo = np.where(oc == OFF_CAP, lo, np.nan)  # a ray on the cylinder starts at its near root
    hi = np.where(oc == INTO_LENS, np.nan, hi)  # leaving the disk outward: never back
    t = np.where(lo > T_MIN, lo, np.where(hi > T_MIN, hi, np.inf))
    t = np.where(t < t_limit[s], t, np.inf)
    t_hit[s] = t
    at = np.where(np.isfinite(t), t, 0.0)
    put_rows(normal, s, _radial(os_[:, 0] + at * ds_[:, 0] - axis_x, os_[:, 1] + at * ds_[:, 1] - radius, -1.0))

    capped = np.nonzero(np.isfinite(rho))[0]
    if len(capped):
        t, nrm = _walk_cells(rows(o, capped), rows(d, capped), {k: v[capped] for k, v in geo.items()},
                             pitch[capped], rho[capped], t_limit[capped], on_cap[capped])
        t_hit[capped] = t
        put_rows(normal, capped, nrm)
    return t_hit, normal


def _walk_cells(o, d, g, pitch, rho, t_limit, on_cap) -> tuple[np.ndarray, np.ndarray]:
    """The cell walk over the (at most two) pieces of each ray inside the shell between cylinder
    B (apex) and cylinder A (corner)."""
    n = len(o)
    X, Y = o[:, 0] - g["axis_x"], o[:, 1] - g["radius"]
    dX, dY = d[:, 0], d[:, 1]
    # the two circles share the quadratic's a and b, and |(X, Y)|^2 (the same bits as apart)
    a = dX * dX + dY * dY
    b = X * dX + Y * dY
    r0_sq = X * X + Y * Y
    corner, apex = g["corner"], g["apex"]
    a_lo, a_hi = _roots(a, b, r0_sq - corner * corner)
    b_lo, b_hi = _roots(a, b, r0_sq - apex * apex)
    along_axis = a <= 1e-15  # moving along z: the radius stays put
    crosses_b = np.isfinite(b_lo)
    if along_axis.any():  # rare
        r0 = np.hypot(X, Y)
        in_shell = (r0 >= apex) & (r0 <= corner)
        a_lo = np.where(along_axis, np.where(in_shell, -np.inf, np.nan), a_lo)
        a_hi = np.where(along_axis, np.where(in_shell, np.inf, np.nan), a_hi)
        crosses_b &= ~along_axis
    # first piece: from entering A to entering B (or leaving A); second: leaving B to leaving A
    # (NaN, a line that misses a circle, propagates through maximum/minimum and fails start <= end)
    start1, end1 = np.maximum(a_lo, 0.0), np.minimum(np.where(crosses_b, b_lo, a_hi), t_limit)
    start2, end2 = np.maximum(np.where(crosses_b, b_hi, np.nan), 0.0), np.minimum(a_hi, t_limit)
    go1 = np.nonzero(start1 <= end1)[0]
    piece2 = start2 <= end2
    step = pitch / g["base"]  # the cell's angle about the axis

    t_hit = np.full(n, np.inf)
    cell = np.zeros((n, 2))
    # Both pieces walked at once, one column each (most rays have one): a ray's first piece comes
    # first along it, so its hit there wins, and the second's counts only without one.
    go2 = np.nonzero(piece2)[0]
    first = len(go1)
    go = np.concatenate([go1, go2])
    if len(go):
        t_start = np.concatenate([start1.take(go1), start2.take(go2)])
        t_end = np.concatenate([end1.take(go1), end2.take(go2)])
        col_t, col_cell = np.full(len(go), np.inf), np.empty((2, len(go)))
        walk_to_hits(_Piece(o, d, g, step, pitch, rho, t_start, t_end, on_cap, go), MAX_CELL_STEPS, col_t, col_cell)
        for part in (slice(first, None), slice(0, first)):  # the second pieces' hits, then the first's over them
            found = np.nonzero(np.isfinite(col_t[part]))[0]
            if len(found):
                ray = go[part].take(found)
                t_hit[ray] = col_t[part].take(found)
                cell[ray, 0], cell[ray, 1] = col_cell[0, part].take(found), col_cell[1, part].take(found)
    normal = np.zeros((n, 3))
    hit = np.nonzero(np.isfinite(t_hit))[0]
    if len(hit):
        oh, dh, th, rh = rows(o, hit), rows(d, hit), t_hit[hit], rho[hit]
        phi = cell_angle(g["phi_center"][hit], g["base"][hit], pitch[hit], cell[hit, 0])
        ex, ey = g["side"][hit] * np.sin(phi), -np.cos(phi)  # the cell's radial direction e
        apex_h = apex[hit]
        # the hit relative to the sphere's centre (rho beyond the cap's apex along e): away from
        # it is out of the lens
        h = np.empty((len(hit), 3))
        h[:, 0] = oh[:, 0] - g["axis_x"][hit] - apex_h * ex + th * dh[:, 0] - rh * ex
        h[:, 1] = oh[:, 1] - g["radius"][hit] - apex_h * ey + th * dh[:, 1] - rh * ey
        h[:, 2] = oh[:, 2] - cell[hit, 1] * pitch[hit] + th * dh[:, 2]  # (e has no z)
        put_rows(normal, hit, optics.normalize(h))
    return t_hit, normal


def _cell_of(o, d, t, g, pitch) -> np.ndarray:
    """The cell (i, j) holding each ray's point at parameter ``t`` (rows of NaN where t is NaN)."""
    p = o + t[:, None] * d
    phi = np.arctan2(g["side"] * (p[:, 0] - g["axis_x"]), g["radius"] - p[:, 1])
    i = np.floor((phi - g["phi_center"]) * g["base"] / pitch + 0.5)
    j = np.floor(p[:, 2] / pitch + 0.5)
    return np.stack([i, j], axis=1)


class _Piece:
    """The rays walking one shell piece [t_start, t_end] of their path, cell after cell, testing
    each cell's cap (paper Fig. 9 on the curved base); the first root inside its own cell is the
    hit. The rays still walking are the columns of one (rows, K) array, so dropping the finished
    ones is one gather (as ``cuts._CellWalk``); ``r`` names its rows. Runs under
    ``np.errstate(divide="ignore", invalid="ignore")`` (``hit_cylinder_cuts``)."""

    # (the first ``BORDER_ROWS`` are what ``_next_border`` reads: only they are gathered for it)
    ROWS = ("X", "Y", "dX", "dY", "side", "phi_c", "step", "i", "si", "Z", "dZ", "apex", "p", "rho", "j", "sj",
            "t_cell", "t_end", "t_next_i", "t_next_j", "dt_j", "own", "i0", "j0")
    BORDER_ROWS = 9

    def __init__(self, o, d, g, step, pitch, rho, t_start, t_end, on_cap, go):
        """The rays ``go`` of the caller's arrays (one may come twice, once per piece), each
        walking from ``t_start`` to ``t_end`` (per column); ``ray`` is then the column."""
        self._set(np.arange(len(go)), np.empty((len(self.ROWS), len(go))))
        row = self.r
        row["t_cell"][:], row["t_end"][:] = t_start, t_end
        # (1-D arrays gathered with take; (N, 3) ones by rows: take of a strided column copies it first)
        for name, values in (("side", g["side"]), ("apex", g["apex"]), ("phi_c", g["phi_center"]), ("step", step),
                             ("p", pitch), ("rho", rho)):
            np.take(values, go, out=row[name], mode="clip")  # "clip": valid indices, no buffer copy
        row["own"][:] = on_cap.take(go)
        oc, dc = rows(o, go), rows(d, go)
        row["dX"][:], row["dY"][:], row["dZ"][:] = dc[:, 0], dc[:, 1], dc[:, 2]
        axis_x, radius, base = g["axis_x"].take(go), g["radius"].take(go), g["base"].take(go)
        X, Y, Z, dX, dY, dZ, p = row["X"], row["Y"], row["Z"], row["dX"], row["dY"], row["dZ"], row["p"]
        np.subtract(oc[:, 0], axis_x, out=X)
        np.subtract(oc[:, 1], radius, out=Y)
        Z[:] = oc[:, 2]
        # the cell at t_start, and for a ray that starts on a cap the cell of that cap, its own
        # (``cap_hits``; NaN for the others)
        self._cell_at(row["t_cell"], oc, axis_x, radius, base, row["i"], row["j"])
        self.any_own = bool(row["own"].any())
        if self.any_own:
            self._cell_at(0.0, oc, axis_x, radius, base, row["i0"], row["j0"])
            off = row["own"] == OFF_CAP
            row["i0"][off] = row["j0"][off] = np.nan
        # the angle about the axis changes monotonically along a line: its direction is the sign of
        # the (constant) moment of the line about the axis
        np.sign(row["side"] * (X * dY - Y * dX), out=row["si"])
        np.sign(dZ, out=row["sj"])
        np.divide((row["j"] + 0.5 * row["sj"]) * p - Z, dZ, out=row["t_next_j"])
        np.divide(p, np.abs(dZ), out=row["dt_j"])
        level = np.nonzero(row["sj"] == 0)[0]
        if len(level):  # horizontal rays never cross a row border
            row["t_next_j"][level] = row["dt_j"][level] = np.inf
        row["t_next_i"][:] = self._next_border()
        if self.any_own:
            self._leave_own_caps()

    def _cell_at(self, t, oc, axis_x, radius, base, i, j) -> None:
        """The cell (into ``i``, ``j``) holding each ray's point at ``t`` (``_cell_of``, the same
        operations)."""
        r = self.r
        phi = np.arctan2(r["side"] * ((oc[:, 0] + t * r["dX"]) - axis_x), radius - (oc[:, 1] + t * r["dY"]))
        np.floor((phi - r["phi_c"]) * base / r["p"] + 0.5, out=i)
        np.floor((oc[:, 2] + t * r["dZ"]) / r["p"] + 0.5, out=j)

    def _set(self, ray: np.ndarray, state: np.ndarray) -> None:
        self.ray = ray  # index of the ray in the caller's arrays
        self.state = state  # (len(ROWS), K)
        self.r = dict(zip(self.ROWS, state, strict=True))

    def _leave_own_caps(self) -> None:
        """A ray leaving a cap into the air never meets that cap again (``cap_hits``): in the
        cell of its own cap it moves straight on to the next, and most leave the piece before."""
        r = self.r
        leaving = (r["own"] == INTO_AIR) & (r["i"] == r["i0"]) & (r["j"] == r["j0"])
        if not leaving.any():
            return
        r["own"][leaving] = OFF_CAP
        self.advance(np.ones(len(leaving), bool), leaving)  # the others stay: t_start <= t_end

    def _next_border(self, cols: np.ndarray | None = None) -> np.ndarray:
        """Where each walking ray (those ``cols``, default all) crosses the radial half-plane at
        the far border of its cell column (inf if never: the line's angle stops short of it)."""
        r = self.r if cols is None else dict(zip(self.ROWS[:self.BORDER_ROWS],
                                                  self.state[:self.BORDER_ROWS].take(cols, axis=1), strict=True))
        angle = r["phi_c"] + (r["i"] + 0.5 * r["si"]) * r["step"]
        cos_b, sin_b = np.cos(angle), r["side"] * np.sin(angle)  # the plane's normal (cos, side sin)
        X, Y, dX, dY = r["X"], r["Y"], r["dX"], r["dY"]
        t = -(cos_b * X + sin_b * Y) / (cos_b * dX + sin_b * dY)
        on_half = sin_b * (X + t * dX) - cos_b * (Y + t * dY) > 0  # the radial direction is (side sin, -cos)
        return np.where((r["si"] != 0) & np.isfinite(t) & on_half, t, np.inf)

    def row(self, name: str) -> np.ndarray:
        return self.r[name]

    def cap_hits(self) -> np.ndarray:
        """Each ray's hit on the cap of its current cell within the cell (inf if none); see
        ``cuts._CellWalk.cap_hits`` for the roots. A ray that starts on a cap excludes it by
        geometry: the near root is its own start, and out of a sphere it never comes back in."""
        r = self.r
        phi = r["phi_c"] + r["i"] * r["step"]
        ex, ey = r["side"] * np.sin(phi), -np.cos(phi)  # the cell's radial direction
        # the ray's origin relative to the cap's apex; the sphere's centre lies rho beyond it along e
        apex, dX, dY, dZ, rho = r["apex"], r["dX"], r["dY"], r["dZ"], r["rho"]
        ax, ay, az = r["X"] - apex * ex, r["Y"] - apex * ey, r["Z"] - r["j"] * r["p"]
        b = ax * dX + ay * dY + az * dZ - rho * (ex * dX + ey * dY)
        c = ax * ax + ay * ay + az * az - 2.0 * rho * (ax * ex + ay * ey)
        q = -(b + np.copysign(np.sqrt(b * b - c), b))
        r2 = c / q
        lo, hi = np.fmin(q, r2), np.fmax(q, r2)
        if self.any_own:
            own = r["own"]
            in_own = (own != OFF_CAP) & (r["i"] == r["i0"]) & (r["j"] == r["j0"])
            lo[in_own] = np.nan  # the near root is the ray's own start
            hi[in_own & (own == INTO_AIR)] = np.nan  # out of a sphere: never back in
            # along a line the angle and z change monotonically: a cell left is never entered again
            own[in_own] = OFF_CAP
        tc = r["t_cell"]
        t_stop = np.minimum(np.minimum(r["t_next_i"], r["t_next_j"]), r["t_end"])
        lo_ok = (lo > T_MIN) & (lo >= tc - TOL) & (lo <= t_stop + TOL)
        hi_ok = (hi > T_MIN) & (hi >= tc - TOL) & (hi <= t_stop + TOL)
        return np.where(lo_ok, lo, np.where(hi_ok, hi, np.inf))

    def advance(self, walking: np.ndarray, moving: np.ndarray | None = None) -> None:
        """Step the rays still ``walking`` (no hit in their cell) into the neighbouring cell they
        enter next; drop the others and those whose next cell lies beyond the piece (most, after
        their first cell: they are dropped before the stepping). With ``moving`` only those rays
        step, and the others stay (all walking) where they are."""
        r = self.r
        step_i = r["t_next_i"] < r["t_next_j"]
        t_next = np.where(step_i, r["t_next_i"], r["t_next_j"])
        if moving is None:
            r["t_cell"][:] = t_next
        else:
            np.copyto(r["t_cell"], t_next, where=moving)
        keep = walking & (r["t_cell"] <= r["t_end"])
        if not keep.all():
            idx = np.nonzero(keep)[0]
            self._set(self.ray[idx], self.state.take(idx, axis=1))
            r, step_i = self.r, step_i[idx]
            moving = None if moving is None else moving[idx]
        if len(self.ray) == 0:
            return
        if self.any_own:
            self.any_own = bool(r["own"].any())
        step_j = ~step_i
        if moving is not None:
            step_i &= moving
            step_j &= moving
        np.add(r["i"], r["si"], out=r["i"], where=step_i)
        np.add(r["j"], r["sj"], out=r["j"], where=step_j)
        np.add(r["t_next_j"], r["dt_j"], out=r["t_next_j"], where=step_j)
        cols = np.nonzero(step_i)[0]
        if len(cols):
            r["t_next_i"][cols] = self._next_border(cols)

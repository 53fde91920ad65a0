"""The cylindrical lens (README, "cylindrical lens"): its outer face on a vertical-axis cylinder
and its fish-eye cuts laid out by arc length on the concentric cylinder of the cut base.

Everything is in the lamp's frame (x, z from the lamp axis, y as in the world). The cylinder
axis is the vertical line (x, y) = (``axis_x``, ``radius``); an angle phi about it is measured
from the tangent line (phi = 0 at y = 0) and grows toward the wrap side ``side`` (+1: +x), so
the point at radius r and angle phi is (axis_x + side r sin phi, radius - r cos phi).

The cuts generalise MODEL.md §3.1 to the curved base: cell (i, j) covers the angles
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
from .base import T_MIN
from .cuts import INTO_AIR, INTO_LENS, OFF_CAP

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
    c = X * X + Y * Y - r * r
    with np.errstate(invalid="ignore", divide="ignore"):
        sq = np.sqrt(b * b - a * c)
        q = -(b + np.copysign(sq, b))
        r1, r2 = q / a, c / q
    return np.fmin(r1, r2), np.fmax(r1, r2), a


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
    return t, outward_normal(o + np.where(np.isfinite(t), t, 0.0)[:, None] * d, axis_x, radius)


def outward_normal(p: np.ndarray, axis_x: np.ndarray, radius: np.ndarray) -> np.ndarray:
    """Unit normal of the cylinder through ``p`` about the axis, pointing away from the axis."""
    nx, ny = p[:, 0] - axis_x, p[:, 1] - radius
    length = np.sqrt(nx * nx + ny * ny)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.stack([nx / length, ny / length, np.zeros(len(p))], axis=1)


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
    n = len(o)
    t_hit = np.full(n, np.inf)
    normal = np.zeros((n, 3))
    X, Y = o[:, 0] - geo["axis_x"], o[:, 1] - geo["radius"]
    dX, dY = d[:, 0], d[:, 1]

    smooth = ~np.isfinite(rho)
    if smooth.any():  # the base cylinder, left or met from either side
        s = np.nonzero(smooth)[0]
        lo, hi, _ = _circle_roots(X[s], Y[s], dX[s], dY[s], geo["base"][s])
        oc = on_cap[s]
        lo = np.where(oc == OFF_CAP, lo, np.nan)  # a ray on the cylinder starts at its near root
        hi = np.where(oc == INTO_LENS, np.nan, hi)  # leaving the disk outward: never back
        with np.errstate(invalid="ignore"):
            t = np.where(lo > T_MIN, lo, np.where(hi > T_MIN, hi, np.inf))
        t = np.where(t < t_limit[s], t, np.inf)
        t_hit[s] = t
        p = o[s] + np.where(np.isfinite(t), t, 0.0)[:, None] * d[s]
        normal[s] = -outward_normal(p, geo["axis_x"][s], geo["radius"][s])

    capped = np.nonzero(~smooth)[0]
    if len(capped):
        g = {k: v[capped] for k, v in geo.items()}
        t, nrm = _walk_cells(o[capped], d[capped], X[capped], Y[capped], g, pitch[capped], rho[capped],
                             t_limit[capped], on_cap[capped])
        t_hit[capped] = t
        normal[capped] = nrm
    return t_hit, normal


def _walk_cells(o, d, X, Y, g, pitch, rho, t_limit, on_cap) -> tuple[np.ndarray, np.ndarray]:
    """The cell walk over the (at most two) pieces of each ray inside the shell between cylinder
    B (apex) and cylinder A (corner)."""
    n = len(o)
    dX, dY = d[:, 0], d[:, 1]
    a_lo, a_hi, a = _circle_roots(X, Y, dX, dY, g["corner"])
    b_lo, b_hi, _ = _circle_roots(X, Y, dX, dY, g["apex"])
    along_axis = a <= 1e-15  # moving along z: the radius stays put
    r0 = np.hypot(X, Y)
    in_shell = (r0 >= g["apex"]) & (r0 <= g["corner"])
    a_lo = np.where(along_axis, np.where(in_shell, -np.inf, np.nan), a_lo)
    a_hi = np.where(along_axis, np.where(in_shell, np.inf, np.nan), a_hi)
    crosses_b = ~along_axis & np.isfinite(b_lo)
    # first piece: from entering A to entering B (or leaving A); second: leaving B to leaving A
    # (NaN, a line that misses a circle, propagates through maximum/minimum and fails start <= end)
    start1, end1 = np.maximum(a_lo, 0.0), np.minimum(np.where(crosses_b, b_lo, a_hi), t_limit)
    start2, end2 = np.maximum(np.where(crosses_b, b_hi, np.nan), 0.0), np.minimum(a_hi, t_limit)
    start_cell = _cell_of(o, d, np.where(on_cap != OFF_CAP, 0.0, np.nan), g, pitch)

    t_hit = np.full(n, np.inf)
    cell = np.zeros((n, 2))
    for start, end in ((start1, end1), (start2, end2)):
        with np.errstate(invalid="ignore"):
            go = np.nonzero((start <= end) & ~np.isfinite(t_hit))[0]
        if len(go):
            t, ij = _walk_piece(o[go], d[go], {k: v[go] for k, v in g.items()}, pitch[go], rho[go], start[go],
                                end[go], on_cap[go], start_cell[go])
            t_hit[go], cell[go] = t, ij
    normal = np.zeros((n, 3))
    hit = np.nonzero(np.isfinite(t_hit))[0]
    if len(hit):
        e, rel = _apex_frame(o[hit], g, pitch[hit], cell[hit, 0], cell[hit, 1], hit)
        h = rel + t_hit[hit, None] * d[hit] - rho[hit, None] * e
        normal[hit] = optics.normalize(h)  # away from the sphere's centre: out of the lens
    return t_hit, normal


def _apex_frame(o, g, pitch, i, j, sel=None):
    """The radial unit vector e of cell (i, j) and the ray origin relative to its cap's apex."""
    pick = (lambda v: v) if sel is None else (lambda v: v[sel])
    side, axis_x, radius, apex = pick(g["side"]), pick(g["axis_x"]), pick(g["radius"]), pick(g["apex"])
    phi = cell_angle(pick(g["phi_center"]), pick(g["base"]), pitch, i)
    e = np.stack([side * np.sin(phi), -np.cos(phi), np.zeros(len(phi))], axis=1)
    rel = np.stack([o[:, 0] - axis_x - apex * e[:, 0], o[:, 1] - radius - apex * e[:, 1], o[:, 2] - j * pitch],
                   axis=1)
    return e, rel


def _cell_of(o, d, t, g, pitch) -> np.ndarray:
    """The cell (i, j) holding each ray's point at parameter ``t`` (rows of NaN where t is NaN)."""
    p = o + t[:, None] * d
    phi = np.arctan2(g["side"] * (p[:, 0] - g["axis_x"]), g["radius"] - p[:, 1])
    i = np.floor((phi - g["phi_center"]) * g["base"] / pitch + 0.5)
    j = np.floor(p[:, 2] / pitch + 0.5)
    return np.stack([i, j], axis=1)


_ROWS = ("X", "Y", "Z", "dX", "dY", "dZ", "side", "apex", "phi_c", "step", "p", "rho", "i", "j", "si", "sj",
         "t_cell", "t_end", "t_next_i", "t_next_j", "dt_j", "ray", "own", "i0", "j0")
_ROW = {name: k for k, name in enumerate(_ROWS)}


def _walk_piece(o, d, g, pitch, rho, t_start, t_end, on_cap, start_cell) -> tuple[np.ndarray, np.ndarray]:
    """Walk the cells one shell piece [t_start, t_end] crosses, in order, testing each cell's cap
    (paper Fig. 9 on the curved base); the first root inside its own cell is the hit. The rays
    still walking are the columns of one (rows, K) array, so dropping the finished ones is one
    gather (as ``cuts._CellWalk``)."""
    n = len(o)
    t_hit = np.full(n, np.inf)
    cell_hit = np.zeros((n, 2))
    state = np.empty((len(_ROWS), n))
    row = dict(zip(_ROWS, state, strict=True))
    row["X"][:], row["Y"][:], row["Z"][:] = o[:, 0] - g["axis_x"], o[:, 1] - g["radius"], o[:, 2]
    row["dX"][:], row["dY"][:], row["dZ"][:] = d[:, 0], d[:, 1], d[:, 2]
    row["side"][:], row["apex"][:], row["phi_c"][:] = g["side"], g["apex"], g["phi_center"]
    row["step"][:], row["p"][:], row["rho"][:] = pitch / g["base"], pitch, rho
    ij = _cell_of(o, d, t_start, g, pitch)
    row["i"][:], row["j"][:] = ij[:, 0], ij[:, 1]
    # the angle about the axis changes monotonically along a line: its direction is the sign of
    # the (constant) moment of the line about the axis
    row["si"][:] = np.sign(g["side"] * (row["X"] * d[:, 1] - row["Y"] * d[:, 0]))
    row["sj"][:] = np.sign(d[:, 2])
    row["t_cell"][:], row["t_end"][:] = t_start, t_end
    with np.errstate(divide="ignore", invalid="ignore"):
        row["t_next_j"][:] = np.where(row["sj"] != 0, ((row["j"] + 0.5 * row["sj"]) * pitch - o[:, 2]) / d[:, 2],
                                      np.inf)
        row["dt_j"][:] = np.where(row["sj"] != 0, pitch / np.abs(d[:, 2]), np.inf)
    row["ray"][:] = np.arange(n)
    row["own"][:] = on_cap
    row["i0"][:], row["j0"][:] = start_cell[:, 0], start_cell[:, 1]
    row["t_next_i"][:] = _next_border(state)
    for _ in range(MAX_CELL_STEPS):
        if state.shape[1] == 0:
            break
        r = {name: state[k] for name, k in _ROW.items()}
        phi = r["phi_c"] + r["i"] * r["step"]
        ex, ey = r["side"] * np.sin(phi), -np.cos(phi)  # the cell's radial direction
        # the ray's origin relative to the cap's apex; the sphere's centre lies rho beyond it along e
        ax, ay, az = r["X"] - r["apex"] * ex, r["Y"] - r["apex"] * ey, r["Z"] - r["j"] * r["p"]
        rho_ = r["rho"]
        b = ax * r["dX"] + ay * r["dY"] + az * r["dZ"] - rho_ * (ex * r["dX"] + ey * r["dY"])
        c = ax * ax + ay * ay + az * az - 2.0 * rho_ * (ax * ex + ay * ey)
        with np.errstate(invalid="ignore", divide="ignore"):
            q = -(b + np.copysign(np.sqrt(b * b - c), b))
            r2 = c / q
        lo, hi = np.fmin(q, r2), np.fmax(q, r2)
        own = np.where((r["i"] == r["i0"]) & (r["j"] == r["j0"]), r["own"], OFF_CAP)
        lo = np.where(own == OFF_CAP, lo, np.nan)  # the near root is the ray's own start
        hi = np.where(own == INTO_AIR, np.nan, hi)  # out of a sphere: never back in
        tc = r["t_cell"]
        t_stop = np.minimum(np.minimum(r["t_next_i"], r["t_next_j"]), r["t_end"])
        with np.errstate(invalid="ignore"):
            lo_ok = (lo > T_MIN) & (lo >= tc - TOL) & (lo <= t_stop + TOL)
            hi_ok = (hi > T_MIN) & (hi >= tc - TOL) & (hi <= t_stop + TOL)
        t = np.where(lo_ok, lo, np.where(hi_ok, hi, np.inf))
        found = np.isfinite(t)
        if found.any():
            hit = r["ray"][found].astype(np.int64)
            t_hit[hit] = t[found]
            cell_hit[hit, 0], cell_hit[hit, 1] = r["i"][found], r["j"][found]
        # step to the neighbouring cell entered next
        step_i = r["t_next_i"] < r["t_next_j"]
        r["t_cell"][:] = np.where(step_i, r["t_next_i"], r["t_next_j"])
        np.add(r["i"], r["si"], out=r["i"], where=step_i)
        np.add(r["j"], r["sj"], out=r["j"], where=~step_i)
        np.add(r["t_next_j"], r["dt_j"], out=r["t_next_j"], where=~step_i)
        r["t_next_i"][:] = np.where(step_i, _next_border(state), r["t_next_i"])
        keep = ~found & (r["t_cell"] <= r["t_end"])
        if not keep.all():
            state = state.take(np.nonzero(keep)[0], axis=1)
    return t_hit, cell_hit


def _next_border(state: np.ndarray) -> np.ndarray:
    """Where each walking ray crosses the radial half-plane at the far border of its cell column
    (inf if never: the line's angle stops short of it)."""
    r = {name: state[k] for name, k in _ROW.items()}
    angle = r["phi_c"] + (r["i"] + 0.5 * r["si"]) * r["step"]
    cos_b, sin_b = np.cos(angle), r["side"] * np.sin(angle)  # the plane's normal (cos, side sin)
    X, Y, dX, dY = r["X"], r["Y"], r["dX"], r["dY"]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = -(cos_b * X + sin_b * Y) / (cos_b * dX + sin_b * dY)
    on_half = sin_b * (X + t * dX) - cos_b * (Y + t * dY) > 0  # the radial direction is (side sin, -cos)
    return np.where((r["si"] != 0) & np.isfinite(t) & on_half, t, np.inf)

"""The prism plate's ring face (README, the prism plate; profile in ``scene.prism_profile``):
concentric conical facets with vertical draft faces on the plate's back, toward the bulb; a
Fresnel surface met from inside the plate and from the air behind it.

Found like the cuts (paper §3.2.4, Fig. 9, generalised): the ring face lies between plane A (the
ring bottoms) and plane B (the highest ring top). Walk the rings the ray crosses between the two
planes, from the entry side: in each ring test its facet (a cone about the axis) within the stretch
of the ray that lies over the ring; where the ray crosses into the next ring, test the draft face
there (the cylinder r = k p, as high as ring k's top). The first hit found is the nearest. A ray
crosses a few rings in the slab, whatever their number: never test every ring.

Ring k covers the radii [k p, (k + 1) p] (the last is cut by the rim r = R); its facet is the cone
y = y_A + s_k ((k + 1) p - r), its draft the cylinder r = k p for y in [y_A, y_A + s_k p].
"""

from __future__ import annotations

import math

import numpy as np

from ...scene.spec import MAX_RINGS
from .. import paths as P
from ..lamp_table import LampTable
from .base import T_MIN, Segments, solve_quadratic

SURFACE = P.RINGS
MEDIA = (P.IN_AIR, P.IN_PLATE)
# A ray crosses each ring boundary at most twice (in and out again past its nearest approach to
# the axis), so it visits at most 2 * rings + 1 rings.
MAX_RING_STEPS = 2 * MAX_RINGS + 3
TOL = 1e-9  # mm of ray parameter: a facet root on a ring border belongs to both rings
NONE = -1


def intersect(rays: Segments, lamps: LampTable, t_limit: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    n = len(rays.o)
    t = np.full(n, np.inf)
    normal = np.zeros((n, 3))
    li = rays.lamp
    plate = np.isfinite(lamps.plate_base[li])
    if not plate.any():
        return t, normal
    # From inside the plate, or from the air behind it (a ray in front of the plate meets the
    # flat front face first).
    behind = rays.o[:, 1] > lamps.plate_front[li]
    sel = np.nonzero(plate & ((rays.medium == P.IN_PLATE) | ((rays.medium == P.IN_AIR) & behind)))[0]
    if len(sel):
        ls = li[sel]
        t[sel], normal[sel] = hit_rings(rays.o[sel], rays.d[sel], lamps.plate_base[ls], lamps.plate_peak[ls],
                                        lamps.plate_pitch[ls], lamps.radius[ls], lamps.ring_slopes, ls,
                                        lamps.ring_count[ls].astype(np.int64), t_limit[sel],
                                        rays.src[sel] == P.RINGS)
    return t, normal


def hit_rings(o: np.ndarray, d: np.ndarray, y_a: np.ndarray, y_b: np.ndarray, pitch: np.ndarray,
              radius: np.ndarray, table: np.ndarray, row: np.ndarray, count: np.ndarray, t_limit: np.ndarray,
              on_rings: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The ring face: per ray the hit parameter (inf for none before ``t_limit``) and the unit
    normal out of the plate material. Ray i's ring slopes are ``table[row[i]]`` (``LampTable.ring_slopes``),
    ``count[i]`` its rings.

    ``on_rings`` marks rays that start on the ring face: the facet or draft they start on is
    found from their origin, and its root nearest the origin is excluded (by geometry, not
    distance, as for the cuts: see ``cuts.hit_cuts``)."""
    n = len(o)
    t_hit = np.full(n, np.inf)
    normal = np.zeros((n, 3))
    slopes = _Slopes(table, row)
    own_facet, own_draft = _own_element(o, y_a, pitch, slopes, count, on_rings)
    walk = _enter(o, d, y_a, y_b, pitch, radius, count, t_limit)
    hit_ring = np.zeros(n, np.int64)
    hit_draft = np.zeros(n, bool)
    for _ in range(MAX_RING_STEPS):
        if len(walk["ray"]) == 0:
            break
        ray, k = walk["ray"], walk["k"]
        oo, dd = o[ray], d[ray]
        p = pitch[ray]
        s = slopes(ray, k)
        r_out = np.minimum((k + 1) * p, radius[ray])
        t_next, inward = _next_border(walk, oo, dd, k * p, r_out)
        t_end = np.minimum(t_next, walk["t_out"])
        # the facet within the stretch over this ring
        tf = _facet_hit(oo, dd, y_a[ray], s, (k + 1) * p, k * p, r_out, walk["t_a"], t_end, own_facet[ray] == k)
        found = np.isfinite(tf)
        t_hit[ray[found]] = tf[found]
        hit_ring[ray[found]] = k[found]
        # the border into the next ring, before the slab ends: a draft face there?
        cross = ~found & (t_next <= walk["t_out"])
        border_ring = np.where(inward, k, k + 1)  # the ring whose draft stands on that border
        at_rim = ~inward & ((k + 1) >= count[ray])  # leaving the plate's rings at its rim
        y = oo[:, 1] + t_next * dd[:, 1]
        s_border = slopes(ray, np.minimum(border_ring, table.shape[1] - 1))
        in_draft = (y >= y_a[ray]) & (y <= y_a[ray] + s_border * pitch[ray]) & (border_ring > 0) & ~at_rim
        draft = cross & in_draft & (t_next > T_MIN)
        maybe_own = np.nonzero(draft & (own_draft[ray] == border_ring))[0]
        if len(maybe_own):  # a ray leaving its own draft: that crossing is its start
            m = maybe_own
            draft[m] = ~_is_start_root(oo[m], dd[m], border_ring[m] * p[m], t_next[m])
        t_hit[ray[draft]] = t_next[draft]
        hit_ring[ray[draft]] = border_ring[draft]
        hit_draft[ray[draft]] = True
        go = cross & ~draft & ~at_rim
        walk["k"] = np.where(inward, k - 1, k + 1)
        walk["t_a"] = t_next
        walk = {key: value[go] for key, value in walk.items()}

    hit = np.nonzero(np.isfinite(t_hit))[0]
    if len(hit):
        p = o[hit] + t_hit[hit, None] * d[hit]
        rho = np.hypot(p[:, 0], p[:, 2])
        with np.errstate(invalid="ignore", divide="ignore"):
            ux, uz = np.where(rho > 0, p[:, 0] / rho, 0.0), np.where(rho > 0, p[:, 2] / rho, 0.0)
        s = slopes(hit, hit_ring[hit])
        facet = np.stack([s * ux, np.ones(len(hit)), s * uz], axis=1) / np.sqrt(1.0 + s * s)[:, None]
        draft = np.stack([-ux, np.zeros(len(hit)), -uz], axis=1)
        normal[hit] = np.where(hit_draft[hit, None], draft, facet)
    return t_hit, normal


class _Slopes:
    """Ray i's slope of ring k, ``table[row[i], k]``, without a copy of each ray's row."""

    def __init__(self, table: np.ndarray, row: np.ndarray):
        self.flat, self.width, self.row = table.ravel(), table.shape[1], row

    def __call__(self, ray: np.ndarray, ring: np.ndarray) -> np.ndarray:
        return self.flat[self.row[ray] * self.width + ring]


def _enter(o, d, y_a, y_b, pitch, radius, count, t_limit) -> dict[str, np.ndarray]:
    """The rays whose path crosses the slab between planes A and B before ``t_limit``, each in
    the ring where it enters the slab (or where it starts, inside it)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        ta = (y_a - o[:, 1]) / d[:, 1]
        tb = (y_b - o[:, 1]) / d[:, 1]
    t_in, t_out = np.fmin(ta, tb), np.fmax(ta, tb)
    parallel = d[:, 1] == 0
    in_slab = (o[:, 1] >= y_a) & (o[:, 1] <= y_b)
    t_in = np.where(parallel, np.where(in_slab, 0.0, np.inf), t_in)
    t_out = np.where(parallel, np.where(in_slab, np.inf, -np.inf), t_out)
    t_in = np.maximum(t_in, 0.0)
    t_out = np.minimum(t_out, t_limit)
    ray = np.nonzero(t_in <= t_out)[0]
    t_in = t_in[ray]
    x, z = o[ray, 0] + t_in * d[ray, 0], o[ray, 2] + t_in * d[ray, 2]
    k = np.floor(np.hypot(x, z) / pitch[ray]).astype(np.int64)
    k = np.clip(k, 0, count[ray] - 1)
    return {"ray": ray, "k": k, "t_a": t_in, "t_out": t_out[ray]}


def _next_border(walk, o, d, r_in, r_out) -> tuple[np.ndarray, np.ndarray]:
    """Where the ray, inside the ring r_in <= r <= r_out from walk["t_a"] on, next crosses one
    of its borders, and whether inward (r_in) or outward (r_out). Never before walk["t_a"]."""
    a = d[:, 0] ** 2 + d[:, 2] ** 2
    b = o[:, 0] * d[:, 0] + o[:, 2] * d[:, 2]  # half the linear coefficient
    oo = o[:, 0] ** 2 + o[:, 2] ** 2
    with np.errstate(invalid="ignore", divide="ignore"):
        t_near = -b / a  # nearest approach to the axis
        rho2_near = np.maximum(oo - b * b / a, 0.0)
        out = t_near + np.sqrt(np.maximum(r_out**2 - rho2_near, 0.0) / a)
        inner = t_near - np.sqrt((r_in**2 - rho2_near) / a)
    moving = a > 1e-30
    inner_ok = moving & (r_in > 0) & (rho2_near < r_in**2) & (inner >= walk["t_a"] - TOL) & (t_near > walk["t_a"])
    t_inner = np.where(inner_ok, np.maximum(inner, walk["t_a"]), np.inf)
    t_outer = np.where(moving, np.maximum(out, walk["t_a"]), np.inf)
    inward = t_inner < t_outer
    return np.where(inward, t_inner, t_outer), inward


def _is_start_root(o, d, r, t) -> np.ndarray:
    """Whether ``t`` is the root of the circle r (about the axis, in x-z) nearer the ray's
    origin: for a ray starting on that draft face, its own start."""
    a = d[:, 0] ** 2 + d[:, 2] ** 2
    b = 2.0 * (o[:, 0] * d[:, 0] + o[:, 2] * d[:, 2])
    c = o[:, 0] ** 2 + o[:, 2] ** 2 - r**2
    lo, hi = solve_quadratic(a, b, c)
    own = np.where(np.abs(lo) <= np.abs(hi), lo, hi)
    other = np.where(np.abs(lo) <= np.abs(hi), hi, lo)
    with np.errstate(invalid="ignore"):
        return np.abs(t - own) < np.abs(t - other)


def _facet_hit(o, d, y_a, s, r_foot, r_in, r_out, t_a, t_b, own) -> np.ndarray:
    """The cone r = r_foot - (y - y_a) / s between radii r_in and r_out, for roots in [t_a, t_b];
    for ``own`` rays (starting on this facet) the root nearest 0 is the start itself."""
    e = r_foot - (o[:, 1] - y_a) / s  # r on the cone as a linear function of t: e + g t
    g = -d[:, 1] / s
    a = d[:, 0] ** 2 + d[:, 2] ** 2 - g * g
    b = 2.0 * (o[:, 0] * d[:, 0] + o[:, 2] * d[:, 2] - e * g)
    c = o[:, 0] ** 2 + o[:, 2] ** 2 - e * e
    lo, hi = solve_quadratic(a, b, c)
    own_is_lo = np.abs(lo) <= np.abs(hi)
    lo = np.where(own & own_is_lo, np.nan, lo)
    hi = np.where(own & ~own_is_lo, np.nan, hi)

    def ok(t):
        r = e + g * t
        with np.errstate(invalid="ignore"):
            return ((t > T_MIN) & (t >= t_a - TOL) & (t <= t_b + TOL) & (r >= r_in - 1e-9) & (r <= r_out + 1e-9))

    return np.where(ok(lo), lo, np.where(ok(hi), hi, np.inf))


def _own_element(o, y_a, pitch, slopes, count, on_rings) -> tuple[np.ndarray, np.ndarray]:
    """For rays starting on the ring face: the ring whose facet, or whose draft, they start on
    (the element whose equation the origin satisfies best); NONE elsewhere."""
    n = len(o)
    own_facet, own_draft = np.full(n, NONE), np.full(n, NONE)
    if on_rings is None or not on_rings.any():
        return own_facet, own_draft
    idx = np.nonzero(on_rings)[0]
    p, ya, last = pitch[idx], y_a[idx], count[idx] - 1
    rho = np.hypot(o[idx, 0], o[idx, 2])
    y = o[idx, 1]
    k0 = np.clip(np.floor(rho / p).astype(np.int64), 0, last)
    best, best_facet, best_draft = np.full(len(idx), np.inf), np.full(len(idx), NONE), np.full(len(idx), NONE)
    for k in (k0 - 1, k0, k0 + 1):
        kk = np.clip(k, 0, last)
        s = slopes(idx, kk)
        res = np.abs(y - ya - s * ((kk + 1) * p - rho)) / np.sqrt(1.0 + s * s)  # distance to the cone
        better = (k == kk) & (res < best)
        best = np.where(better, res, best)
        best_facet = np.where(better, kk, best_facet)
    j = np.clip(np.rint(rho / p).astype(np.int64), 1, np.maximum(last, 1))
    res = np.abs(rho - j * p)
    better = (j <= last) & (res < best)
    best_draft = np.where(better, j, NONE)
    best_facet = np.where(better, NONE, best_facet)
    own_facet[idx], own_draft[idx] = best_facet, best_draft
    return own_facet, own_draft


def brute_force_rings(o: np.ndarray, d: np.ndarray, y_a: float, pitch: float, radius: float, slopes: np.ndarray,
                      t_limit: float = math.inf) -> np.ndarray:
    """Every ring's facet and draft tested, the nearest hit kept: the walk's reference (tests)."""
    n = len(o)
    best = np.full(n, np.inf)
    for k, s in enumerate(slopes):
        r_in, r_out = k * pitch, min((k + 1) * pitch, radius)
        tf = _facet_hit(o, d, np.full(n, y_a), np.full(n, s), np.full(n, (k + 1) * pitch), np.full(n, r_in),
                        np.full(n, r_out), np.zeros(n), np.full(n, t_limit), np.zeros(n, bool))
        best = np.minimum(best, tf)
        if k == 0:
            continue
        a = d[:, 0] ** 2 + d[:, 2] ** 2
        b = 2.0 * (o[:, 0] * d[:, 0] + o[:, 2] * d[:, 2])
        c = o[:, 0] ** 2 + o[:, 2] ** 2 - r_in**2
        lo, hi = solve_quadratic(a, b, c)
        for t in (lo, hi):
            y = o[:, 1] + t * d[:, 1]
            with np.errstate(invalid="ignore"):
                ok = (t > T_MIN) & (t <= t_limit) & (y >= y_a) & (y <= y_a + s * pitch) & (a > 1e-30)
            best = np.where(ok & (t < best), t, best)
    return best

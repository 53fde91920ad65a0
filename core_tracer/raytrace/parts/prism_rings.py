"""The prism plate's ring face (docs/model.md, the prism plate; profile in ``scene.prism_profile``):
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
WALK_ALL = 0.9  # the share of walking rays from which the others walk too (from t = inf: no hit)


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
        t[sel] = _hit_rings(np.take(rays.o, sel, axis=0), np.take(rays.d, sel, axis=0), lamps.plate_base[ls],
                            lamps.plate_peak[ls], lamps.plate_pitch[ls], lamps.radius[ls], lamps.ring_slopes, ls,
                            lamps.ring_count[ls].astype(np.int64), t_limit[sel], rays.src[sel] == P.RINGS,
                            normal, sel)
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
    normal = np.zeros((len(o), 3))
    t = _hit_rings(o, d, y_a, y_b, pitch, radius, table, row, count, t_limit, on_rings, normal, np.arange(len(o)))
    return t, normal


def _hit_rings(o, d, y_a, y_b, pitch, radius, table, row, count, t_limit, on_rings, normal, into) -> np.ndarray:
    """``hit_rings``, its normals written into ``normal[into]`` (the caller's rays, of which these
    are ``into``: no gather and scatter of normals)."""
    n = len(o)
    t_hit = np.full(n, np.inf)
    with np.errstate(invalid="ignore", divide="ignore"):  # NaN roots and rays along the axis fail the tests
        ray, k, t_a, t_out = _enter(o, d, y_a, y_b, pitch, radius, count, t_limit)
        if ray is None:  # (nearly) every ray walks: all of them, those that do not with no stretch to walk
            w = _Walk(o, d, y_a, pitch, radius, count, row * table.shape[1], table.ravel(), on_rings)
            ray = np.arange(n)
        elif len(ray) == 0:
            return t_hit
        else:
            w = _Walk(np.take(o, ray, axis=0), np.take(d, ray, axis=0), y_a[ray], pitch[ray], radius[ray],
                      count[ray], row[ray] * table.shape[1], table.ravel(),
                      None if on_rings is None else on_rings[ray])
        hit_ring = np.zeros(n, np.int64)
        hit_draft = np.zeros(n, bool)
        _walk(w, ray, k, t_a, t_out, table.shape[1] - 1, t_hit, hit_ring, hit_draft)
        _normals(normal, into, o, d, t_hit, hit_ring, hit_draft, table.ravel(), row * table.shape[1])
    return t_hit


def _walk(w: _Walk, ray, k, t_a, t_out, last: int, t_hit, hit_ring, hit_draft) -> None:
    """Walk the rays ``w`` (``ray`` among all) ring by ring from ring ``k`` at ``t_a`` until
    ``t_out``: into ``t_hit``, ``hit_ring``, ``hit_draft`` their first hit. Each step keeps only
    the rays still walking (after the first ring, a few): a step costs the same few dozen array
    operations however few they are."""
    for _ in range(MAX_RING_STEPS):
        if len(k) == 0:
            break
        r_in = k * w.p
        r_foot = (k + 1) * w.p
        r_out = np.minimum(r_foot, w.radius)
        t_next, inward = _next_border(w, r_in, r_out, t_a)
        # the facet within the stretch over this ring
        tf = _facet_hit(w, w.slopes[w.row + k], r_foot, r_in, r_out, t_a, np.minimum(t_next, t_out), k)
        found = tf < np.inf
        # the border into the next ring, before the slab ends: a draft face there?
        cross = ~found & (t_next <= t_out)
        border_ring = np.where(inward, k, k + 1)  # the ring whose draft stands on that border
        at_rim = ~inward & ((k + 1) >= w.count)  # leaving the plate's rings at its rim
        y = w.oy + t_next * w.dy
        s_border = w.slopes[w.row + np.minimum(border_ring, last)]
        draft = cross & (y >= w.y_a) & (y <= w.y_a + s_border * w.p) & (border_ring > 0) & ~at_rim & (t_next > T_MIN)
        maybe_own = np.nonzero(draft & (w.own_draft == border_ring))[0]
        if len(maybe_own):  # a ray leaving its own draft: that crossing is its start
            m = maybe_own
            draft[m] = ~_is_start_root(w.o[m], w.d[m], border_ring[m] * w.p[m], t_next[m])
        done = np.nonzero(found | draft)[0]
        on_facet = found[done]
        here = ray[done]
        t_hit[here] = np.where(on_facet, tf[done], t_next[done])
        hit_ring[here] = np.where(on_facet, k[done], border_ring[done])
        hit_draft[here] = ~on_facet
        go = np.nonzero(cross & ~draft & ~at_rim)[0]
        k = np.where(inward, k - 1, k + 1)[go]
        t_a, t_out, ray = t_next[go], t_out[go], ray[go]
        w = w.take(go)


def _normals(normal, into, o, d, t_hit, hit_ring, on_draft, slopes, row) -> None:
    """Into ``normal[into]``, where ``t_hit`` is a hit: the unit normal out of the plate, the
    cone's on a facet (ray i's slope of ring k is ``slopes[row[i] + k]``), -r on a draft (the
    radial direction at the hit point)."""
    hit = np.nonzero(t_hit < np.inf)[0]
    if len(hit) == 0:
        return
    t = t_hit[hit]
    x = o[hit, 0] + t * d[hit, 0]
    z = o[hit, 2] + t * d[hit, 2]
    rho = np.hypot(x, z)
    if (rho > 0).all():  # (a hit on the axis itself has no radial direction: 0 there)
        ux, uz = x / rho, z / rho
    else:
        ux, uz = np.where(rho > 0, x / rho, 0.0), np.where(rho > 0, z / rho, 0.0)
    facet = ~on_draft[hit]
    s = slopes[row[hit] + hit_ring[hit]]
    length = np.sqrt(1.0 + s * s)
    # on a draft (-ux, 0, -uz); the 0 is the caller's
    rows = into[hit]
    normal[rows, 0] = np.where(facet, s * ux / length, -ux)
    normal[rows, 1] = np.where(facet, 1.0 / length, 0.0)
    normal[rows, 2] = np.where(facet, s * uz / length, -uz)


class _Walk:
    """What the walk needs of each walking ray, worked out once (not at every ring it visits).
    Every number is computed by the same expression as when each step worked it out afresh, so
    the hits are the same bits."""

    _PER_RAY = ("o", "d", "y_a", "p", "radius", "count", "row", "oy", "dy", "a", "b", "oo", "t_near", "rho2_near",
                "height", "fall", "own_facet", "own_draft")

    def __init__(self, o, d, y_a, p, radius, count, row, slopes, on_rings):
        self.o, self.d, self.y_a, self.p, self.radius, self.count, self.row = o, d, y_a, p, radius, count, row
        self.slopes = slopes
        if on_rings is False:  # ``take``: filled in there
            return
        ox, oz, dx, dz = o[:, 0], o[:, 2], d[:, 0], d[:, 2]
        self.oy, self.dy = o[:, 1], d[:, 1]
        self.a = dx**2 + dz**2
        self.b = ox * dx + oz * dz  # half the linear coefficient of r^2 along the ray
        self.oo = ox**2 + oz**2
        self.t_near = -self.b / self.a  # nearest approach to the axis
        self.rho2_near = np.maximum(self.oo - self.b * self.b / self.a, 0.0)
        self.moving = self.a > 1e-30
        self.all_moving = bool(self.moving.all())
        self.height = self.oy - y_a
        self.fall = -self.dy
        self.own_facet, self.own_draft = _own_element(o, self.height, p, slopes, row, count, on_rings)

    def take(self, sel: np.ndarray) -> _Walk:
        """The rays ``sel`` only."""
        part = _Walk(*(None,) * 7, self.slopes, False)
        for name in self._PER_RAY:
            value = getattr(self, name)
            setattr(part, name, np.take(value, sel, axis=0) if value.ndim == 2 else value[sel])
        part.all_moving = self.all_moving
        part.moving = None if self.all_moving else self.moving[sel]
        return part


def _next_border(w: _Walk, r_in, r_out, t_a) -> tuple[np.ndarray, np.ndarray]:
    """Where the ray, inside the ring r_in <= r <= r_out from ``t_a`` on, next crosses one of its
    borders, and whether inward (r_in) or outward (r_out). Never before ``t_a``."""
    t_near, rho2_near, a = w.t_near, w.rho2_near, w.a
    out = t_near + np.sqrt(np.maximum(r_out**2 - rho2_near, 0.0) / a)
    inner = t_near - np.sqrt((r_in**2 - rho2_near) / a)
    inner_ok = (r_in > 0) & (rho2_near < r_in**2) & (inner >= t_a - TOL) & (t_near > t_a)
    if w.all_moving:
        t_inner = np.where(inner_ok, np.maximum(inner, t_a), np.inf)
        t_outer = np.maximum(out, t_a)
    else:
        t_inner = np.where(w.moving & inner_ok, np.maximum(inner, t_a), np.inf)
        t_outer = np.where(w.moving, np.maximum(out, t_a), np.inf)
    inward = t_inner < t_outer
    return np.where(inward, t_inner, t_outer), inward


def _facet_hit(w: _Walk, s, r_foot, r_in, r_out, t_a, t_b, k) -> np.ndarray:
    """The cone r = r_foot - (y - y_a) / s between radii r_in and r_out, for roots in [t_a, t_b];
    for a ray starting on this facet (``w.own_facet == k``) the root nearest 0 is the start itself."""
    e = r_foot - w.height / s  # r on the cone as a linear function of t: e + g t
    g = w.fall / s
    lo, hi = _roots(w.a - g * g, 2.0 * (w.b - e * g), w.oo - e * e)
    own = w.own_facet == k
    if own.any():
        own_is_lo = np.abs(lo) <= np.abs(hi)
        lo = np.where(own & own_is_lo, np.nan, lo)
        hi = np.where(own & ~own_is_lo, np.nan, hi)
    # t > T_MIN and t >= t_a - TOL in one comparison (NaN fails both)
    lower = np.maximum(_ABOVE_T_MIN, t_a - TOL)
    upper = t_b + TOL
    r_lo, r_hi = r_in - 1e-9, r_out + 1e-9
    r = e + g * lo
    ok_lo = (lo >= lower) & (lo <= upper) & (r >= r_lo) & (r <= r_hi)
    r = e + g * hi
    ok_hi = (hi >= lower) & (hi <= upper) & (r >= r_lo) & (r <= r_hi)
    return np.where(ok_lo, lo, np.where(ok_hi, hi, np.inf))


_ABOVE_T_MIN = np.nextafter(T_MIN, np.inf)  # t > T_MIN exactly when t >= this


def _roots(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``base.solve_quadratic``, the same bits, without its linear case where no ray needs it
    (a negative discriminant gives NaN roots either way). Inside ``hit_rings``'s errstate."""
    if (np.abs(a) < 1e-15).any():
        return solve_quadratic(a, b, c)
    sq = np.sqrt(b * b - 4.0 * a * c)
    q = -0.5 * (b + np.copysign(sq, b))
    return np.fmin(q / a, c / q), np.fmax(q / a, c / q)


def _enter(o, d, y_a, y_b, pitch, radius, count, t_limit):
    """The rays whose path crosses the slab between planes A and B before ``t_limit``, each in
    the ring where it enters the slab (or where it starts, inside it): the rays (None for all),
    their rings and where they enter and leave the slab. Inside ``hit_rings``'s errstate."""
    ta = (y_a - o[:, 1]) / d[:, 1]
    tb = (y_b - o[:, 1]) / d[:, 1]
    t_in, t_out = np.fmin(ta, tb), np.fmax(ta, tb)
    parallel = d[:, 1] == 0
    if parallel.any():
        in_slab = (o[:, 1] >= y_a) & (o[:, 1] <= y_b)
        t_in = np.where(parallel, np.where(in_slab, 0.0, np.inf), t_in)
        t_out = np.where(parallel, np.where(in_slab, np.inf, -np.inf), t_out)
    t_in = np.maximum(t_in, 0.0)
    t_out = np.minimum(t_out, t_limit)
    walking = t_in <= t_out
    if np.count_nonzero(walking) >= WALK_ALL * len(o):
        # Gathering the walkers would cost more than walking the few others from t = inf, where
        # they find nothing. Their ring (from any point) only has to be a ring.
        t_in = np.where(walking, t_in, np.inf)
        x, z = o[:, 0] + t_in * d[:, 0], o[:, 2] + t_in * d[:, 2]
        k = np.floor(np.hypot(x, z) / pitch).astype(np.int64)
        return None, np.minimum(np.maximum(k, 0), count - 1), t_in, t_out
    ray = np.nonzero(walking)[0]
    t_in = t_in[ray]
    x, z = o[ray, 0] + t_in * d[ray, 0], o[ray, 2] + t_in * d[ray, 2]
    k = np.floor(np.hypot(x, z) / pitch[ray]).astype(np.int64)
    return ray, np.minimum(np.maximum(k, 0), count[ray] - 1), t_in, t_out[ray]


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


def _facet_hit_alone(o, d, y_a, s, r_foot, r_in, r_out, t_a, t_b, own) -> np.ndarray:
    """``_facet_hit`` from the rays alone (no ``_Walk``): the brute force's test of one ring."""
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


def _own_element(o, height, pitch, slopes, row, count, on_rings) -> tuple[np.ndarray, np.ndarray]:
    """For rays starting on the ring face: the ring whose facet, or whose draft, they start on
    (the element whose equation the origin satisfies best: the first of rings k0 - 1, k0, k0 + 1
    about the origin's, then the draft nearest it); NONE elsewhere. ``height`` is y - y_A at the
    origin; ray i's slope of ring k is ``slopes[row[i] + k]``."""
    n = len(o)
    own_facet, own_draft = np.full(n, NONE), np.full(n, NONE)
    if on_rings is None or not on_rings.any():
        return own_facet, own_draft
    idx = None if on_rings.all() else np.nonzero(on_rings)[0]
    if idx is not None:
        o, height, pitch, row, count = o[idx], height[idx], pitch[idx], row[idx], count[idx]
    last = count - 1
    lengths = np.sqrt(1.0 + slopes * slopes)  # per ring: the residual below over this is the distance to the cone
    rho = np.hypot(o[:, 0], o[:, 2])
    k0 = np.minimum(np.maximum(np.floor(rho / pitch).astype(np.int64), 0), last)

    def residual(k):
        return np.abs(height - slopes[row + k] * ((k + 1) * pitch - rho)) / lengths[row + k]

    best_facet = np.where(k0 >= 1, k0 - 1, NONE)
    best = np.where(k0 >= 1, residual(np.maximum(k0 - 1, 0)), np.inf)
    res = residual(k0)
    better = res < best
    best = np.where(better, res, best)
    best_facet = np.where(better, k0, best_facet)
    res = residual(np.minimum(k0 + 1, last))
    better = (k0 + 1 <= last) & (res < best)
    best = np.where(better, res, best)
    best_facet = np.where(better, k0 + 1, best_facet)
    j = np.minimum(np.maximum(np.rint(rho / pitch).astype(np.int64), 1), np.maximum(last, 1))
    better = (j <= last) & (np.abs(rho - j * pitch) < best)
    best_draft = np.where(better, j, NONE)
    best_facet = np.where(better, NONE, best_facet)
    if idx is None:
        return best_facet, best_draft
    own_facet[idx], own_draft[idx] = best_facet, best_draft
    return own_facet, own_draft


def brute_force_rings(o: np.ndarray, d: np.ndarray, y_a: float, pitch: float, radius: float, slopes: np.ndarray,
                      t_limit: float = math.inf) -> np.ndarray:
    """Every ring's facet and draft tested, the nearest hit kept: the walk's reference (tests)."""
    n = len(o)
    best = np.full(n, np.inf)
    for k, s in enumerate(slopes):
        r_in, r_out = k * pitch, min((k + 1) * pitch, radius)
        tf = _facet_hit_alone(o, d, np.full(n, y_a), np.full(n, s), np.full(n, (k + 1) * pitch), np.full(n, r_in),
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

"""The light guide (docs/photometric.md, light guides): a straight rod of acrylic or polycarbonate,
round or rectangular, with V-shaped extraction prisms cut across its back (+y), a Fresnel surface
met from the lamp's air and from inside the rod, whose material is the lamp's second dielectric
(``paths.IN_GUIDE``: the prism plate's medium, index and absorption).

Geometry, in the guide's frame (``GuideTable``): s along the axis from the first end face, u across
it in the lens plane, v along y from the axis. The rod is the set

    0 <= s <= L,   u² + v² <= r²  (round)  or  |u| <= w/2, |v| <= h/2  (rectangular),
    v <= v_back − δ + m |s − s_k|  for the prism k nearest s (its apex line at s_k),

with v_back its back (r or h/2), δ the prism depth and m the tangent of the facets' angle to the
axis: each prism a V groove of width 2δ/m. A ray's hit is the nearest point past ``T_MIN`` where it
crosses one of these bounding surfaces while inside all the others (the boundary of an intersection
of sets): the two end planes, the side (a cylinder's two roots, or four planes), and the facets of
the prisms whose cells the ray crosses between the grooves' bottom and the back, walked in order
along s: a few cells per ray, whatever the number of prisms (as the cut walk of Fig. 9).
"""

from __future__ import annotations

import numpy as np

from .. import paths as P
from ..guide_table import GuideTable
from ..lamp_table import LampTable
from . import guide_arc
from .base import T_MIN, Segments, put_rows, rows, slab_span, solve_quadratic

SURFACE = P.GUIDE
MEDIA = (P.IN_AIR, P.IN_GUIDE)
EPS = 1e-7  # mm: a point this close outside a bounding surface still lies on the rod


def intersect(rays: Segments, lamps: LampTable, t_limit: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    n = len(rays.o)
    t = np.full(n, np.inf)
    normal = np.zeros((n, 3))
    guide = lamps.guide
    if guide is None:
        return t, normal
    present, arc = guide.present.take(rays.lamp) > 0, guide.arc.take(rays.lamp) > 0
    straight = np.nonzero(present & ~arc)[0]
    if len(straight):  # the rays inside a rod meet it: no box test for them
        t_sel, n_sel = hit_guide(rows(rays.o, straight), rows(rays.d, straight), guide, rays.lamp.take(straight),
                                 rays.medium.take(straight) == P.IN_GUIDE)
        t[straight] = t_sel
        put_rows(normal, straight, n_sel)
    bent = np.nonzero(present & arc)[0]
    if len(bent):
        t_sel, n_sel = guide_arc.hit_arc(rows(rays.o, bent), rows(rays.d, bent), guide, rays.lamp.take(bent))
        t[bent] = t_sel
        put_rows(normal, bent, n_sel)
    return t, normal


def to_guide(o: np.ndarray, d: np.ndarray, guide: GuideTable, lamp: np.ndarray):
    """Origins and directions in the guide's frame: (s, u, v) of each, as six (N,) arrays."""
    axis, across = rows(guide.axis, lamp), rows(guide.across, lamp)
    rel = o - rows(guide.start, lamp)
    s0 = np.einsum("ij,ij->i", rel, axis)
    u0 = np.einsum("ij,ij->i", rel, across)
    ds = np.einsum("ij,ij->i", d, axis)
    du = np.einsum("ij,ij->i", d, across)
    return s0, u0, rel[:, 1], ds, du, d[:, 1]


def inside(s: np.ndarray, u: np.ndarray, v: np.ndarray, g: dict) -> np.ndarray:
    """Whether guide-frame points lie in the rod (within ``EPS``): its section, its ends, its prisms."""
    rnd = g["round"] > 0
    section = np.where(rnd, u * u + v * v <= (g["half_u"] + EPS) ** 2,
                       (np.abs(u) <= g["half_u"] + EPS) & (np.abs(v) <= g["half_v"] + EPS))
    ends = (s >= -EPS) & (s <= g["length"] + EPS)
    return section & ends & ~in_groove(s, v, g)


def in_groove(s: np.ndarray, v: np.ndarray, g: dict) -> np.ndarray:
    """Whether guide-frame points lie inside a prism's V groove (off the rod), beyond ``EPS``."""
    k = nearest_prism(s, g)
    apex = g["first_prism"] + k * g["pitch"]
    floor = g["half_v"] - g["prism_depth"] + g["slope"] * np.abs(s - apex)
    return (g["prisms"] > 0) & (v > floor + EPS * np.sqrt(1.0 + g["slope"] ** 2))


def nearest_prism(s: np.ndarray, g: dict) -> np.ndarray:
    """The index of the prism whose apex line is nearest s (clamped to the row)."""
    with np.errstate(invalid="ignore", divide="ignore"):
        k = np.floor((s - g["first_prism"]) / g["pitch"] + 0.5)
    return np.clip(k, 0.0, np.maximum(g["prisms"] - 1.0, 0.0))


def gathered(guide: GuideTable, lamp: np.ndarray) -> dict:
    keys = ("round", "half_u", "half_v", "length", "pitch", "prism_depth", "slope", "prisms", "first_prism")
    return {key: getattr(guide, key).take(lamp) for key in keys}


def hit_guide(o: np.ndarray, d: np.ndarray, guide: GuideTable, lamp: np.ndarray,
              inside_rod: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Per ray, the nearest hit on the rod of its lamp's guide (inf for none) and the unit normal
    there pointing out of the rod's material, in the lamp frame. ``inside_rod`` marks rays known
    to travel inside the rod (they meet it: the bounding-box test is skipped for them).

    The rod without its grooves is convex: the ray's span inside it is [t_enter, t_exit], the
    largest entry and the smallest exit over its end planes and its side (slabs, or the cylinder's
    two roots), and its hit the entry, or the exit for a ray inside. The grooves only take material
    away near the back: that hit is dropped where its point lies in a groove, and the facets the ray
    crosses within the span, cell by cell, are offered instead (``_facets``)."""
    t, normal = np.full(len(o), np.inf), np.zeros((len(o), 3))
    frame = to_guide(o, d, guide, lamp)
    box = {key: getattr(guide, key).take(lamp) for key in ("half_u", "half_v", "length")}
    # most rays of the air pass far from a thin rod: the rest only for the rays that meet its box
    meets = _meets_box(frame, box)
    if inside_rod is not None:
        meets |= inside_rod
    near = np.nonzero(meets)[0]
    if len(near):
        lamp_near = lamp.take(near)
        sub = gathered(guide, lamp_near)
        with np.errstate(divide="ignore", invalid="ignore"):
            t_near, n_frame = _hit_in_frame(tuple(part.take(near) for part in frame), sub)
        t[near] = t_near
        axis, across = rows(guide.axis, lamp_near), rows(guide.across, lamp_near)
        n_near = axis * n_frame[0][:, None] + across * n_frame[1][:, None]
        n_near[:, 1] += n_frame[2]
        put_rows(normal, near, n_near)
    return t, normal


def _meets_box(frame: tuple, g: dict) -> np.ndarray:
    """Whether each ray meets the rod's bounding box (ahead of it): a cheap test before the exact one."""
    s0, u0, v0, ds, du, dv = frame
    t_near, t_far = np.zeros(len(s0)), np.full(len(s0), np.inf)
    with np.errstate(divide="ignore", invalid="ignore"):
        for origin, direction, lo, hi in ((v0, dv, -g["half_v"], g["half_v"]), (u0, du, -g["half_u"], g["half_u"]),
                                          (s0, ds, 0.0, g["length"])):
            t_lo, t_hi = (lo - EPS - origin) / direction, (hi + EPS - origin) / direction
            # a ray parallel to a slab: inside it for ever (NaN where it starts on a bound: kept) or never
            near, far = np.fmin(t_lo, t_hi), np.fmax(t_lo, t_hi)
            parallel = direction == 0
            if parallel.any():
                outside = parallel & ((origin < lo - EPS) | (origin > hi + EPS))
                near = np.where(parallel, np.where(outside, np.inf, 0.0), near)
                far = np.where(parallel, np.where(outside, -np.inf, np.inf), far)
            np.fmax(t_near, near, out=t_near)
            np.fmin(t_far, far, out=t_far)
    return (t_near <= t_far) & (t_far > T_MIN)


def _hit_in_frame(frame: tuple, g: dict) -> tuple[np.ndarray, tuple]:
    """``hit_guide`` in the guide's frame: t and the normal's (s, u, v) components."""
    s0, u0, v0, ds, du, dv = frame
    n = len(s0)
    # (axis of the normal in the guide frame: 0 s, 1 u, 2 v, 3 the cylinder's radial; its sign)
    enter, exit_ = np.full(n, -np.inf), np.full(n, np.inf)
    enter_axis, exit_axis = np.zeros(n, np.int8), np.zeros(n, np.int8)
    enter_sign, exit_sign = np.zeros(n), np.zeros(n)

    def slab(origin, direction, lo, hi, axis):
        """Narrow the span to the slab lo <= x <= hi along one axis of the guide's frame."""
        t_lo, t_hi = (lo - origin) / direction, (hi - origin) / direction  # (the caller ignores x / 0)
        near, far = np.fmin(t_lo, t_hi), np.fmax(t_lo, t_hi)
        parallel = direction == 0  # in the slab for ever, or never
        if parallel.any():
            outside = parallel & ((origin < lo) | (origin > hi))
            near = np.where(parallel, np.where(outside, np.inf, -np.inf), near)
            far = np.where(parallel, np.where(outside, -np.inf, np.inf), far)
        sign_near = np.where(direction > 0, -1.0, 1.0)  # entering through the lo side when moving up
        take = near > enter
        np.copyto(enter, near, where=take)
        np.copyto(enter_axis, axis, where=take)
        np.copyto(enter_sign, sign_near, where=take)
        take = far < exit_
        np.copyto(exit_, far, where=take)
        np.copyto(exit_axis, axis, where=take)
        np.copyto(exit_sign, -sign_near, where=take)

    slab(s0, ds, 0.0, g["length"], 0)
    rnd = g["round"] > 0
    if not rnd.any():  # rectangular rods only: their slabs as they are
        slab(u0, du, -g["half_u"], g["half_u"], 1)
        slab(v0, dv, -g["half_v"], g["half_v"], 2)
    elif not rnd.all():
        inf = np.where(rnd, np.inf, 1.0)  # round rods are bounded by the cylinder below, not by slabs
        slab(u0, du, -g["half_u"] * inf, g["half_u"] * inf, 1)
        slab(v0, dv, -g["half_v"] * inf, g["half_v"] * inf, 2)
    if rnd.any():
        a = du * du + dv * dv
        c = u0 * u0 + v0 * v0 - g["half_u"] ** 2
        lo, hi = solve_quadratic(a, 2.0 * (u0 * du + v0 * dv), c)
        along = a < 1e-15  # parallel to the axis: inside the cylinder for ever, or never
        lo = np.where(along, np.where(c <= 0, -np.inf, np.inf), np.where(np.isnan(lo), np.inf, lo))
        hi = np.where(along, np.where(c <= 0, np.inf, -np.inf), np.where(np.isnan(hi), -np.inf, hi))
        lo, hi = np.where(rnd, lo, -np.inf), np.where(rnd, hi, np.inf)
        take = lo > enter
        np.copyto(enter, lo, where=take)
        np.copyto(enter_axis, 3, where=take)
        take = hi < exit_
        np.copyto(exit_, hi, where=take)
        np.copyto(exit_axis, 3, where=take)

    span = (enter <= exit_) & (exit_ > T_MIN)
    from_outside = enter > T_MIN
    t = np.where(span, np.where(from_outside, enter, exit_), np.inf)
    axis_hit = np.where(from_outside, enter_axis, exit_axis)
    sign_hit = np.where(from_outside, enter_sign, exit_sign)
    ns, nu, nv = np.zeros(n), np.zeros(n), np.zeros(n)
    for out, axis in ((ns, 0), (nu, 1), (nv, 2)):
        np.copyto(out, sign_hit, where=axis_hit == axis)
    radial = np.nonzero((axis_hit == 3) & np.isfinite(t))[0]
    if len(radial):
        tr = t[radial]
        r = g["half_u"][radial]
        nu[radial] = (u0[radial] + tr * du[radial]) / r
        nv[radial] = (v0[radial] + tr * dv[radial]) / r

    # the grooves matter only to rays whose span inside the rod rises above the grooves' bottom (v is
    # linear along a ray: its highest point is one end of the span)
    v_top = np.maximum(v0 + np.maximum(enter, 0.0) * dv, v0 + np.minimum(exit_, 1e30) * dv)
    has = np.nonzero(span & (g["prisms"] > 0) & (v_top > g["half_v"] - g["prism_depth"]))[0]
    if len(has):
        _grooves(has, t, (ns, nu, nv), s0, v0, ds, dv, g, enter, exit_)

    return t, (ns, nu, nv)


def _grooves(has, t, normal, s0, v0, ds, dv, g, enter, exit_) -> None:
    """The rays ``has`` whose lamps' rods have prisms: their convex hit dropped where it lies in a
    groove, then the facets of the prisms whose cells they cross between the grooves' bottom and the
    back, within their span of the rod, offered (in place on ``t`` and ``normal``)."""
    sub = {key: g[key].take(has) for key in ("half_v", "prism_depth", "first_prism", "pitch", "prisms", "slope")}
    s0, v0, ds, dv = s0.take(has), v0.take(has), ds.take(has), dv.take(has)
    t_sub = t.take(has)
    bottom = sub["half_v"] - sub["prism_depth"]
    v_hit = v0 + t_sub * dv
    high = np.nonzero(v_hit > bottom)[0]  # only there can the hit lie in a groove
    if len(high):
        at_high = {key: value.take(high) for key, value in sub.items()}
        grooved = in_groove(s0.take(high) + t_sub.take(high) * ds.take(high), v_hit.take(high), at_high)
        t_sub[high[grooved]] = np.inf
    ns, nu, nv = (part.take(has) for part in normal)
    t_in, t_out = slab_span(v0, dv, bottom, sub["half_v"], np.minimum(exit_.take(has), t_sub))
    t_in = np.maximum(t_in, np.maximum(enter.take(has), 0.0))
    live = np.nonzero(t_in <= t_out)[0]
    if len(live):
        # the live rays' values gathered once; the cells walked in step, each a subset of the last
        ray = {"s0": s0.take(live), "v0": v0.take(live), "ds": ds.take(live), "dv": dv.take(live),
               "bottom": bottom.take(live), "top": sub["half_v"].take(live) + EPS,
               "first": sub["first_prism"].take(live), "pitch": sub["pitch"].take(live), "m": sub["slope"].take(live),
               "lo": enter.take(has).take(live) - EPS, "hi": exit_.take(has).take(live) + EPS,
               "t": t_sub.take(live), "ns": ns.take(live), "nv": nv.take(live), "at": np.arange(len(live))}
        row = {"first_prism": ray["first"], "pitch": ray["pitch"], "prisms": sub["prisms"].take(live)}
        k_in = nearest_prism(ray["s0"] + t_in.take(live) * ray["ds"], row)
        k_out = nearest_prism(ray["s0"] + t_out.take(live) * ray["ds"], row)
        ray["k"], ray["step"] = k_in, np.sign(k_out - k_in)
        ray["cells"] = np.abs(k_out - k_in).astype(np.int64)
        ray["sec"] = np.sqrt(1.0 + ray["m"] * ray["m"])
        found = {"t": ray["t"].copy(), "ns": ray["ns"].copy(), "nv": ray["nv"].copy(), "nu": nu.take(live)}
        cells = ray["cells"]
        for j in range(int(cells.max()) + 1):
            if j:  # the rays with a j-th cell still to cross
                going = np.nonzero(ray["cells"] >= j)[0]
                ray = {key: value.take(going) for key, value in ray.items()}
                ray["t"] = found["t"].take(ray["at"])
            _cell_facets(ray, j, found)
        t_sub[live], ns[live], nu[live], nv[live] = found["t"], found["ns"], found["nu"], found["nv"]
    t[has] = t_sub
    for part, values in zip(normal, (ns, nu, nv), strict=True):
        part[has] = values


def _cell_facets(ray: dict, j: int, found: dict) -> None:
    """The two facets of the j-th prism cell of each ray in ``ray`` (the live rays' values; ``at``: their
    places in ``found``), where met nearer than the ray's best so far, within its span, below the back:
    taken into ``found`` (t and the normal's s, u, v) and ``ray["t"]``."""
    m, s0, v0, ds, dv = ray["m"], ray["s0"], ray["v0"], ray["ds"], ray["dv"]
    apex = ray["first"] + (ray["k"] + j * ray["step"]) * ray["pitch"]
    for side in (1.0, -1.0):  # the facet beyond the apex (s > s_k) rises with s, the other falls
        # v = bottom + side m (s − apex) along the ray: v0 + t dv = bottom + side m (s0 + t ds − apex)
        tf = (ray["bottom"] + side * m * (s0 - apex) - v0) / (dv - side * m * ds)
        s_hit = s0 + tf * ds
        ok = (tf > T_MIN) & (tf < ray["t"]) & (side * (s_hit - apex) >= -EPS)
        ok &= (tf >= ray["lo"]) & (tf <= ray["hi"])
        ok &= v0 + tf * dv <= ray["top"]
        take = np.nonzero(ok)[0]
        if len(take):
            at = ray["at"].take(take)
            t_new = tf.take(take)
            ray["t"][take] = t_new
            found["t"][at] = t_new
            sec = ray["sec"].take(take)
            found["ns"][at] = -side * m.take(take) / sec
            found["nu"][at] = 0.0
            found["nv"][at] = 1.0 / sec

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
    sel = np.nonzero(guide.present.take(rays.lamp) > 0)[0]
    if len(sel):
        t_sel, n_sel = hit_guide(rows(rays.o, sel), rows(rays.d, sel), guide, rays.lamp.take(sel))
        t[sel] = t_sel
        put_rows(normal, sel, n_sel)
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


def hit_guide(o: np.ndarray, d: np.ndarray, guide: GuideTable, lamp: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per ray, the nearest hit on the rod of its lamp's guide (inf for none) and the unit normal
    there pointing out of the rod's material, in the lamp frame."""
    g = gathered(guide, lamp)
    s0, u0, v0, ds, du, dv = to_guide(o, d, guide, lamp)
    n = len(o)
    best = np.full(n, np.inf)
    ns, nu, nv = np.zeros(n), np.zeros(n), np.zeros(n)  # the normal in the guide frame

    def offer(t: np.ndarray, normal: tuple, extra: np.ndarray | None = None) -> None:
        """Keep ``t`` where it is past T_MIN, nearer than the best, and its point lies on the rod."""
        with np.errstate(invalid="ignore"):
            ok = (t > T_MIN) & (t < best)
        if extra is not None:
            ok &= extra
        idx = np.nonzero(ok)[0]
        if not len(idx):
            return
        ti = t[idx]
        on = inside(s0[idx] + ti * ds[idx], u0[idx] + ti * du[idx], v0[idx] + ti * dv[idx],
                    {key: value[idx] for key, value in g.items()})
        idx = idx[on]
        best[idx] = t[idx]
        for out, value in zip((ns, nu, nv), normal, strict=True):
            out[idx] = value if np.isscalar(value) else value[idx]

    with np.errstate(divide="ignore", invalid="ignore"):
        # the end faces
        offer(-s0 / ds, (-1.0, 0.0, 0.0))
        offer((g["length"] - s0) / ds, (1.0, 0.0, 0.0))
        # the side
        rnd = g["round"] > 0
        if rnd.any():
            lo, hi = solve_quadratic(du * du + dv * dv, 2.0 * (u0 * du + v0 * dv),
                                     u0 * u0 + v0 * v0 - g["half_u"] ** 2)
            for root in (lo, hi):
                r = g["half_u"]
                offer(root, (0.0, (u0 + root * du) / r, (v0 + root * dv) / r), rnd)
        square = ~rnd
        if square.any():
            for sign in (-1.0, 1.0):
                offer((sign * g["half_u"] - u0) / du, (0.0, sign, 0.0), square)
                offer((sign * g["half_v"] - v0) / dv, (0.0, 0.0, sign), square)
        # the prisms' facets, cell by cell between the grooves' bottom and the back
        _offer_facets(offer, s0, v0, ds, dv, g, best)

    axis, across = rows(guide.axis, lamp), rows(guide.across, lamp)
    normal = axis * ns[:, None] + across * nu[:, None]
    normal[:, 1] += nv
    return best, normal


def _offer_facets(offer, s0, v0, ds, dv, g, best) -> None:
    """The V grooves' facets the rays can meet: the cells of the prisms crossed while between the
    grooves' bottom (v_back − δ) and the back (v_back), nearer than the best hit so far."""
    has = np.nonzero(g["prisms"] > 0)[0]
    if not len(has):
        return
    bottom = g["half_v"] - g["prism_depth"]
    t_in, t_out = slab_span(v0, dv, bottom, g["half_v"], best)
    live = np.zeros(len(s0), bool)
    live[has] = True
    live &= t_in <= t_out
    idx = np.nonzero(live)[0]
    if not len(idx):
        return
    row = {key: g[key][idx] for key in ("first_prism", "pitch", "prisms")}
    k_in = nearest_prism(s0[idx] + t_in[idx] * ds[idx], row)
    k_out = nearest_prism(s0[idx] + t_out[idx] * ds[idx], row)
    step = np.sign(k_out - k_in)
    cells = np.abs(k_out - k_in).astype(np.int64)
    m = g["slope"]
    sec = np.sqrt(1.0 + m * m)
    for j in range(int(cells.max()) + 1):
        going = idx[cells >= j]
        k = np.full(len(s0), np.nan)
        k[going] = (k_in + j * step)[cells >= j]
        apex = g["first_prism"] + k * g["pitch"]
        for side in (1.0, -1.0):  # the facet beyond the apex (s > s_k) rises with s, the other falls
            # v = bottom + side m (s − apex) along the ray: v0 + t dv = bottom + side m (s0 + t ds − apex)
            t = (bottom + side * m * (s0 - apex) - v0) / (dv - side * m * ds)
            s_hit = s0 + t * ds
            on_side = side * (s_hit - apex) >= -EPS
            offer(t, (-side * m / sec, 0.0, 1.0 / sec), on_side & np.isfinite(k))

"""An arc light guide's intersections (docs/model.md §8.7a): a rectangular section swept along a
circular arc in the lens plane, with V-shaped extraction prisms across its back (+y).

With C the arc's centre, R its radius, Φ its sweep, ρ a point's distance from C in the lens plane,
φ its angle about C from the guide's middle (``GuideTable``: P(φ) = C + R (sin φ · a − cos φ · c)),
v = y − depth, the rod is the set

    |ρ − R| <= w/2,   |v| <= h/2,   |φ| <= Φ/2,   v <= h/2 − δ + m |τ_k|,

τ_k = (x − C)·t_k the distance from the radial plane of the prism k nearest φ (t_k the tangent at
its apex angle φ_k, so each facet is a plane), m the tangent of the facets' angle. Its bounding
surfaces are exact: two cylinders about the y axis through C (a quadratic each), two planes v =
±h/2, two radial end planes, and the facets. The rod is not convex, so a ray's hit is the nearest
candidate past ``T_MIN`` — each surface's crossings, and the facets of the prisms whose cells the
ray crosses in the grooves' slab — whose point lies in the rod (within ``EPS``). A round section
swept along an arc would be a torus (a quartic): refused (``scene.guide_checks``).
"""

from __future__ import annotations

import numpy as np

from ..guide_table import GuideTable
from .base import T_MIN, rows, slab_span, solve_quadratic

EPS = 1e-7  # mm, as ``light_guide.EPS``


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.einsum("ij,ij->i", a, b)


class _Arc:
    """The rows' arc guides gathered: per ray its guide's values."""

    def __init__(self, guide: GuideTable, lamp: np.ndarray):
        self.centre, self.a, self.c = (rows(x, lamp) for x in (guide.arc_centre, guide.axis, guide.across))
        self.radius, self.sweep = guide.radius.take(lamp), guide.sweep.take(lamp)
        self.half_w, self.half_h = guide.half_u.take(lamp), guide.half_v.take(lamp)
        self.depth = self.centre[:, 1]
        self.pitch, self.first = guide.pitch.take(lamp), guide.first_prism.take(lamp)
        self.count = guide.prisms.take(lamp)
        self.prism_depth, self.slope = guide.prism_depth.take(lamp), guide.slope.take(lamp)

    def take(self, idx: np.ndarray) -> _Arc:
        out = object.__new__(_Arc)
        for key, value in vars(self).items():
            setattr(out, key, value.take(idx, axis=0))
        return out

    def angle(self, p: np.ndarray) -> np.ndarray:
        rel = p - self.centre
        return np.arctan2(_dot(rel, self.a), -_dot(rel, self.c))

    def nearest_prism(self, phi: np.ndarray) -> np.ndarray:
        s = self.radius * (phi + 0.5 * self.sweep)
        with np.errstate(invalid="ignore", divide="ignore"):
            k = np.floor((s - self.first) / self.pitch + 0.5)
        return np.clip(k, 0.0, np.maximum(self.count - 1.0, 0.0))

    def tangent(self, k: np.ndarray) -> np.ndarray:
        """t_k: the tangent at prism k's apex angle φ_k = s_k / R − Φ/2."""
        phi = (self.first + k * self.pitch) / self.radius - 0.5 * self.sweep
        return np.cos(phi)[:, None] * self.a + np.sin(phi)[:, None] * self.c

    def inside(self, p: np.ndarray) -> np.ndarray:
        rel = p - self.centre
        rho = np.hypot(rel[:, 0], rel[:, 2])
        v = p[:, 1] - self.depth
        phi = self.angle(p)
        ok = (np.abs(rho - self.radius) <= self.half_w + EPS) & (np.abs(v) <= self.half_h + EPS)
        ok &= np.abs(phi) <= 0.5 * self.sweep + EPS / np.maximum(rho, EPS)
        tau = _dot(rel, self.tangent(self.nearest_prism(phi)))
        floor = self.half_h - self.prism_depth + self.slope * np.abs(tau)
        grooved = (self.count > 0) & (v > floor + EPS * np.sqrt(1.0 + self.slope**2))
        return ok & ~grooved


def hit_arc(o: np.ndarray, d: np.ndarray, guide: GuideTable, lamp: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per ray, the nearest hit on its lamp's arc guide (inf for none) and the unit normal there
    pointing out of the rod's material, in the lamp frame."""
    n = len(o)
    t_best, normal = np.full(n, np.inf), np.zeros((n, 3))
    g = _Arc(guide, lamp)
    rel = o - g.centre
    # the crossings of the two cylinders |(x − C)_xz| = R ± w/2: a, b, c of a t² + b t + c
    qa = d[:, 0] ** 2 + d[:, 2] ** 2
    qb = 2.0 * (rel[:, 0] * d[:, 0] + rel[:, 2] * d[:, 2])
    rho2 = rel[:, 0] ** 2 + rel[:, 2] ** 2
    outer_lo, outer_hi = solve_quadratic(qa, qb, rho2 - (g.radius + g.half_w) ** 2)
    # most rays pass far from a thin rod: the rest only for those that meet the outer cylinder within its slab
    t_in, t_out = slab_span(rel[:, 1], d[:, 1], -g.half_h - EPS, g.half_h + EPS, np.full(n, np.inf))
    vertical, within = qa < 1e-15, rho2 <= (g.radius + g.half_w) ** 2
    lo = np.where(vertical, np.where(within, -np.inf, np.inf), np.nan_to_num(outer_lo, nan=np.inf))
    hi = np.where(vertical, np.where(within, np.inf, -np.inf), np.nan_to_num(outer_hi, nan=-np.inf))
    near = np.nonzero((np.maximum(lo, t_in) <= np.minimum(hi, t_out) + EPS) & (np.minimum(hi, t_out) > T_MIN))[0]
    if not len(near):
        return t_best, normal
    g, o, d, rel = g.take(near), rows(o, near), rows(d, near), rows(rel, near)
    qa, qb, rho2 = qa.take(near), qb.take(near), rho2.take(near)
    t_sub, n_sub = np.full(len(near), np.inf), np.zeros((len(near), 3))

    def offer(t: np.ndarray, nrm: np.ndarray, idx: np.ndarray | None = None) -> None:
        """Keep candidate t (normal nrm) where it is nearer and its point lies in the rod."""
        idx = np.arange(len(t_sub)) if idx is None else idx
        with np.errstate(invalid="ignore"):
            ok = np.isfinite(t) & (t > T_MIN) & (t < t_sub.take(idx))
        sel = np.nonzero(ok)[0]
        if not len(sel):
            return
        rays = idx.take(sel)
        p = rows(o, rays) + rows(d, rays) * t.take(sel)[:, None]
        good = g.take(rays).inside(p)
        rays, sel = rays[good], sel[good]
        t_sub[rays] = t.take(sel)
        n_sub[rays] = rows(nrm, sel)

    for sign in (1.0, -1.0):  # the outer cylinder (normal outward from C), the inner (toward C)
        roots = solve_quadratic(qa, qb, rho2 - (g.radius + sign * g.half_w) ** 2)
        for root in roots:
            with np.errstate(invalid="ignore"):
                p = rel + d * np.nan_to_num(root, nan=0.0)[:, None]
            radial = p * np.array([1.0, 0.0, 1.0])
            radial /= np.maximum(np.linalg.norm(radial, axis=1), 1e-300)[:, None]
            offer(np.where(qa < 1e-15, np.nan, root), sign * radial)
    with np.errstate(divide="ignore", invalid="ignore"):
        for sign in (1.0, -1.0):  # the back and the front, v = ±h/2
            offer((sign * g.half_h - rel[:, 1]) / d[:, 1], np.tile([0.0, sign, 0.0], (len(t_sub), 1)))
        for sign in (1.0, -1.0):  # the end faces φ = ±Φ/2, their normal ±t(±Φ/2)
            end = 0.5 * sign * g.sweep
            tangent = np.cos(end)[:, None] * g.a + np.sin(end)[:, None] * g.c
            offer(-_dot(rel, tangent) / _dot(d, tangent), sign * tangent)
    _facets(g, o, d, rel, offer, len(t_sub))
    t_best[near] = t_sub
    normal[near] = n_sub
    return t_best, normal


def _facets(g: _Arc, o: np.ndarray, d: np.ndarray, rel: np.ndarray, offer, n: int) -> None:
    """Offer the facets of the prisms whose cells each ray crosses in the grooves' slab, h/2 − δ <= v
    <= h/2, within the outer cylinder: a line's angle about C changes monotonically along it, so its
    cells there are the ones between those of its two ends."""
    has = np.nonzero(g.count > 0)[0]
    if not len(has):
        return
    bottom = g.half_h - g.prism_depth
    qa = d[:, 0] ** 2 + d[:, 2] ** 2
    lo, hi = solve_quadratic(qa, 2.0 * (rel[:, 0] * d[:, 0] + rel[:, 2] * d[:, 2]),
                             rel[:, 0] ** 2 + rel[:, 2] ** 2 - (g.radius + g.half_w) ** 2)
    vertical = qa < 1e-15  # along y: within the outer cylinder for ever, or never
    within = rel[:, 0] ** 2 + rel[:, 2] ** 2 <= (g.radius + g.half_w) ** 2
    lo = np.where(vertical, np.where(within, -np.inf, np.inf), np.nan_to_num(lo, nan=np.inf))
    far = np.where(vertical, np.where(within, np.inf, -np.inf), np.nan_to_num(hi, nan=-np.inf))
    t_in, t_out = slab_span(rel[:, 1], d[:, 1], bottom - EPS, g.half_h + EPS, far)
    t_in = np.maximum(np.maximum(t_in, lo), 0.0)
    t_out = np.minimum(t_out, 1e12)  # a ray along the back within the cylinder: its cells to the rod's far side
    live = has[np.nonzero((t_in.take(has) <= t_out.take(has)) & np.isfinite(t_out.take(has)))[0]]
    if not len(live):
        return
    gl = g.take(live)
    k_in = gl.nearest_prism(gl.angle(rows(o, live) + rows(d, live) * t_in.take(live)[:, None]))
    k_out = gl.nearest_prism(gl.angle(rows(o, live) + rows(d, live) * t_out.take(live)[:, None]))
    step = np.sign(k_out - k_in)
    cells = np.abs(k_out - k_in).astype(np.int64)
    m = gl.slope
    sec = np.sqrt(1.0 + m * m)
    for j in range(int(cells.max()) + 1):
        going = np.nonzero(cells >= j)[0]
        rays = live.take(going)
        tk = g.take(rays).tangent((k_in + j * step).take(going))
        tau0, dtau = _dot(rows(rel, rays), tk), _dot(rows(d, rays), tk)
        mg = m.take(going)
        for side in (1.0, -1.0):  # v = bottom + side m τ: the facet on the τ > 0 side rises with τ
            with np.errstate(divide="ignore", invalid="ignore"):
                tf = (bottom.take(rays) + side * mg * tau0 - rel[rays, 1]) / (d[rays, 1] - side * mg * dtau)
                on_side = side * (tau0 + tf * dtau) >= -EPS
            nrm = (-side * mg)[:, None] * tk
            nrm[:, 1] += 1.0
            offer(np.where(on_side, tf, np.nan), nrm / sec.take(going)[:, None], rays)

"""Cylindrical flutes: parallel cylindrical ridges on the lens's inner face, Table 1's cut face
like the fish-eye cuts (``cuts``) and the saw-tooth ridges (``sawtooth``).

Geometry (README, model: where the paper is silent). With s = a . (x, z) across the ridges
(``LampTable.ridge_across``), strip k covers (k - 1/2) p <= s <= (k + 1/2) p, one strip centred on
the axis; its flute is the cylinder of radius rho = (p^2/4 + h^2) / 2h along the ridges, apex at
(s = k p, plane B), meeting plane A at the strip's borders, so neighbouring flutes meet in creases.

Intersection: the paper's plane-A / plane-B method (Fig. 9) with strips for cells: the strips
crossed between the two planes are walked from the entry side (a 1-D traversal) and each one's
cylinder tested; the first root inside its own strip is the hit. A ray crosses a few strips in the
slab, and at most (2R/p + 3) however it is aimed, which validation bounds."""

from __future__ import annotations

import numpy as np

from ...scene.spec import MAX_CUTS_ACROSS
from .. import optics
from .. import paths as P
from ..lamp_table import LampTable
from .base import T_MIN, Segments
from .cuts import INTO_AIR, INTO_LENS, OFF_CAP, flat_base_hits

SURFACE = P.CUT
MEDIA = (P.IN_LENS, P.IN_AIR)
MAX_STRIP_STEPS = MAX_CUTS_ACROSS + 3  # across the lens diameter 2R <= MAX_CUTS_ACROSS p, and the ends
TOL = 1e-9  # mm of ray parameter: a root on a strip border belongs to both strips


def intersect(rays: Segments, lamps: LampTable, t_limit: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    # As for the fish-eye caps: a ray that starts on a flute excludes it by geometry.
    on_cap = np.where(rays.src != P.CUT, OFF_CAP, np.where(rays.medium == P.IN_AIR, INTO_AIR, INTO_LENS))
    li = rays.lamp
    return hit_flutes(rays.o, rays.d, lamps.plane_a[li], lamps.plane_b[li], lamps.pitch[li], lamps.flute_radius[li],
                      lamps.ridge_across[li], t_limit, on_cap.astype(np.int8))


def hit_flutes(o: np.ndarray, d: np.ndarray, plane_a: np.ndarray, plane_b: np.ndarray, pitch: np.ndarray,
               rho: np.ndarray, across: np.ndarray, t_limit: np.ndarray,
               on_cap: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The fluted surface: the hit parameter (inf for none nearer than ``t_limit``) and the unit
    normal out of the lens material. ``on_cap`` as in ``cuts.hit_cuts``."""
    n = len(o)
    t_hit = np.full(n, np.inf)
    normal = np.zeros((n, 3))
    normal[:, 1] = 1.0
    on_cap = np.zeros(n, np.int8) if on_cap is None else on_cap

    flat_base_hits(o, d, plane_a, t_limit, np.nonzero(~np.isfinite(rho) & (on_cap == OFF_CAP))[0], t_hit)

    ray = np.nonzero(np.isfinite(rho))[0]
    if len(ray) == 0:
        return t_hit, normal
    ax, az = across[ray, 0], across[ray, 1]
    oy, dy = o[ray, 1], d[ray, 1]
    s0 = o[ray, 0] * ax + o[ray, 2] * az
    ds = d[ray, 0] * ax + d[ray, 2] * az
    a_plane, b_plane, p, r, cap = plane_a[ray], plane_b[ray], pitch[ray], rho[ray], on_cap[ray]

    with np.errstate(divide="ignore", invalid="ignore"):
        ta, tb = (a_plane - oy) / dy, (b_plane - oy) / dy
    t_in, t_out = np.fmin(ta, tb), np.fmax(ta, tb)
    parallel = dy == 0
    in_slab = (oy >= a_plane) & (oy <= b_plane)
    t_in = np.where(parallel, np.where(in_slab, 0.0, np.inf), np.maximum(t_in, 0.0))
    t_out = np.minimum(np.where(parallel, np.where(in_slab, np.inf, -np.inf), t_out), t_limit[ray])

    live = np.nonzero(t_in <= t_out)[0]
    ray, s0, ds, oy, dy, p, r, cap = ray[live], s0[live], ds[live], oy[live], dy[live], p[live], r[live], cap[live]
    t_cell, t_out, b_plane = t_in[live], t_out[live], b_plane[live]
    k = np.floor((s0 + t_cell * ds) / p + 0.5)
    step = np.sign(ds)
    with np.errstate(divide="ignore", invalid="ignore"):
        t_next = np.where(step != 0, ((k + 0.5 * step) * p - s0) / ds, np.inf)
        dt = np.where(step != 0, p / np.abs(ds), np.inf)
    # Cell-independent terms of the roots, relative to the apex (see ``cuts._CellWalk.cap_hits``):
    # |q + t D + rho y|^2 = rho^2 with q = (s0 - k p, o_y - plane B), D = (d_s, d_y).
    qy = oy - b_plane
    a2 = ds * ds + dy * dy
    b_y = qy * dy + r * dy
    c_y = qy * qy + 2.0 * r * qy
    strip = np.zeros(n)
    first = True
    for _ in range(MAX_STRIP_STEPS):
        if len(ray) == 0:
            break
        qs = s0 - k * p
        b = qs * ds + b_y
        c = qs * qs + c_y
        with np.errstate(invalid="ignore", divide="ignore"):
            q = -(b + np.copysign(np.sqrt(b * b - a2 * c), b))
            r1, r2 = q / a2, c / q
        lo, hi = np.fmin(r1, r2), np.fmax(r1, r2)
        if first:  # the flute a ray starts on: leaving it outward never back, inward only its far root
            lo = np.where(cap == OFF_CAP, lo, np.nan)
            hi = np.where(cap == INTO_AIR, np.nan, hi)
            first = False
        t_end = np.minimum(t_next, t_out)
        lo_ok = (lo > T_MIN) & (lo >= t_cell - TOL) & (lo <= t_end + TOL)
        hi_ok = (hi > T_MIN) & (hi >= t_cell - TOL) & (hi <= t_end + TOL)
        t = np.where(lo_ok, lo, np.where(hi_ok, hi, np.inf))
        found = np.isfinite(t)
        t_hit[ray[found]] = t[found]
        strip[ray[found]] = k[found]
        go = ~found & (t_next <= t_out)
        t_cell, k, t_next = t_next, k + step, t_next + dt
        keep = np.nonzero(go)[0]
        ray, s0, ds, p, t_cell, t_out, k, t_next, dt, b_y, c_y, a2, step = (
            x[keep] for x in (ray, s0, ds, p, t_cell, t_out, k, t_next, dt, b_y, c_y, a2, step))

    hit = np.nonzero(np.isfinite(t_hit) & np.isfinite(rho))[0]
    if len(hit):
        h = o[hit] + t_hit[hit, None] * d[hit]
        ax, az = across[hit, 0], across[hit, 1]
        ns = h[:, 0] * ax + h[:, 2] * az - strip[hit] * pitch[hit]
        ny = h[:, 1] - (plane_b[hit] - rho[hit])
        normal[hit] = optics.normalize(np.stack([ns * ax, ny, ns * az], axis=1))
    return t_hit, normal


def profile_height(x: np.ndarray, z: np.ndarray, plane_b: float, pitch: float, rho: float,
                   across: tuple[float, float]) -> np.ndarray:
    """Height y of the fluted surface above (x, z)."""
    s = np.asarray(x) * across[0] + np.asarray(z) * across[1]
    u = s - np.floor(s / pitch + 0.5) * pitch
    return plane_b - u * u / (rho + np.sqrt(np.maximum(rho * rho - u * u, 0.0)))

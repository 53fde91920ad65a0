"""The saw-tooth cuts (paper §5(2), 鋸状カット): parallel prismatic ridges on the lens's inner
face, a Fresnel surface met from inside the lens and from the air, like the fish-eye cuts
(``cuts``) whose surface id (Table 1's cut face) they share.

Geometry (README, model: where the paper is silent). With ``a`` the unit vector across the ridges
in the lens plane (``LampTable.ridge_across``) and s = a . (x, z), strip k covers
(k - 1/2) p <= s <= (k + 1/2) p, one strip centred on the lamp axis. Its inclined facet rises from
plane A (y = t) at the strip's lower border at the tooth angle alpha to plane B (y = t + h,
h = p tan alpha) at its upper border; its return facet is the plane s = (k + 1/2) p between the
two planes, perpendicular to the lens plane. The lens material lies below the profile (smaller y).

Intersection: the paper's plane-A / plane-B method (Fig. 9) with strips for cells. Every strip
border crossed between the planes carries a return facet as high as the whole slab, so a ray
entering the slab in strip k meets either strip k's inclined facet, or the return facet at the
border ahead of it, or neither (it leaves the slab first): one strip and one border per ray,
whatever the number of ridges, and never every strip."""

from __future__ import annotations

import numpy as np

from .. import paths as P
from ..lamp_table import LampTable
from .base import T_MIN, Segments

SURFACE = P.CUT
MEDIA = (P.IN_LENS, P.IN_AIR)

# mm: a ray whose origin lies this close to a facet's plane starts on it, and a plane is never
# met again by a ray leaving it (whatever the distance a rounding error would put the
# re-intersection at for a grazing ray); likewise the border a ray stands on is behind it.
ON_PLANE = 1e-9
TOL = 1e-9  # mm of ray parameter: a hit on a strip border belongs to both sides


def intersect(rays: Segments, lamps: LampTable, t_limit: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    li = rays.lamp
    return hit_sawtooth(rays.o, rays.d, lamps.plane_a[li], lamps.plane_b[li], lamps.pitch[li],
                        lamps.tooth_slope[li], lamps.ridge_across[li], t_limit)


def hit_sawtooth(o: np.ndarray, d: np.ndarray, plane_a: np.ndarray, plane_b: np.ndarray, pitch: np.ndarray,
                 slope: np.ndarray, across: np.ndarray, t_limit: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The saw-tooth surface: the hit parameter (inf for none nearer than ``t_limit``) and the
    unit normal pointing out of the lens material (toward the air). ``slope`` is tan alpha,
    ``across`` the (N, 2) [x, z] unit vector across the ridges."""
    n = len(o)
    t_hit = np.full(n, np.inf)
    normal = np.zeros((n, 3))
    normal[:, 1] = 1.0
    oy, dy = o[:, 1], d[:, 1]

    flat = np.nonzero(slope == 0)[0]
    if len(flat):  # a zero tooth angle is a flat inner face: plane A, never met again from it
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (plane_a[flat] - oy[flat]) / dy[flat]
        ok = (t > T_MIN) & (t < t_limit[flat]) & (np.abs(oy[flat] - plane_a[flat]) > ON_PLANE)
        t_hit[flat[ok]] = t[ok]

    ray = np.nonzero(slope != 0)[0]
    if len(ray) == 0:
        return t_hit, normal
    o, d, a, b, p, m, ax, az, limit = (
        o[ray], d[ray], plane_a[ray], plane_b[ray], pitch[ray], slope[ray], across[ray, 0], across[ray, 1],
        t_limit[ray])
    oy, dy = o[:, 1], d[:, 1]

    # Planes A and B: the part of the ray inside the slab, [t_in, t_out], cut at the limit.
    with np.errstate(divide="ignore", invalid="ignore"):
        ta, tb = (a - oy) / dy, (b - oy) / dy
    t_in, t_out = np.fmin(ta, tb), np.fmax(ta, tb)
    parallel = dy == 0  # parallel to the planes: in the slab for ever or never
    in_slab = (oy >= a) & (oy <= b)
    t_in = np.where(parallel, np.where(in_slab, 0.0, np.inf), np.maximum(t_in, 0.0))
    t_out = np.minimum(np.where(parallel, np.where(in_slab, np.inf, -np.inf), t_out), limit)

    # The strip where the ray enters the slab; a ray standing on the border ahead of it (it starts
    # on that return facet, or rounding put it on the wrong side) is in the next strip.
    s0 = o[:, 0] * ax + o[:, 2] * az
    ds = d[:, 0] * ax + d[:, 2] * az
    step = np.sign(ds)
    with np.errstate(invalid="ignore"):
        s_in = s0 + np.where(np.isfinite(t_in), t_in, 0.0) * ds
    k = np.floor(s_in / p + 0.5)
    k += np.where((k + 0.5 * step) * p * step - s_in * step <= ON_PLANE, step, 0.0)

    # The inclined facet of strip k: y = A + m (s - (k - 1/2) p), skipped when the ray starts on it.
    s_low = (k - 0.5) * p
    residual = oy - a - m * (s0 - s_low)
    with np.errstate(divide="ignore", invalid="ignore"):
        t_facet = residual / (m * ds - dy)
        t_border = np.where(step != 0, ((k + 0.5 * step) * p - s0) / ds, np.inf)
    t_end = np.minimum(t_border, t_out)
    on_facet = np.abs(residual) <= ON_PLANE * np.sqrt(1.0 + m * m)  # distance to the plane
    facet = (~on_facet & (t_facet > T_MIN) & (t_facet >= t_in - TOL) & (t_facet <= t_end + TOL)
             & (t_in <= t_out))
    # Otherwise the return facet at the border ahead, if the ray reaches it inside the slab.
    border = ~facet & (t_border > T_MIN) & (t_border >= t_in - TOL) & (t_border <= t_out) & (t_in <= t_out)

    t_hit[ray] = np.where(facet, t_facet, np.where(border, t_border, np.inf))
    # Normals out of the lens: the facet's (-sin alpha a, cos alpha), the return facet's +a.
    cos_a = 1.0 / np.sqrt(1.0 + m * m)
    sin_a = m * cos_a
    normal[ray] = np.where(facet[:, None], np.stack([-sin_a * ax, cos_a, -sin_a * az], axis=1),
                           np.stack([ax, np.zeros_like(ax), az], axis=1))
    return t_hit, normal


def profile_height(x: np.ndarray, z: np.ndarray, plane_a: float, pitch: float, slope: float,
                   across: tuple[float, float]) -> np.ndarray:
    """Height y of the saw-tooth surface above (x, z) (on a return facet: its foot, plane A)."""
    s = np.asarray(x) * across[0] + np.asarray(z) * across[1]
    return plane_a + slope * (s - (np.floor(s / pitch + 0.5) - 0.5) * pitch)

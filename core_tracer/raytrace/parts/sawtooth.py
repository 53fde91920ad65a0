"""The saw-tooth cuts (paper §5(2), 鋸状カット): parallel prismatic ridges on the lens's inner
face, a Fresnel surface met from inside the lens and from the air, like the fish-eye cuts
(``cuts``) whose surface id (Table 1's cut face) they share.

Geometry (docs/model.md, model: where the paper is silent). With ``a`` the unit vector across the ridges
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
from .base import T_MIN, Segments, put_rows, rows, slab_span

SURFACE = P.CUT
MEDIA = (P.IN_LENS, P.IN_AIR)

# mm: a ray whose origin lies this close to a facet's plane starts on it, and a plane is never
# met again by a ray leaving it (whatever the distance a rounding error would put the
# re-intersection at for a grazing ray); likewise the border a ray stands on is behind it.
ON_PLANE = 1e-9
TOL = 1e-9  # mm of ray parameter: a hit on a strip border belongs to both sides


def intersect(rays: Segments, lamps: LampTable, t_limit: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    li = rays.lamp  # (the lamps' rows gathered with take: faster than indexing)
    return hit_sawtooth(rays.o, rays.d, lamps.plane_a.take(li), lamps.plane_b.take(li), lamps.pitch.take(li),
                        lamps.tooth_slope.take(li), lamps.ridge_across.take(li, axis=0), t_limit)


def hit_sawtooth(o: np.ndarray, d: np.ndarray, plane_a: np.ndarray, plane_b: np.ndarray, pitch: np.ndarray,
                 slope: np.ndarray, across: np.ndarray, t_limit: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The saw-tooth surface: the hit parameter (inf for none nearer than ``t_limit``) and the
    unit normal pointing out of the lens material (toward the air). ``slope`` is tan alpha,
    ``across`` the (N, 2) [x, z] unit vector across the ridges."""
    n = len(o)
    flat = np.nonzero(slope == 0)[0]
    if len(flat) == 0:  # the usual case: every ray's lamp has teeth, no gathers
        return _hit_teeth(o, d, plane_a, plane_b, pitch, slope, across, t_limit)
    t_hit = np.full(n, np.inf)
    normal = np.zeros((n, 3))
    normal[:, 1] = 1.0
    oy, dy = o[:, 1], d[:, 1]
    # a zero tooth angle is a flat inner face: plane A, never met again from it
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (plane_a[flat] - oy[flat]) / dy[flat]
    ok = (t > T_MIN) & (t < t_limit[flat]) & (np.abs(oy[flat] - plane_a[flat]) > ON_PLANE)
    t_hit[flat[ok]] = t[ok]

    ray = np.nonzero(slope != 0)[0]
    if len(ray):
        t_hit[ray], nrm = _hit_teeth(rows(o, ray), rows(d, ray), plane_a[ray], plane_b[ray], pitch[ray], slope[ray],
                                     rows(across, ray), t_limit[ray])
        put_rows(normal, ray, nrm)
    return t_hit, normal


def _hit_teeth(o, d, a, b, p, m, across, limit) -> tuple[np.ndarray, np.ndarray]:
    """``hit_sawtooth`` for rays whose lamps all have teeth (m != 0)."""
    ax, az = across[:, 0], across[:, 1]
    oy, dy = o[:, 1], d[:, 1]
    # (one errstate: rays parallel to the planes or to the ridges divide by zero, on purpose)
    with np.errstate(divide="ignore", invalid="ignore"):
        # Planes A and B: the part of the ray inside the slab, [t_in, t_out], cut at the limit.
        t_in, t_out = slab_span(oy, dy, a, b, limit)

        # The strip where the ray enters the slab; a ray standing on the border ahead of it (it
        # starts on that return facet, or rounding put it on the wrong side) is in the next strip.
        s0 = o[:, 0] * ax + o[:, 2] * az
        ds = d[:, 0] * ax + d[:, 2] * az
        step = np.sign(ds)
        s_in = s0 + np.where(np.isfinite(t_in), t_in, 0.0) * ds
        k = np.floor(s_in / p + 0.5)
        np.add(k, step, out=k, where=(k + 0.5 * step) * p * step - s_in * step <= ON_PLANE)

        # The inclined facet of strip k: y = A + m (s - (k - 1/2) p), skipped when the ray starts on it.
        s_low = (k - 0.5) * p
        residual = oy - a - m * (s0 - s_low)
        t_facet = residual / (m * ds - dy)
        t_border = ((k + 0.5 * step) * p - s0) / ds
        along = np.nonzero(step == 0)[0]
        if len(along):  # parallel to the ridges: no border ahead
            t_border[along] = np.inf
        t_end = np.minimum(t_border, t_out)
        sec = np.sqrt(1.0 + m * m)
        live = t_in <= t_out
        facet = np.abs(residual) > ON_PLANE * sec  # not on the facet: farther from its plane than that
        facet &= t_facet > T_MIN
        facet &= t_facet >= t_in - TOL
        facet &= t_facet <= t_end + TOL
        facet &= live
        # Otherwise the return facet at the border ahead, if the ray reaches it inside the slab.
        border = ~facet
        border &= t_border > T_MIN
        border &= t_border >= t_in - TOL
        border &= t_border <= t_out
        border &= live

    t_hit = np.where(facet, t_facet, np.where(border, t_border, np.inf))
    # Normals out of the lens: the facet's (-sin alpha a, cos alpha), the return facet's +a.
    normal = np.zeros((len(o), 3))
    normal[:, 0], normal[:, 2] = ax, az
    f = np.nonzero(facet)[0]
    if len(f):
        cos_a = 1.0 / sec[f]
        sin_a = m[f] * cos_a
        normal[f, 0] = -sin_a * ax[f]
        normal[f, 1] = cos_a
        normal[f, 2] = -sin_a * az[f]
    return t_hit, normal


def profile_height(x: np.ndarray, z: np.ndarray, plane_a: float, pitch: float, slope: float,
                   across: tuple[float, float]) -> np.ndarray:
    """Height y of the saw-tooth surface above (x, z) (on a return facet: its foot, plane A)."""
    s = np.asarray(x) * across[0] + np.asarray(z) * across[1]
    return plane_a + slope * (s - (np.floor(s / pitch + 0.5) - 0.5) * pitch)

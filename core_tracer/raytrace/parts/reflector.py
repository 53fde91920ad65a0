"""The reflector (docs/model.md §3.2): the paraboloid y = y_v - (x^2 + z^2) / 4f between its rim and
its vertex, met from the air inside the lamp; shaded by eq. (3) and mirror-reflecting."""

from __future__ import annotations

import numpy as np

from .. import paths as P
from ..lamp_table import LampTable
from .base import Segments, axis_cylinder_terms, first_beyond, solve_quadratic

SURFACE = P.REFLECTOR
MEDIA = (P.IN_AIR,)


def hit_reflector(o: np.ndarray, d: np.ndarray, focal: np.ndarray, vertex: np.ndarray, rim: np.ndarray,
                  leaving: np.ndarray | None = None) -> np.ndarray:
    """The paraboloid y = y_v - (x^2 + z^2) / 4f between the rim and the vertex.

    For rays that start on the reflector (``leaving``) the root nearer 0 is the start itself:
    only the other one can be a hit, whatever its distance (see ``cuts.hit_cuts``)."""
    inv4f = 0.25 / focal
    # a = (d_x^2 + d_z^2) / 4f, b = d_y + 2 (o_x d_x + o_z d_z) / 4f, c = o_y + (o_x^2 + o_z^2) / 4f - y_v:
    # the axis cylinder's terms (of radius 0) scaled, in place
    a, b, c = axis_cylinder_terms(o, d, 0.0)
    a *= inv4f
    b *= inv4f
    b += d[:, 1]
    c *= inv4f
    c += o[:, 1]
    c -= vertex
    lo, hi = solve_quadratic(a, b, c)
    own = np.nonzero(leaving)[0] if leaving is not None else ()
    if len(own):  # (the few rays leaving the reflector, by index: not a select over every ray)
        lo_own, hi_own = lo.take(own), hi.take(own)
        own_is_lo = np.abs(lo_own) <= np.abs(hi_own)
        lo[own[own_is_lo]] = np.nan
        hi[own[~own_is_lo]] = np.nan
    y_lo = o[:, 1] + lo * d[:, 1]
    y_hi = o[:, 1] + hi * d[:, 1]
    return first_beyond(lo, hi, y_lo >= rim - 1e-9, y_hi >= rim - 1e-9)


def intersect(rays: Segments, lamps: LampTable, t_limit: np.ndarray) -> tuple[np.ndarray, None]:
    li = rays.lamp
    return hit_reflector(rays.o, rays.d, lamps.focal.take(li), lamps.vertex.take(li), lamps.rim.take(li),
                         rays.src == P.REFLECTOR), None


def reflector_normal(p: np.ndarray, focal: np.ndarray) -> np.ndarray:
    """Unit normal of the paraboloid facing the lamp interior."""
    two_f = 2.0 * focal
    nx, nz = -p[:, 0] / two_f, -p[:, 2] / two_f
    # the length as np.linalg.norm sums it, (x^2 + y^2) + z^2, without its slow reduction over rows
    length = np.sqrt(nx * nx + 1.0 + nz * nz)
    normal = np.empty((len(p), 3))  # (each column divided into place: no stacking copy)
    np.divide(nx, length, out=normal[:, 0])
    np.divide(-1.0, length, out=normal[:, 1])
    np.divide(nz, length, out=normal[:, 2])
    return normal

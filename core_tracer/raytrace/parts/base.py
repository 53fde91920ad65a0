"""What every part of a lamp offers the tracer, and the root-finding the parts share.

A part is a module with three names (see ``Part``): the surface it is in Table 1's terms
(``paths.OUTER``, ``paths.CUT`` …), the media a ray can reach it from, and ``intersect``. Inside
a lamp everything is in the lamp's local frame: x and z measured from the lamp axis, y as in the
world (outer lens face y = 0, interior y > 0).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

from ..lamp_table import LampTable

T_MIN = 1e-6  # mm: a hit closer than this to the ray's origin is the origin's own surface


@dataclass(frozen=True)
class Segments:
    """Rays inside their lamps, in each lamp's local frame, that can reach a part."""

    o: np.ndarray  # (N, 3) origins
    d: np.ndarray  # (N, 3) unit directions
    lamp: np.ndarray  # (N,) lamp number, the row of the ``LampTable``
    src: np.ndarray  # (N,) surface each ray starts on (``paths.OUTER`` …)
    medium: np.ndarray  # (N,) ``paths.IN_LENS`` or ``paths.IN_AIR``, one of the part's ``MEDIA``


class Part(Protocol):
    """One part type of the lamp (a module satisfies this)."""

    SURFACE: int  # the surface id of paths.CLASS_OF
    MEDIA: tuple[int, ...]  # the media from which a ray can reach it

    def intersect(self, rays: Segments, lamps: LampTable, t_limit: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
        """Per ray, the parameter of its first hit on this part (``inf`` for none) and, for a
        surface whose normal is only known while finding the hit, the unit normal there (else
        None). ``t_limit`` is the nearest hit on the parts before this one; a hit beyond it may
        be reported as ``inf``."""
        ...


def rows(a: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """``a[idx]`` for an index array: numpy's fancy indexing copies the rows of an (N, 3) array
    several times slower than ``take`` (and a boolean mask is slower still: index arrays throughout)."""
    return a.take(idx, axis=0)


def put_rows(a: np.ndarray, idx: np.ndarray, values: np.ndarray) -> None:
    """``a[idx] = values`` for (N, 3) arrays, column by column: several times faster than numpy's
    scatter of whole rows."""
    for axis in range(a.shape[1]):
        a[idx, axis] = values[:, axis]


def solve_quadratic(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Roots (small, large) of a t^2 + b t + c = 0 by the stable formula; NaN where none.
    Handles a == 0 (a linear equation) with both roots equal."""
    a, b, c = np.broadcast_arrays(a, b, c)
    r1, r2 = quadratic_roots(a, b, c)
    lo, hi = np.fmin(r1, r2), np.fmax(r1, r2)
    linear = np.nonzero(np.abs(a) < 1e-15)[0]  # rare: patched, not a select over every ray
    if len(linear):
        with np.errstate(invalid="ignore", divide="ignore"):
            lo[linear] = hi[linear] = -c[linear] / b[linear]
    return lo, hi


def slab_span(oy: np.ndarray, dy: np.ndarray, a: np.ndarray, b: np.ndarray,
              t_limit: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The part [t_in, t_out] of each ray (origin height ``oy``, direction ``dy`` in y) that lies in
    the slab between the planes y = a and y = b (the cut walks' planes A and B), from t = 0 and cut
    at ``t_limit``; empty (t_in > t_out) where it misses the slab. A ray parallel to the planes is in
    the slab for ever or never."""
    # (in place where a temporary is free: these run on every ray that reaches a cut walk)
    with np.errstate(divide="ignore", invalid="ignore"):
        ta, tb = np.subtract(a, oy), np.subtract(b, oy)
        ta /= dy
        tb /= dy
    t_in, t_out = np.fmin(ta, tb), np.fmax(ta, tb, out=tb)
    np.maximum(t_in, 0.0, out=t_in)
    parallel = np.nonzero(dy == 0)[0]
    if len(parallel):
        y = oy[parallel]
        in_slab = (y >= a[parallel]) & (y <= b[parallel])
        t_in[parallel] = np.where(in_slab, 0.0, np.inf)
        t_out[parallel] = np.where(in_slab, np.inf, -np.inf)
    np.minimum(t_out, t_limit, out=t_out)
    return t_in, t_out


def axis_cylinder_terms(o: np.ndarray, d: np.ndarray, radius: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The coefficients a, b, c of a t^2 + b t + c = 0 for the ray o + t d on the cylinder of
    ``radius`` about the lamp axis (x^2 + z^2 = r^2): d_x^2 + d_z^2, 2 (o_x d_x + o_z d_z) and
    o_x^2 + o_z^2 - r^2, computed in place (the socket and the side wall meet every ray)."""
    ox, oz, dx, dz = o[:, 0], o[:, 2], d[:, 0], d[:, 2]
    a = np.square(dx)
    a += np.square(dz)
    b, term = ox * dx, oz * dz
    b += term
    b *= 2.0
    c = np.square(ox)
    c += np.square(oz, out=term)
    c -= radius**2
    return a, b, c


def quadratic_roots(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The two roots q / a and c / q of ``solve_quadratic`` (unordered), for callers that only use
    rays with a != 0 (there ``solve_quadratic`` returns exactly their min and max)."""
    with np.errstate(invalid="ignore", divide="ignore"):
        # (the same operations in place: every ray that can reach the socket or the wall runs them)
        disc, four_ac = b * b, 4.0 * a
        four_ac *= c
        disc -= four_ac
        q = np.sqrt(disc, out=disc)  # NaN where no root is real (copysign then gives it b's sign, as for any NaN)
        np.copysign(q, b, out=q)
        q += b
        q *= -0.5
        return q / a, np.divide(c, q, out=four_ac)


def first_beyond(lo: np.ndarray, hi: np.ndarray, ok_lo: np.ndarray, ok_hi: np.ndarray) -> np.ndarray:
    """The nearer of two roots that lies beyond ``T_MIN`` and passes its test; ``inf`` if none."""
    lo_ok = (lo > T_MIN) & ok_lo
    hi_ok = (hi > T_MIN) & ok_hi
    return np.where(lo_ok, lo, np.where(hi_ok, hi, np.inf))

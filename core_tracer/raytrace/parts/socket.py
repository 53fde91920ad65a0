"""The socket (docs/model.md §3): a solid cylinder on the lamp axis from the reflector vertex to the
plane of the bulb centre, closed there by a flat disk; opaque, a ray ends there (⑫)."""

from __future__ import annotations

import numpy as np

from .. import paths as P
from ..lamp_table import LampTable
from .base import T_MIN, Segments, axis_cylinder_terms, quadratic_roots
from .bulb import without_bulbs

SURFACE = P.SOCKET
MEDIA = (P.IN_AIR,)


def hit_socket(o: np.ndarray, d: np.ndarray, radius: np.ndarray, y_start: np.ndarray,
               y_end: np.ndarray) -> np.ndarray:
    """A solid cylinder of ``radius`` about the axis from the plane of the bulb centre ``y_start``
    back to the reflector vertex ``y_end``, closed at ``y_start`` by a flat disk. Its far end lies
    behind the reflector, so it needs no cap."""
    a, b, c = axis_cylinder_terms(o, d, radius)
    r1, r2 = quadratic_roots(a, b, c)  # a <= 1e-15 (parallel to the axis) misses the side
    lo = np.fmin(r1, r2)
    y = o[:, 1] + lo * d[:, 1]
    with np.errstate(invalid="ignore"):
        side = np.where((a > 1e-15) & (lo > T_MIN) & (y >= y_start) & (y <= y_end), lo, np.inf)
    with np.errstate(divide="ignore", invalid="ignore"):  # rays parallel to the disk miss it (NaN, inf)
        t = (y_start - o[:, 1]) / d[:, 1]
        x, z = o[:, 0] + t * d[:, 0], o[:, 2] + t * d[:, 2]
    end = np.where((t > T_MIN) & (x * x + z * z <= radius**2), t, np.inf)
    return np.minimum(side, end)


def intersect(rays: Segments, lamps: LampTable, t_limit: np.ndarray) -> tuple[np.ndarray, None]:
    li = rays.lamp
    # (the lamps' values gathered with take: faster than indexing)
    t = hit_socket(rays.o, rays.d, lamps.socket_radius.take(li), lamps.bulb_center[:, 1].take(li),
                   lamps.vertex.take(li))
    return without_bulbs(t, lamps, li), None

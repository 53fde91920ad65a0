"""The lens side wall (MODEL.md §3): the cylinder r = R about the lamp axis between the outer
face and the cut apex plane, met from inside; opaque and not reflecting, a ray ends there (⑦)."""

from __future__ import annotations

import numpy as np

from .. import paths as P
from ..lamp_table import LampTable
from .base import T_MIN, Segments, quadratic_roots

SURFACE = P.WALL
MEDIA = (P.IN_LENS, P.IN_AIR)


def hit_side_wall(o: np.ndarray, d: np.ndarray, radius: np.ndarray) -> np.ndarray:
    """The cylinder r = R, left from inside (the far root)."""
    a = d[:, 0] ** 2 + d[:, 2] ** 2
    b = 2.0 * (o[:, 0] * d[:, 0] + o[:, 2] * d[:, 2])
    c = o[:, 0] ** 2 + o[:, 2] ** 2 - radius**2
    r1, r2 = quadratic_roots(a, b, c)  # a <= 1e-15 (parallel to the axis) misses the wall
    hi = np.fmax(r1, r2)
    return np.where((a > 1e-15) & (hi > T_MIN), hi, np.inf)


def intersect(rays: Segments, lamps: LampTable, t_limit: np.ndarray) -> tuple[np.ndarray, None]:
    return hit_side_wall(rays.o, rays.d, lamps.radius[rays.lamp]), None

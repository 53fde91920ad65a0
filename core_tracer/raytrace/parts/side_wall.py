"""The lens side wall (docs/model.md §3): the lens outline (``outline``) extruded along the lamp axis,
met from inside: for a round lens the cylinder r = R, for a rectangular one four planes and four
quarter cylinders. It stands from the outer face back to the reflector's edge (the prism holds the
trimmed paraboloid: a ray in the lamp meets the wall before any part of the paraboloid outside it);
opaque and not reflecting, a ray ends there (⑦)."""

from __future__ import annotations

import numpy as np

from ...scene import outline
from .. import paths as P
from ..lamp_table import LampTable
from .base import T_MIN, Segments, axis_cylinder_terms, quadratic_roots

SURFACE = P.WALL
MEDIA = (P.IN_LENS, P.IN_AIR)


def hit_side_wall(o: np.ndarray, d: np.ndarray, radius: np.ndarray) -> np.ndarray:
    """The cylinder r = R, left from inside (the far root)."""
    a, b, c = axis_cylinder_terms(o, d, radius)
    r1, r2 = quadratic_roots(a, b, c)  # a <= 1e-15 (parallel to the axis) misses the wall
    hi = np.fmax(r1, r2)
    return np.where((a > 1e-15) & (hi > T_MIN), hi, np.inf)


def hit_outline_wall(o: np.ndarray, d: np.ndarray, half_size: np.ndarray, corner: np.ndarray) -> np.ndarray:
    """The extruded rectangular outline, left from inside (``outline.wall_exit``)."""
    t = outline.wall_exit(o, d, half_size[:, 0], half_size[:, 1], corner)
    return np.where(t > T_MIN, t, np.inf)


def intersect(rays: Segments, lamps: LampTable, t_limit: np.ndarray) -> tuple[np.ndarray, None]:
    if not lamps.rectangular.any():  # round lenses only: no ray needs sorting
        return hit_side_wall(rays.o, rays.d, lamps.radius.take(rays.lamp)), None
    rect = lamps.rectangular[rays.lamp] > 0
    t = np.empty(len(rect))
    rnd = ~rect
    if rnd.any():
        t[rnd] = hit_side_wall(rays.o[rnd], rays.d[rnd], lamps.radius[rays.lamp[rnd]])
    li = rays.lamp[rect]
    t[rect] = hit_outline_wall(rays.o[rect], rays.d[rect], lamps.half_size[li], lamps.corner[li])
    return t, None

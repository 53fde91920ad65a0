"""The housing of a prism-plate lamp (docs/model.md, the prism plate): the cylinder r = R about the lamp
axis from the plate's front face back, closed by a flat disk at the housing's depth; opaque and
not reflecting, a ray ends there (⑲) with the housing's colour, as at the socket.

It stands before the lens side wall in ``PARTS``: both are the cylinder r = R, computed by the
same function, so the tie keeps the housing wherever it covers the wall (behind the plate's
front face). A lamp without a plate has its planes at +inf: no ray meets its housing."""

from __future__ import annotations

import numpy as np

from .. import paths as P
from ..lamp_table import LampTable
from .base import T_MIN, Segments
from .side_wall import hit_side_wall

SURFACE = P.HOUSING
MEDIA = (P.IN_AIR, P.IN_PLATE)


def hit_housing(o: np.ndarray, d: np.ndarray, radius: np.ndarray, y_front: np.ndarray,
                y_back: np.ndarray) -> np.ndarray:
    """The cylinder r = ``radius`` behind ``y_front``, left from inside, and the back disk at ``y_back``."""
    t_side = hit_side_wall(o, d, radius)
    with np.errstate(invalid="ignore"):
        side = np.where(o[:, 1] + t_side * d[:, 1] >= y_front, t_side, np.inf)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (y_back - o[:, 1]) / d[:, 1]
        x, z = o[:, 0] + t * d[:, 0], o[:, 2] + t * d[:, 2]
        back = np.where((d[:, 1] > 0) & (t > T_MIN) & (x * x + z * z <= radius**2), t, np.inf)
    return np.minimum(side, back)


def intersect(rays: Segments, lamps: LampTable, t_limit: np.ndarray) -> tuple[np.ndarray, None]:
    housed = np.isfinite(lamps.housing_back[rays.lamp]) & (rays.medium != P.IN_LENS)
    if housed.all():  # every lamp has a plate: no gather
        li = rays.lamp
        return hit_housing(rays.o, rays.d, lamps.radius[li], lamps.plate_front[li], lamps.housing_back[li]), None
    t = np.full(len(rays.o), np.inf)
    sel = np.nonzero(housed)[0]
    if len(sel):
        li = rays.lamp[sel]
        o, d = np.take(rays.o, sel, axis=0), np.take(rays.d, sel, axis=0)  # (take: 3x a fancy index of rows)
        t[sel] = hit_housing(o, d, lamps.radius[li], lamps.plate_front[li], lamps.housing_back[li])
    return t, None

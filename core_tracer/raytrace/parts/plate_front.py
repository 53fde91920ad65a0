"""The prism plate's flat front face (README, the prism plate): the disk r <= R in the plane
y = plate front, toward the lens; a Fresnel surface met from the air between lens and plate and
from inside the plate. A lamp without a plate has the plane at +inf: no ray meets it."""

from __future__ import annotations

import numpy as np

from .. import paths as P
from ..lamp_table import LampTable
from .base import T_MIN, Segments

SURFACE = P.PLATE_FRONT
MEDIA = (P.IN_AIR, P.IN_PLATE)
NORMAL = np.array([0.0, -1.0, 0.0])  # out of the plate material, toward the lens


def hit_plate_front(o: np.ndarray, d: np.ndarray, y_front: np.ndarray, radius: np.ndarray,
                    in_plate: np.ndarray) -> np.ndarray:
    """The plane y = ``y_front`` within ``radius``: from inside the plate (``in_plate``, heading
    -y) or from the air in front of it (heading +y). A ray never meets the plane it starts on
    again: its direction points away from it."""
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (y_front - o[:, 1]) / d[:, 1]
        x, z = o[:, 0] + t * d[:, 0], o[:, 2] + t * d[:, 2]
    toward = np.where(in_plate, d[:, 1] < 0, (d[:, 1] > 0) & (o[:, 1] <= y_front))
    return np.where(toward & (t > T_MIN) & (x * x + z * z <= radius**2), t, np.inf)


def intersect(rays: Segments, lamps: LampTable, t_limit: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    t = np.full(len(rays.o), np.inf)
    sel = np.nonzero(np.isfinite(lamps.plate_front[rays.lamp]) & (rays.medium != P.IN_LENS)
                     & (rays.src != P.PLATE_FRONT))[0]
    if len(sel):
        li = rays.lamp[sel]
        t[sel] = hit_plate_front(rays.o[sel], rays.d[sel], lamps.plate_front[li], lamps.radius[li],
                                 rays.medium[sel] == P.IN_PLATE)
    return t, np.broadcast_to(NORMAL, rays.o.shape)

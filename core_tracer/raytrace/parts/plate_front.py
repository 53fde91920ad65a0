"""The prism plate's flat front face (docs/model.md, the prism plate): the disk r <= R in the plane
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
    y_front = lamps.plate_front[rays.lamp]
    # Only rays heading for the plane can meet it: those are worth gathering (``hit_plate_front``'s
    # own test, done first on every ray; a lamp without a plate has its plane at +inf).
    dy, in_plate = rays.d[:, 1], rays.medium == P.IN_PLATE
    toward = np.where(in_plate, dy < 0, (dy > 0) & (rays.o[:, 1] <= y_front))
    sel = np.nonzero(toward & np.isfinite(y_front) & (rays.medium != P.IN_LENS) & (rays.src != P.PLATE_FRONT))[0]
    if len(sel):
        li = rays.lamp[sel]
        o, d = np.take(rays.o, sel, axis=0), np.take(rays.d, sel, axis=0)  # (take: 3x a fancy index of rows)
        t[sel] = hit_plate_front(o, d, y_front[sel], lamps.radius[li], in_plate[sel])
    return t, np.broadcast_to(NORMAL, rays.o.shape)

"""The lens's outer face (docs/model.md §3): the lens outline's inside in the plane y = 0, a Fresnel
surface reached from inside the lens (eye rays meet it from outside in ``lens_at``)."""

from __future__ import annotations

import numpy as np

from ...scene import outline
from .. import paths as P
from ..lamp_table import LampTable
from .base import T_MIN, Segments
from .cylinder_lens import hit_outer_cylinder

SURFACE = P.OUTER
MEDIA = (P.IN_LENS,)
NORMAL = np.array([0.0, -1.0, 0.0])  # out of the lens material, toward the viewer


def hit_outer_face(o: np.ndarray, d: np.ndarray) -> np.ndarray:
    """The plane y = 0, reached from inside the lens (d_y < 0)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        t = -o[:, 1] / d[:, 1]
    return np.where((d[:, 1] < 0) & (t > T_MIN), t, np.inf)


def intersect(rays: Segments, lamps: LampTable, t_limit: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    if not lamps.any_cylindrical:
        return hit_outer_face(rays.o, rays.d), np.broadcast_to(NORMAL, rays.o.shape)
    t, normal = hit_outer_face(rays.o, rays.d), np.tile(NORMAL, (len(rays.o), 1))
    curved = np.nonzero(lamps.cylindrical[rays.lamp] > 0)[0]
    li = rays.lamp[curved]
    t[curved], normal[curved] = hit_outer_cylinder(rays.o[curved], rays.d[curved], lamps.cyl_axis_x[li],
                                                   lamps.cyl_radius[li], rays.src[curved] == P.OUTER)
    return t, normal


def lens_at(x: np.ndarray, z: np.ndarray, lamps: LampTable) -> np.ndarray:
    """For world points (x, z) on the body's front plane, the lamp whose lens contains each
    point, or -1 (the lens outline, ``outline``: a circle of the lens radius about the lamp axis, or
    a rounded rectangle)."""
    lamp = np.full(len(x), -1)
    for li in range(len(lamps.radius)):
        dx = x - lamps.center[li, 0]
        dz = z - lamps.center[li, 1]
        if lamps.rectangular[li]:
            (hw, hh), r = lamps.half_size[li], lamps.corner[li]
            lamp[outline.signed_distance(dx, dz, hw - r, hh - r, r) <= 0.0] = li
        else:
            lamp[dx * dx + dz * dz <= lamps.radius[li] ** 2] = li
    return lamp

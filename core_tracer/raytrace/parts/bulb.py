"""The bulb (docs/model.md §3): a sphere of radius r_b about the focus plus the bulb offset, met from
the air; the light source, where a ray ends (⑪)."""

from __future__ import annotations

import numpy as np

from .. import optics
from .. import paths as P
from ..lamp_table import LampTable
from .base import T_MIN, Segments, rows

SURFACE = P.BULB
MEDIA = (P.IN_AIR,)


def hit_sphere(o: np.ndarray, d: np.ndarray, center: np.ndarray, radius: np.ndarray) -> np.ndarray:
    """A sphere reached from outside (the near root)."""
    oc = o - center
    b = optics.dot(oc, d)
    c = optics.dot(oc, oc) - radius**2
    with np.errstate(invalid="ignore"):
        t = -b - np.sqrt(b * b - c)
    return np.where(t > T_MIN, t, np.inf)


def intersect(rays: Segments, lamps: LampTable, t_limit: np.ndarray) -> tuple[np.ndarray, None]:
    t = hit_sphere(rays.o, rays.d, rows(lamps.bulb_center, rays.lamp), lamps.bulb_radius.take(rays.lamp))
    return without_bulbs(t, lamps, rays.lamp), None


def without_bulbs(t: np.ndarray, lamps: LampTable, lamp: np.ndarray) -> np.ndarray:
    """``t`` with ``inf`` for the rays of lamps lit by LEDs, which have no bulb or socket."""
    if lamps.has_bulb.all():
        return t
    return np.where(lamps.has_bulb.take(lamp) > 0.0, t, np.inf)

"""The light guide's LED (docs/photometric.md, light guides): a square Lambertian die facing the
guide's first end face across a small air gap (and one facing the last end face for a guide lit at
both ends); met from the lamp's air, the light source where a ray ends."""

from __future__ import annotations

import numpy as np

from .. import paths as P
from ..lamp_table import LampTable
from .base import T_MIN, Segments, rows
from .light_guide import to_guide

SURFACE = P.GUIDE_LED
MEDIA = (P.IN_AIR,)


def intersect(rays: Segments, lamps: LampTable, t_limit: np.ndarray) -> tuple[np.ndarray, None]:
    n = len(rays.o)
    t = np.full(n, np.inf)
    guide = lamps.guide
    if guide is None:
        return t, None
    sel = np.nonzero(guide.present.take(rays.lamp) > 0)[0]
    if len(sel):
        lamp = rays.lamp.take(sel)
        s0, u0, v0, ds, du, dv = to_guide(rows(rays.o, sel), rows(rays.d, sel), guide, lamp)
        half, gap = guide.led_half.take(lamp), guide.led_gap.take(lamp)
        best = np.full(len(sel), np.inf)
        with np.errstate(divide="ignore", invalid="ignore"):
            # the die before the first end (facing +s, met by rays heading −s), and the one past the last
            for plane, toward, used in ((-gap, ds < 0, True),
                                        (guide.length.take(lamp) + gap, ds > 0, guide.led_ends.take(lamp) > 1)):
                tp = (plane - s0) / ds
                on = (np.abs(u0 + tp * du) <= half) & (np.abs(v0 + tp * dv) <= half)
                ok = toward & used & on & (tp > T_MIN) & (tp < best)
                best = np.where(ok, tp, best)
        t[sel] = best
    return t, None

"""The lens's inner face whatever its cut type: each ray goes to the part of its lamp's cuts,
fish-eye (``cuts``), saw-tooth (``sawtooth``) or flutes (``flutes``). All are Table 1's cut face,
so the Fresnel tree and the path classes do not depend on the cut type. A scene with fish-eye
cuts only is handed to the fish-eye walk whole, exactly as before the cut types existed."""

from __future__ import annotations

import numpy as np

from ..lamp_table import LampTable
from . import cuts, flutes, sawtooth
from .base import Segments

SURFACE = cuts.SURFACE
MEDIA = cuts.MEDIA


def intersect(rays: Segments, lamps: LampTable, t_limit: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    if not (lamps.sawtooth.any() or lamps.flutes.any()):
        return cuts.intersect(rays, lamps, t_limit)
    saw, flute = lamps.sawtooth[rays.lamp] != 0, lamps.flutes[rays.lamp] != 0
    t = np.full(len(saw), np.inf)
    normal = np.zeros((len(saw), 3))
    for part, sel in ((cuts, ~saw & ~flute), (sawtooth, saw), (flutes, flute)):
        if sel.all():
            return part.intersect(rays, lamps, t_limit)
        idx = np.nonzero(sel)[0]
        if len(idx):
            sub = Segments(rays.o[idx], rays.d[idx], rays.lamp[idx], rays.src[idx], rays.medium[idx])
            t[idx], normal[idx] = part.intersect(sub, lamps, t_limit[idx])
    return t, normal

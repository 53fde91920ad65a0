"""The lens's inner face whatever its cut type: each ray goes to the part of its lamp's cuts,
fish-eye (``cuts``, on a flat or a cylindrical lens), saw-tooth (``sawtooth``) or flutes
(``flutes``). All are Table 1's cut face, so the Fresnel tree and the path classes do not depend
on the cut type. A scene with fish-eye cuts on flat lenses only is handed to the fish-eye walk
whole, exactly as before the cut types existed."""

from __future__ import annotations

import numpy as np

from .. import paths as P
from ..lamp_table import CYLINDER_KEYS, LampTable
from . import cuts, flutes, sawtooth
from .base import Segments, put_rows, rows
from .cylinder_lens import hit_cylinder_cuts

SURFACE = cuts.SURFACE
MEDIA = cuts.MEDIA

# The walks, by the number ``_kinds`` gives a lamp.
FISHEYE, CYLINDER, SAWTOOTH, FLUTES = 0, 1, 2, 3


def intersect(rays: Segments, lamps: LampTable, t_limit: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    if not (lamps.sawtooth.any() or lamps.flutes.any() or lamps.any_cylindrical):
        return cuts.intersect(rays, lamps, t_limit)
    kinds = _kinds(lamps)
    present = [k for k in (FISHEYE, CYLINDER, SAWTOOTH, FLUTES) if (kinds == k).any()]
    if len(present) == 1:
        return _walk(present[0], rays, lamps, t_limit)
    kind = kinds[rays.lamp]
    t = np.full(len(kind), np.inf)
    normal = np.zeros((len(kind), 3))
    for k in present:
        idx = np.nonzero(kind == k)[0]
        if len(idx) == len(kind):
            return _walk(k, rays, lamps, t_limit)
        if len(idx):  # the rows gathered with take and scattered column by column (``base.rows``)
            sub = Segments(rows(rays.o, idx), rows(rays.d, idx), rays.lamp[idx], rays.src[idx], rays.medium[idx])
            t[idx], n = _walk(k, sub, lamps, t_limit[idx])
            put_rows(normal, idx, n)
    return t, normal


def _kinds(lamps: LampTable) -> np.ndarray:
    """Per lamp, which walk finds its cuts (``FISHEYE`` …)."""
    kinds = np.where(lamps.cylindrical > 0, CYLINDER, FISHEYE)
    kinds[lamps.sawtooth != 0] = SAWTOOTH
    kinds[lamps.flutes != 0] = FLUTES
    return kinds


def _walk(kind: int, rays: Segments, lamps: LampTable, t_limit: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The hits of ``rays``, all of whose lamps' cuts are of one ``kind``."""
    if kind == SAWTOOTH:
        return sawtooth.intersect(rays, lamps, t_limit)
    if kind == FLUTES:
        return flutes.intersect(rays, lamps, t_limit)
    if kind == FISHEYE:
        return cuts.intersect(rays, lamps, t_limit)
    li = rays.lamp
    # A ray that starts on a cut knows it: its own cap is excluded by geometry (``cuts.hit_cuts``).
    on_cap = np.where(rays.src != P.CUT, cuts.OFF_CAP,
                      np.where(rays.medium == P.IN_AIR, cuts.INTO_AIR, cuts.INTO_LENS)).astype(np.int8)
    # (``LampTable.cylinder_of``, its rows gathered with take: faster than indexing)
    geo = {k: getattr(lamps, "cyl_" + k).take(li) for k in CYLINDER_KEYS}
    return hit_cylinder_cuts(rays.o, rays.d, geo, lamps.pitch.take(li), lamps.cut_radius.take(li), t_limit, on_cap)

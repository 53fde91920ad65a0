"""The LED dies (docs/photometric.md, "LED sources"): flat rectangles in one plane per lamp, on a grid
(``scene.led_array``); opaque, a light source where a ray ends (⑪, as the bulb). A ray meets the
array's plane once and the die whose cell holds that point is the only one to test: the cost does
not grow with the number of dies (as the paper's cut walk, §3.2.4)."""

from __future__ import annotations

import numpy as np

from .. import optics
from .. import paths as P
from ..lamp_table import LampTable
from .base import T_MIN, Segments, put_rows, rows

SURFACE = P.LED
MEDIA = (P.IN_AIR,)


def _on_a_die(offset: np.ndarray, half: np.ndarray, pitch: np.ndarray, count: np.ndarray) -> np.ndarray:
    """Whether points at ``offset`` from the array's centre along one of its axes fall on a die of the
    row: the nearest die centre (i − (count − 1)/2) pitch, i clipped to the row, within ``half``."""
    first = (count - 1.0) / 2.0
    with np.errstate(divide="ignore", invalid="ignore"):  # a single die's pitch may be 0: its one cell
        cell = np.where(count > 1.0, offset / pitch, 0.0)
    i = np.clip(np.rint(cell + first), 0.0, np.maximum(count - 1.0, 0.0))
    return np.abs(offset - (i - first) * pitch) <= half


def _hit_array(o: np.ndarray, d: np.ndarray, lamps: LampTable, lamp: np.ndarray) -> np.ndarray:
    """The parameter of each ray's hit on its lamp's (first) array of dies, ``inf`` for none."""
    center, normal = rows(lamps.led_center, lamp), rows(lamps.led_normal, lamp)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = optics.dot(center - o, normal) / optics.dot(d, normal)
    gap = o + optics.scaled(d, np.where(np.isfinite(t), t, 0.0)) - center
    half, pitch = rows(lamps.led_half, lamp), rows(lamps.led_pitch, lamp)
    on = (_on_a_die(optics.dot(gap, rows(lamps.led_across, lamp)), half[:, 0], pitch[:, 0],
                    lamps.led_columns.take(lamp))
          & _on_a_die(optics.dot(gap, rows(lamps.led_up, lamp)), half[:, 1], pitch[:, 1], lamps.led_rows.take(lamp)))
    with np.errstate(invalid="ignore"):
        return np.where(on & (t > T_MIN) & (lamps.led_columns.take(lamp) > 0), t, np.inf)


def _mirrored(lamps: LampTable, lamp: np.ndarray) -> np.ndarray:
    """The rows whose lamp's guide is lit at both ends: their LED array has a mirror image."""
    if lamps.guide is None or not lamps.guide.both_ends.any():
        return np.zeros(0, dtype=np.intp)
    return np.nonzero(lamps.guide.both_ends.take(lamp) > 0)[0]


def hit_dies(o: np.ndarray, d: np.ndarray, lamps: LampTable, lamp: np.ndarray) -> np.ndarray:
    """The parameter of each ray's hit on its lamp's dies (either side), ``inf`` for none. A guide lit
    at both ends (``GuideTable.both_ends``) adds the array's mirror image: the ray reflected through
    the guide's middle meets the first array where the ray meets the image, at the same t."""
    t = _hit_array(o, d, lamps, lamp)
    sel = _mirrored(lamps, lamp)
    if len(sel):
        o_m, d_m = lamps.guide.mirror(rows(o, sel), rows(d, sel), lamp.take(sel))
        t[sel] = np.minimum(t.take(sel), _hit_array(o_m, d_m, lamps, lamp.take(sel)))
    return t


def intersect(rays: Segments, lamps: LampTable, t_limit: np.ndarray) -> tuple[np.ndarray, None]:
    return hit_dies(rays.o, rays.d, lamps, rays.lamp), None


def emitted(lamps: LampTable, lamp: np.ndarray, d: np.ndarray, at: np.ndarray | None = None) -> np.ndarray:
    """(N, channels) the luminance of the dies of ``lamp`` seen along ``d`` (the eye ray's direction,
    so the light's is −d): the head-on luminance times the pattern's f(θ, φ), θ from the die's
    normal and φ from its across axis toward its up axis; 0 seen from behind (the die is opaque).
    ``at``: the points on the dies, needed where a guide lit at both ends has the array's mirror
    image (a point on the other side of the guide's middle from the array is on the image, whose
    luminance along d is the array's along d mirrored)."""
    toward = -d
    sel = _mirrored(lamps, lamp) if at is not None else ()
    if len(sel):
        guide, index = lamps.guide, lamp.take(sel)
        axis, centre, middle = rows(guide.axis, index), rows(lamps.led_center, index), rows(guide.middle, index)
        image = optics.dot(rows(at, sel) - middle, axis) * optics.dot(centre - middle, axis) < 0.0
        flip = sel[image]
        if len(flip):
            toward = toward.copy()
            put_rows(toward, flip, guide.mirror(rows(at, flip), rows(toward, flip), lamp.take(flip))[1])
    cos_theta = optics.dot(toward, rows(lamps.led_normal, lamp))
    out = rows(lamps.led_radiance, lamp)
    if not lamps.led_patterns:
        return out * (cos_theta > 0.0)[:, None]
    factor = np.zeros(len(lamp))
    for index in np.unique(lamp):
        sel = np.nonzero(lamp == index)[0]
        phi = np.degrees(np.arctan2(optics.dot(toward[sel], rows(lamps.led_up, lamp[sel])),
                                    optics.dot(toward[sel], rows(lamps.led_across, lamp[sel]))))
        factor[sel] = lamps.led_patterns[index].factor(cos_theta[sel], phi)
    return out * factor[:, None]

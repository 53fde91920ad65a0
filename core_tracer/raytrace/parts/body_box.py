"""The body (MODEL.md §3): an axis-aligned box, its front face in y = 0, in the world frame.
Only eye rays meet it: it decides background, body or lens (paper §3.1)."""

from __future__ import annotations

import numpy as np


def body_box(body: dict) -> tuple[np.ndarray, np.ndarray]:
    """The body's box (MODEL.md §3): its lowest and highest corners; the front face lies in y = 0
    and the depth runs into +y."""
    (cx, cz), (sx, sz) = body["center"], body["size"]
    return np.array([cx - sx / 2, 0.0, cz - sz / 2]), np.array([cx + sx / 2, body["depth"], cz + sz / 2])


def hit_box(o: np.ndarray, d: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rays against the axis-aligned box [lo, hi] (the slab test): per ray, the entry distance, the
    exit distance and the axis (0, 1, 2) of the entry face. A ray from outside hits the box where
    ``t_near <= t_far`` and ``t_near > 0``."""
    with np.errstate(divide="ignore", invalid="ignore"):
        t1 = (lo - o) / d
        t2 = (hi - o) / d
    # A ray parallel to a slab is inside it (−inf, inf) or outside it (inf, −inf).
    inside = (o >= lo) & (o <= hi)
    t_lo = np.where(d == 0, np.where(inside, -np.inf, np.inf), np.fmin(t1, t2))
    t_hi = np.where(d == 0, np.where(inside, np.inf, -np.inf), np.fmax(t1, t2))
    return np.max(t_lo, axis=1), np.min(t_hi, axis=1), np.argmax(t_lo, axis=1)

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
    # Axis by axis on the columns (the same values as on the (N, 3) arrays, without numpy's slow
    # reductions over a 3-wide axis).
    t_lo, t_hi = [], []
    for axis in range(3):
        oa, da = o[:, axis], d[:, axis]
        with np.errstate(divide="ignore", invalid="ignore"):
            t1 = (lo[axis] - oa) / da
            t2 = (hi[axis] - oa) / da
        # A ray parallel to a slab is inside it (−inf, inf) or outside it (inf, −inf).
        parallel = da == 0
        if parallel.any():
            inside = (oa >= lo[axis]) & (oa <= hi[axis])
            t_lo.append(np.where(parallel, np.where(inside, -np.inf, np.inf), np.fmin(t1, t2)))
            t_hi.append(np.where(parallel, np.where(inside, np.inf, -np.inf), np.fmax(t1, t2)))
        else:
            t_lo.append(np.fmin(t1, t2))
            t_hi.append(np.fmax(t1, t2))
    t_near = np.maximum(np.maximum(t_lo[0], t_lo[1]), t_lo[2])
    t_far = np.minimum(np.minimum(t_hi[0], t_hi[1]), t_hi[2])
    # argmax's choice: the first axis whose entry is the latest
    face = np.where((t_lo[0] >= t_lo[1]) & (t_lo[0] >= t_lo[2]), 0, np.where(t_lo[1] >= t_lo[2], 1, 2))
    return t_near, t_far, face

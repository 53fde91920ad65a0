"""Overlapping lens volumes: a point inside two lenses has no single medium, so a design with
lenses that interpenetrate is refused (touching lenses are fine)."""

from __future__ import annotations

import numpy as np

from ..scene.reading import SceneError
from ..scene.safe_text import printable
from .embree import EmbreeScene
from .geometry import Geometry

SAMPLES_PER_LENS = 512  # triangle centres tested per lens: a real overlap covers many of them
MAX_CROSSINGS = 4096  # safety net on the walk along a test ray
# A fixed, irrational-looking direction: a test ray along an axis could run along a mesh's edges.
_DIRECTION = np.array([0.5773, 0.6172, 0.5345]) / np.linalg.norm([0.5773, 0.6172, 0.5345])


def winding(points: np.ndarray, geometry: Geometry, embree: EmbreeScene, part: int) -> np.ndarray:
    """How many times each point is inside the closed outward mesh of ``part`` (0 outside, 1 inside):
    the signed count of its surface crossings along a ray from the point."""
    n = len(points)
    count = np.zeros(n, np.int64)
    o = points.copy()
    d = np.broadcast_to(_DIRECTION, (n, 3)).copy()
    live = np.arange(n)
    step = geometry.epsilon
    for _ in range(MAX_CROSSINGS):
        if len(live) == 0:
            break
        t, tri, _ = embree.nearest(o[live], d[live])
        hit = tri >= 0
        live, t, tri = live[hit], t[hit], tri[hit]
        mine = geometry.part[tri] == part
        sign = np.sign(geometry.normal[tri] @ _DIRECTION).astype(np.int64)
        np.add.at(count, live[mine], sign[mine])
        o[live] = o[live] + (t + step)[:, None] * d[live]
    return count


def check_lens_overlap(scene: dict, geometry: Geometry, embree: EmbreeScene) -> None:
    """Refuse two lens meshes whose volumes overlap, naming both."""
    parts = scene["freeform"]["parts"]
    lenses = [i for i, p in enumerate(parts) if p["role"] == "lens"]
    if len(lenses) < 2:
        return
    boxes = {}
    for i in lenses:
        v = geometry.corners(geometry.part == i).reshape(-1, 3)
        boxes[i] = (v.min(axis=0), v.max(axis=0))
    rng = np.random.default_rng(0)
    for i in lenses:
        tris = np.nonzero(geometry.part == i)[0]
        pick = tris if len(tris) <= SAMPLES_PER_LENS else rng.choice(tris, SAMPLES_PER_LENS, replace=False)
        # Triangle centres moved just inside lens i: inside another lens only if the volumes overlap.
        points = geometry.corners(pick).mean(axis=1) - 4 * geometry.epsilon * geometry.normal[pick]
        for j in lenses:
            if j == i:
                continue
            lo, hi = boxes[j]
            near = np.all((points >= lo) & (points <= hi), axis=1)
            if not near.any():
                continue
            if (winding(points[near], geometry, embree, j) > 0).any():
                a, b = parts[min(i, j)]["object"], parts[max(i, j)]["object"]
                raise SceneError(f'lens "{printable(a, 40)}"',
                                 f'overlaps lens "{printable(b, 40)}"; allowed lens volumes that do not '
                                 "overlap (move them apart, or join them into one mesh)")

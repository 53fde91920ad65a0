"""One trial as a Dask task: the design rendered with its passes kept, returned as the image and
the mask of the pixels that see a lamp (what ``measures`` need), or found in the cell cache."""

from __future__ import annotations

import numpy as np

from ..cluster.cache import CellCache
from ..cluster.cells import Cell, stop_flag, worker_scene

# The passes of light that come from the lamp; a pixel that gets any of them sees the lamp.
LAMP_PASSES = ("lens_surface", "bulb", "reflector_constant", "reflector_scatter", "socket", "side_wall")
MASK_SUFFIX = "-lamp"


def render_trial(cell: Cell, environment: bytes | None = None, stop: str | None = None,
                 threads: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """The task: (the linear image with glare as a study shows it, the lamp mask (H, W) bool)."""
    from ..images import glare
    from ..raytrace.engine import render_passes

    scene = worker_scene(cell, environment)
    result = render_passes(scene, cell.width, cell.height, should_stop=stop_flag(stop), threads=threads,
                           keep_passes=True)
    mask = np.zeros((cell.height, cell.width), dtype=bool)
    for name in LAMP_PASSES:
        mask |= (result.passes[name] != 0).any(axis=-1)
    return glare.apply(result.image, scene), mask


def cached(cache: CellCache | None, key: str) -> tuple[np.ndarray, np.ndarray] | None:
    if cache is None:
        return None
    image, mask = cache.get(key), cache.get_array(key + MASK_SUFFIX)
    if image is None or mask is None or mask.shape != image.shape[:2] or mask.dtype != bool:
        return None
    return image, mask


def keep(cache: CellCache | None, key: str, image: np.ndarray, mask: np.ndarray) -> None:
    if cache is not None:
        cache.put_array(key + MASK_SUFFIX, mask)
        cache.put(key, image)

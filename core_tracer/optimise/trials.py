"""One trial as a Dask task: the design rendered with its passes kept, returned as the image and
the mask of the pixels that see a lamp (what the image's measures need), and the photometric work
its photometric measures need (``photometric.figures``); or all of it found in the cell cache."""

from __future__ import annotations

import hashlib

import numpy as np

from ..cluster.cache import CellCache
from ..cluster.cells import Cell, stop_flag, worker_scene
from . import photometric as P

# The passes of light that come from the lamp; a pixel that gets any of them sees the lamp.
LAMP_PASSES = ("lens_surface", "bulb", "reflector_constant", "reflector_scatter", "socket", "side_wall")
MASK_SUFFIX = "-lamp"


def render_trial(cell: Cell, environment: bytes | None = None, stop: str | None = None,
                 threads: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """The camera's view: (the linear image with glare as a study shows it, the lamp mask (H, W) bool)."""
    from ..freeform.traced import render_scene
    from ..images import glare

    scene = worker_scene(cell, environment)
    result = render_scene(scene, cell.width, cell.height, should_stop=stop_flag(stop), threads=threads,
                           keep_passes=True)
    mask = np.zeros((cell.height, cell.width), dtype=bool)
    for name in LAMP_PASSES:
        mask |= (result.passes[name] != 0).any(axis=-1)
    return glare.apply(result.image, scene), mask


def run_trial(cell: Cell, environment: bytes | None, stop: str | None, camera: bool,
              request: P.Request) -> tuple[np.ndarray | None, np.ndarray | None, P.Figures | None]:
    """The task: the camera's view if ``camera``, and the photometric ``request``'s figures if any
    (the measurement sees no environment: only the lamps' own light)."""
    image, mask = render_trial(cell, environment, stop) if camera else (None, None)
    return image, mask, (P.figures(cell.scene, request) if request else None)


def figures_key(key: str, request: P.Request) -> str:
    return hashlib.sha256(f"{key}|{request!r}".encode()).hexdigest()


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


def cached_figures(cache: CellCache | None, key: str, scene: dict, request: P.Request) -> P.Figures | None:
    """A trial's figures from the cache (kept as arrays, ``keep_figures``), or None."""
    if cache is None:
        return None
    fkey = figures_key(key, request)
    lamps = P.lit_lamps(scene)
    out = P.Figures()
    if request.front_pixel_mm is not None:
        lum, owner = cache.get_array(fkey + "-front"), cache.get_array(fkey + "-owner")
        if lum is None or owner is None or lum.shape != owner.shape:
            return None
        out.front_luminance, out.front_owner, out.front_pixel_mm = lum, owner, request.front_pixel_mm
    if request.flux and lamps:
        flux = cache.get_array(fkey + "-flux")
        if flux is None or flux.shape != (len(lamps), 2):
            return None
        out.flux = {i: (float(flux[k, 0]), float(flux[k, 1])) for k, i in enumerate(lamps)}
    if request.grid_directions and lamps:
        grid = cache.get_array(fkey + "-grid")
        if grid is None or grid.shape != (len(lamps), len(request.grid_directions), 2):
            return None
        out.grid = {i: {d: (float(grid[k, j, 0]), float(grid[k, j, 1]))
                        for j, d in enumerate(request.grid_directions)} for k, i in enumerate(lamps)}
    if request.axis and lamps:
        axis = cache.get_array(fkey + "-axis")
        if axis is None or axis.shape != (len(lamps), 5):
            return None
        out.axis = {i: (float(axis[k, 0]), float(axis[k, 1]), axis[k, 2:].copy()) for k, i in enumerate(lamps)}
    return out


def keep_figures(cache: CellCache | None, key: str, scene: dict, request: P.Request, figures: P.Figures) -> None:
    if cache is None:
        return
    fkey = figures_key(key, request)
    lamps = P.lit_lamps(scene)
    if figures.flux:
        cache.put_array(fkey + "-flux", np.array([figures.flux[i] for i in lamps], dtype=np.float64))
    if figures.grid:
        cache.put_array(fkey + "-grid", np.array([[figures.grid[i][d] for d in request.grid_directions]
                                                  for i in lamps], dtype=np.float64))
    if figures.axis:
        cache.put_array(fkey + "-axis", np.array([[figures.axis[i][0], figures.axis[i][1], *figures.axis[i][2]]
                                                  for i in lamps], dtype=np.float64))
    if figures.front_luminance is not None:  # last: its presence says the rest is there
        cache.put_array(fkey + "-owner", figures.front_owner)
        cache.put_array(fkey + "-front", figures.front_luminance)

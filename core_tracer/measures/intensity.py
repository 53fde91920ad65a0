"""Luminous intensity of a design in a direction, from orthographic renders in the photometric mode.

In the far field a lamp seen along −d is a patch of luminance L (cd/m²) on the plane across d;
its luminous intensity toward d is the luminance integrated over that projected area,

    I(d) = ∫ L dA⊥   (cd = cd/m² · m²),

which an orthographic view from d gives pixel by pixel: I ≈ Σ L_pixel · p², p the pixel's side in
metres (the project's lengths are mm: p_mm · 1e-3). Only the lamps' own light counts: the copy of
the scene measured has no sun, no surroundings and no phantom light, so the body and the lenses'
outer reflections are black and the sum holds the light that leaves through the lenses.

The estimate and its error. One render samples the luminance at the centres of a grid of pixels;
the same grid moved by a uniformly random fraction of a pixel (a randomly shifted lattice) makes
Σ L p² an unbiased estimate of the integral (each point of the plane is sampled with the same
probability), and ``replicates`` renders with independent shifts give the mean and its standard
error, std / √M (Owen, "Monte Carlo theory, methods and examples", 2013, §17.2, randomised
lattice rules). The error is what the grid misses at the lens edges and the cut pattern's fine
structure.
"""

from __future__ import annotations

import concurrent.futures
import copy
import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..raytrace.engine import render_passes
from ..raytrace.lamp_table import LampTable
from ..raytrace.parts import body_box, outer_face
from ..scene.reading import SceneError
from .directions import direction

if TYPE_CHECKING:
    from ..freeform.design import DesignMeshes

DEFAULT_PIXEL_MM = 1.0
DEFAULT_REPLICATES = 4
WINDOW_MARGIN_MM = 5.0  # the view's window reaches this far beyond the body's box


@dataclass(frozen=True)
class Intensity:
    """A measured luminous intensity: ``cd`` and its standard error, and the light's tristimulus
    intensity ``xyz`` (X, Y, Z in cd: Y is ``cd``), from which its colour follows."""

    cd: float
    stderr: float
    xyz: np.ndarray

    def as_dict(self) -> dict:
        return {"cd": self.cd, "stderr_cd": self.stderr, "xyz_cd": [float(v) for v in self.xyz]}


def measurement_scene(scene: dict, lit: Iterable[int] | None = None) -> dict:
    """A copy of a normalised photometric scene with only the lamps' own light: no sun, no
    surroundings, no phantom light; the bulbs of lamps not in ``lit`` (None: all) switched off."""
    if scene.get("light_model", "paper") != "photometric":
        raise SceneError("light_model", f'"{scene.get("light_model", "paper")}" has no light in cd; allowed '
                                        '"photometric" for measures')
    out = copy.deepcopy(scene)
    out["light"]["illuminance_lux"] = 0.0
    out["light"]["phantom"] = False
    out["environment"]["world"] = "none"
    if lit is not None:
        keep = set(lit)
        for i, lamp in enumerate(out["lamps"]):
            if i not in keep:
                lamp["bulb"]["on"] = False
    return out


@dataclass(frozen=True)
class View:
    """An orthographic view of a design along −d: the camera section, the image size and its pixel."""

    camera: dict
    width: int
    height: int
    pixel_mm: float
    right: np.ndarray
    up: np.ndarray


def view_along(scene: dict, d: np.ndarray, pixel_mm: float, offset: tuple[float, float] = (0.0, 0.0)) -> View:
    """The orthographic view that sees the whole body from far along ``d`` (the light's direction),
    pixels of ``pixel_mm``, the grid moved by ``offset`` pixels (right, up)."""
    if not (math.isfinite(pixel_mm) and pixel_mm > 0):
        raise ValueError(f"pixel size: {pixel_mm!r} mm is not above 0")
    forward = -np.asarray(d, dtype=np.float64)
    up_hint = np.array([0.0, 0.0, 1.0]) if abs(forward[2]) < 0.99 else np.array([0.0, 1.0, 0.0])
    right = np.cross(forward, up_hint)
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)  # as ``camera.make_camera`` builds them
    lo, hi = body_box.body_box(scene["body"])
    lo, hi = lo - WINDOW_MARGIN_MM, hi + WINDOW_MARGIN_MM
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    u, v = corners @ right, corners @ up
    width = max(1, math.ceil((u.max() - u.min()) / pixel_mm) + 2)
    height = max(1, math.ceil((v.max() - v.min()) / pixel_mm) + 2)
    centre = (right * (u.max() + u.min()) / 2 + up * (v.max() + v.min()) / 2
              + (corners @ forward).mean() * forward)
    centre = centre + (offset[0] * right + offset[1] * up) * pixel_mm
    reach = float(np.linalg.norm(hi - lo)) + 100.0
    camera = {"type": "orthographic", "position": (centre - forward * reach).tolist(), "target": centre.tolist(),
              "up": up.tolist(), "width": width * pixel_mm, "sensor_fit": "horizontal", "shift": [0.0, 0.0],
              "fov_deg": 30.0, "exposure": "auto"}
    return View(camera, width, height, pixel_mm, right, up)


def render_view(measured: dict, view: View, bands: int | None = None, threads: int | None = None,
                meshes: DesignMeshes | None = None) -> np.ndarray:
    """The XYZ image (H, W, 3), Y in cd/m², of a measurement scene seen in ``view``; a free-form
    design's on its ``meshes`` (the same engine, its surfaces found on the meshes)."""
    scene = dict(measured)
    scene["camera"] = {**measured["camera"], **view.camera}
    if "freeform" in scene:
        if meshes is None:
            raise SceneError("freeform", "the design's meshes were not given; allowed a free-form design loaded "
                                         "with its .glb")
        result = meshes.render_passes(scene, view.width, view.height, samples=1, world_seen=False, threads=threads,
                                      bands=bands)
    else:
        result = render_passes(scene, view.width, view.height, samples=1, world_seen=False, keep_passes=False,
                               threads=threads, bands=bands)
    return result.image.astype(np.float64)


def lamp_of_pixels(scene: dict, view: View) -> np.ndarray:
    """(H, W) the lamp whose lens each pixel's ray crosses in the front plane y = 0 (-1: none).
    Exact for flat lenses: a lamp's light leaves through its own outer face, in that plane. A
    free-form design is one lamp, lamp 0 (``design_groups``): every pixel is its."""
    if "freeform" in scene:
        return np.zeros((view.height, view.width), np.int64)
    cam = view.camera
    centre = np.asarray(cam["target"], dtype=np.float64)
    forward = centre - np.asarray(cam["position"], dtype=np.float64)
    forward /= np.linalg.norm(forward)
    cols = (np.arange(view.width) + 0.5 - view.width / 2) * view.pixel_mm
    rows = (view.height / 2 - np.arange(view.height) - 0.5) * view.pixel_mm
    points = centre + cols[None, :, None] * view.right + rows[:, None, None] * view.up  # (H, W, 3)
    t = -points[..., 1] / forward[1] if abs(forward[1]) > 1e-12 else np.full(points.shape[:2], np.nan)
    at = points + t[..., None] * forward
    table = LampTable.from_scene(scene)
    return outer_face.lens_at(at[..., 0].ravel(), at[..., 2].ravel(), table).reshape(view.height, view.width)


def splits_by_lens(scene: dict) -> bool:
    """Whether one render can be split into the lamps' intensities by their lenses (flat lenses;
    a free-form design is measured whole, ``lamp_of_pixels``)."""
    return "freeform" in scene or not LampTable.from_scene(scene).any_cylindrical


def _estimate(samples: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mean and standard error of the mean over the first axis."""
    m = len(samples)
    mean = samples.mean(axis=0)
    if m < 2:
        return mean, np.full_like(mean, np.nan)
    return mean, samples.std(axis=0, ddof=1) / math.sqrt(m)


def rendered_intensities(scene: dict, h_deg: float, v_deg: float, groups: Sequence[Sequence[int]] | None = None, *,
                         pixel_mm: float = DEFAULT_PIXEL_MM, replicates: int = DEFAULT_REPLICATES, seed: int = 0,
                         bands: int | None = None, threads: int | None = None,
                         meshes: DesignMeshes | None = None) -> list[Intensity]:
    """I(H, V) of each group of lamps (None: one group, the whole design), with the bulbs that are on
    in the scene. Flat lenses: each replicate is one render, split by lens (``lamp_of_pixels``);
    otherwise one render per group. A free-form design (its ``meshes``) is one group, measured whole."""
    if replicates < 1:
        raise ValueError(f"replicates: {replicates!r} is not 1 or more")
    groups = [list(range(len(scene["lamps"])))] if groups is None else [list(g) for g in groups]
    d = direction(h_deg, v_deg)
    rng = np.random.default_rng(seed)
    area_m2 = (pixel_mm * 1e-3) ** 2
    per_replicate = np.zeros((replicates, len(groups), 3))
    split = splits_by_lens(scene)
    measured = measurement_scene(scene) if split else None
    for r in range(replicates):
        offset = tuple(rng.uniform(-0.5, 0.5, 2))
        view = view_along(scene, d, pixel_mm, offset)
        if split:
            image = render_view(measured, view, bands, threads, meshes)
            owner = lamp_of_pixels(scene, view)
            for g, group in enumerate(groups):
                per_replicate[r, g] = image[np.isin(owner, group)].sum(axis=0) * area_m2
        else:
            for g, group in enumerate(groups):
                image = render_view(measurement_scene(scene, group), view, bands, threads, meshes)
                per_replicate[r, g] = image.reshape(-1, 3).sum(axis=0) * area_m2
    mean, err = _estimate(per_replicate)
    return [Intensity(float(mean[g, 1]), float(err[g, 1]), mean[g]) for g in range(len(groups))]


# Directions measured in worker processes at once: each direction's renders are one task on the
# local worker pool (``cluster.local_pool``: forked, so no start-up), since a measuring view is one
# or two bands of rows, too few for the band pool, which shares one render's bands among its workers.
MIN_POOLED_DIRECTIONS = 4


def intensities_at(scene: dict, directions: Sequence[tuple[float, float]],
                   groups: Sequence[Sequence[int]] | None = None, **options) -> list[list[Intensity]]:
    """``rendered_intensities`` at each (H, V) of ``directions`` (``measured_together`` without tasks)."""
    return measured_together(scene, directions, groups, **options)[0]


def measured_together(scene: dict, directions: Sequence[tuple[float, float]],
                      groups: Sequence[Sequence[int]] | None = None, *, tasks: Sequence[tuple[Callable, tuple]] = (),
                      task_bytes: int = 0, seeds: Sequence[int] | None = None, workers: int | None = None,
                      progress: Callable[[int, int], None] | None = None,
                      **options) -> tuple[list[list[Intensity]], list]:
    """``rendered_intensities`` at each (H, V) of ``directions`` (seed ``seeds[k]``, default 0), the
    same values bit for bit, with the directions shared among ``workers`` processes (None: one per
    core, as many as the memory budget holds, ``pool_workers``; 1: this process alone), and the
    results of ``tasks`` ((function, arguments) pairs: a light tracing, a front view), submitted to the
    same pool before the directions so that they run beside them rather than after them, on one
    thread; the worker running the largest takes ``task_bytes`` (``pool_workers`` counts it).
    ``progress(done, total)`` as directions finish."""
    seeds = [0] * len(directions) if seeds is None else list(seeds)
    if workers is None:
        count = pool_workers(scene, len(directions), options.get("pixel_mm", DEFAULT_PIXEL_MM), task_bytes)
    else:
        count = max(1, min(workers, len(directions)))
    if options.get("meshes") is not None:  # a free-form design's Embree scenes stay in this process
        count = 1
    out: list[list[Intensity] | None] = [None] * len(directions)
    if count < 2:
        done = [function(*arguments) for function, arguments in tasks]
        for k, (h, v) in enumerate(directions):
            out[k] = rendered_intensities(scene, h, v, groups, seed=seeds[k], **options)
            if progress is not None:
                progress(k + 1, len(directions))
        return out, done  # type: ignore[return-value]
    from ..cluster.local_pool import LocalPool

    with LocalPool(count) as pool:
        others = [pool.submit(function, *arguments).future for function, arguments in tasks]
        futures = {pool.submit(_direction_task, scene, h, v, groups, seeds[k], options).future: k
                   for k, (h, v) in enumerate(directions)}
        try:
            for done, future in enumerate(concurrent.futures.as_completed(futures), 1):
                out[futures[future]] = future.result()
                if progress is not None:
                    progress(done, len(directions))
            results = [f.result() for f in others]
        except BaseException:
            pool.cancel([])
            raise
    return out, results  # type: ignore[return-value]


def _direction_task(scene: dict, h_deg: float, v_deg: float, groups, seed: int, options: dict) -> list[Intensity]:
    """One direction in a pool worker: its renders on the worker's one thread (the workers are the
    parallelism); the values do not depend on the thread count."""
    return rendered_intensities(scene, h_deg, v_deg, groups, seed=seed, **{**options, "threads": 1})


def pool_workers(scene: dict, directions: int, pixel_mm: float, task_bytes: int = 0) -> int:
    """How many processes measure ``directions`` directions: one per core, at most one per
    direction, and as many as the memory budget holds beside this process and its band pool's
    workers (``budget``): each a band worker's figure (``budget.WORKER_BYTES``) and its largest
    view's image; one of them runs the largest task beside the directions, whose ``task_bytes`` (a
    worker's whole figure while it runs it) is counted for that worker where it is more. 1 below
    ``MIN_POOLED_DIRECTIONS``, inside Blender, whose process is not to be forked, and in a worker
    process (a study's or a trial's task, on the pool or on Dask: its siblings have the cores)."""
    import multiprocessing
    import os
    import sys

    from .. import budget

    if directions < MIN_POOLED_DIRECTIONS or "bpy" in sys.modules or multiprocessing.parent_process() is not None:
        return 1
    lo, hi = body_box.body_box(scene["body"])  # no view is wider than the window's diagonal
    side = math.ceil(float(np.linalg.norm(hi - lo)) / pixel_mm + 2 * WINDOW_MARGIN_MM / pixel_mm) + 2
    per_worker = budget.WORKER_BYTES + budget.render_bytes(side, side, False, "exr") - budget.BASE_BYTES
    from ..raytrace import band_pool

    beside = budget.BASE_BYTES + band_pool.running_workers() * budget.WORKER_BYTES  # this process and its band pool
    beside += max(0, task_bytes - per_worker)  # the worker running the largest task
    fits = (budget.MEMORY_BUDGET - beside) // per_worker
    return int(max(1, min(os.cpu_count() or 1, directions, fits)))


def rendered_intensity(scene: dict, h_deg: float, v_deg: float, lamps: Sequence[int] | None = None,
                       **options) -> Intensity:
    """I(H, V) in cd of the lamps ``lamps`` (None: the whole design) with their bulbs as the scene
    has them, and its standard error (the module's docstring); ``options`` as ``rendered_intensities``."""
    return rendered_intensities(scene, h_deg, v_deg, None if lamps is None else [lamps], **options)[0]


@dataclass(frozen=True)
class Sweep:
    """A goniometer sweep on an (H, V) grid: ``cd[g, i, j]`` and ``stderr`` of lamp group g at
    (h[i], v[j]), and the tristimulus intensities ``xyz[g, i, j]``."""

    h_deg: np.ndarray
    v_deg: np.ndarray
    cd: np.ndarray
    stderr: np.ndarray
    xyz: np.ndarray

    def group(self, g: int) -> Sweep:
        return Sweep(self.h_deg, self.v_deg, self.cd[g:g + 1], self.stderr[g:g + 1], self.xyz[g:g + 1])


def sweep(scene: dict, h_deg: Sequence[float], v_deg: Sequence[float], groups: Sequence[Sequence[int]] | None = None,
          **options) -> Sweep:
    """``rendered_intensities`` at every (H, V) of the grid ``h_deg`` × ``v_deg`` (``intensities_at``)."""
    h, v = np.asarray(h_deg, dtype=np.float64), np.asarray(v_deg, dtype=np.float64)
    n_groups = 1 if groups is None else len(groups)
    cd = np.zeros((n_groups, len(h), len(v)))
    err, xyz = np.zeros_like(cd), np.zeros((*cd.shape, 3))
    grid = [(i, j) for i in range(len(h)) for j in range(len(v))]
    values = intensities_at(scene, [(float(h[i]), float(v[j])) for i, j in grid], groups, **options)
    for (i, j), at in zip(grid, values, strict=True):
        for g, value in enumerate(at):
            cd[g, i, j], err[g, i, j], xyz[g, i, j] = value.cd, value.stderr, value.xyz
    return Sweep(h, v, cd, err, xyz)


# The 7-point rule of degree 3 on a disc (Stroud, "Approximate calculation of multiple integrals",
# 1971, formula S2:3-1... as tabulated for the unit disc): the centre with weight 1/4 and six points
# at radius √(2/3) with weight 1/8 each; exact for every polynomial of degree ≤ 3 over the disc.
DISC_RULE = ((0.0, 0.25),) + tuple((math.sqrt(2.0 / 3.0), 0.125) for _ in range(6))


def cone_directions(h_deg: float, v_deg: float, cone_deg: float) -> list[tuple[float, float, float]]:
    """(H, V, weight) of the disc rule's points over the cone of half angle ``cone_deg`` about (H, V):
    the mean of I over the cone is Σ w I(H_i, V_i) to the rule's degree."""
    from .directions import angles_of

    d0 = direction(h_deg, v_deg)
    e1 = np.cross(d0, [0.0, 0.0, 1.0]) if abs(d0[2]) < 0.99 else np.cross(d0, [1.0, 0.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(d0, e1)
    out = []
    for i, (radius, weight) in enumerate(DISC_RULE):
        rho = math.radians(cone_deg) * radius
        psi = math.pi / 3.0 * (i - 1)
        d = math.cos(rho) * d0 + math.sin(rho) * (math.cos(psi) * e1 + math.sin(psi) * e2)
        h, v = angles_of(d)
        out.append((float(h), float(v), weight))
    return out


def rendered_cone_means(scene: dict, h_deg: float, v_deg: float, cone_deg: float,
                        groups: Sequence[Sequence[int]] | None = None, **options) -> list[Intensity]:
    """The mean of I over the cone of half angle ``cone_deg`` about (H, V), by the disc rule over
    ``rendered_intensities``: what ``light_tracing`` estimates, for comparing the two."""
    points = cone_directions(h_deg, v_deg, cone_deg)
    total: list[list] = []
    values = intensities_at(scene, [(h, v) for h, v, _ in points], groups, **options)
    for (_, _, w), at in zip(points, values, strict=True):
        for g, value in enumerate(at):
            if g == len(total):
                total.append([0.0, 0.0, np.zeros(3)])
            total[g][0] += w * value.cd
            total[g][1] += (w * value.stderr) ** 2
            total[g][2] = total[g][2] + w * value.xyz
    return [Intensity(cd, math.sqrt(var), xyz) for cd, var, xyz in total]

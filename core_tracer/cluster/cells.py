"""One render as a self-contained task, and its content address.

A *cell* is a variant scene at a size. What a worker needs travels with it: the scene document
(never a path the worker may not have) and, when the scene sees an environment image, the image's
bytes, sent once per study and named by their SHA-256 (``Inputs``); the worker writes them into
its own cache folder under that name and renders the scene pointed at that copy (``render_cell``).
The measured curves a photometric scene reads (``filter_file``, ``spectrum_file``: a few kB each)
and a free-form design's meshes (its ``.glb``, ``freeform.mesh_file``) travel inside the cell
itself, each named by its SHA-256 and written beside the images.

A cell's *key* is the SHA-256 of everything its image depends on: the scene (with the image file,
the curves and the mesh file replaced by the hashes of their bytes), the size, and the tracer's own
source (``tracer_version``), so a result kept under a key is the image that cell would render now,
on any machine, and a change to the tracer renders everything again.
"""

from __future__ import annotations

import copy
import functools
import hashlib
import json
import os
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import pool_worker

STOP_POLL = 0.5  # seconds between a task's looks at its study's stop flag on the scheduler
PACKAGE = Path(__file__).resolve().parent.parent  # core_tracer


@functools.lru_cache(maxsize=1)
def tracer_version() -> str:
    """SHA-256 of the tracer's Python sources (every ``core_tracer/**/*.py``, by relative path)."""
    digest = hashlib.sha256()
    for path in sorted(PACKAGE.rglob("*.py")):
        digest.update(path.relative_to(PACKAGE).as_posix().encode("utf-8") + b"\0")
        digest.update(path.read_bytes() + b"\0")
    return digest.hexdigest()


def environment_path(scene: dict) -> str | None:
    """The environment image a scene sees (a bundled world's file or the user's), None for none."""
    from ..raytrace import environment

    env = scene.get("environment")
    if env is None or env["world"] == "none":
        return None
    return environment.image_path(env)


class Inputs:
    """The environment images of a run, read once each and named by the SHA-256 of their bytes."""

    def __init__(self) -> None:
        self.data: dict[str, bytes] = {}  # hash -> bytes
        self._by_path: dict[str, tuple[str, str]] = {}  # path -> (hash, suffix)

    def add(self, path: str) -> tuple[str, str]:
        if path not in self._by_path:
            data = Path(path).read_bytes()
            digest = hashlib.sha256(data).hexdigest()
            self.data.setdefault(digest, data)
            self._by_path[path] = (digest, os.path.splitext(path)[1].lower())
        return self._by_path[path]


@dataclass(frozen=True)
class Cell:
    scene: dict  # normalised; its environment file, if any, is replaced by the worker
    width: int
    height: int
    environment: str | None = None  # SHA-256 of the environment image's bytes
    suffix: str = ""  # the image's file suffix (.exr, .hdr): its reader goes by it
    # the measured curves and the mesh file: (where the scene names it, ``curve_paths``; SHA-256; bytes)
    curves: tuple[tuple[tuple, str, bytes], ...] = ()

    @property
    def key(self) -> str:
        from ..scene.beside import with_curves_at

        scene = copy.deepcopy(self.scene)
        if self.environment is not None:
            scene["environment"]["world"] = "file"
            scene["environment"]["file"] = f"sha256:{self.environment}{self.suffix}"
        scene = with_curves_at(scene, {keys: f"sha256:{digest}{_suffix(keys)}" for keys, digest, _data in self.curves})
        doc = {"scene": scene, "size": [self.width, self.height], "tracer": tracer_version()}
        return hashlib.sha256(json.dumps(doc, sort_keys=True, separators=(",", ":")).encode("utf-8")).hexdigest()


def make_cell(scene: dict, width: int, height: int, inputs: Inputs) -> Cell:
    """The cell of a scene whose files are given by full paths (its environment image, its curves)."""
    curves = tuple(_curve(keys, path) for keys, path in curve_paths(scene).items())
    path = environment_path(scene)
    if path is None:
        return Cell(scene, width, height, curves=curves)
    digest, suffix = inputs.add(path)
    return Cell(scene, width, height, digest, suffix, curves)


def curve_paths(scene: dict) -> dict[tuple, str]:
    """The measured curves a scene reads, by where it names them (``beside.named_curves``), and a
    free-form design's mesh file (``MESH_FILE``): the full paths the loader gave them
    (``beside.with_spectrum_files``, ``study``'s runnable variants)."""
    from ..scene.beside import named_curves

    out = {}
    for keys, _where in named_curves(scene):
        node = scene
        for key in keys:
            node = node[key]
        out[keys] = node
    if "freeform" in scene:
        out[MESH_FILE] = scene["freeform"]["mesh_file"]
    return out


MESH_FILE = ("freeform", "mesh_file")


def _suffix(keys: tuple) -> str:
    """The suffix a sent file is written with: its reader goes by it for the mesh file."""
    return ".glb" if keys == MESH_FILE else ".csv"


def _curve(keys: tuple, path: str) -> tuple[tuple, str, bytes]:
    data = Path(path).read_bytes()
    return keys, hashlib.sha256(data).hexdigest(), data


def inputs_folder() -> str:
    """Where a worker keeps the environment images it was sent: ``<cache>/lamp-styling/inputs``."""
    from ..raytrace.world_cache import ENV_FOLDER

    root = os.environ.get(ENV_FOLDER)
    if not root:
        base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
        root = os.path.join(base, "lamp-styling")
    folder = os.path.join(root, "inputs")
    os.makedirs(folder, mode=0o700, exist_ok=True)
    return folder


def _materialise(digest: str, suffix: str, data: bytes) -> str:
    """The local path of the image ``digest``, written (atomically) the first time."""
    from ..fileio import atomic_write_bytes

    path = os.path.join(inputs_folder(), digest + suffix)
    if not os.path.isfile(path) or hashlib.sha256(Path(path).read_bytes()).hexdigest() != digest:
        atomic_write_bytes(path, data)
    return path


def stop_flag(name: str | None):
    """A ``should_stop`` that looks at the study's ``distributed.Event`` at most every ``STOP_POLL``
    seconds (each look is a message to the scheduler), the pool's event in a ``local_pool`` worker,
    or None elsewhere."""
    if name is None:
        return None
    if pool_worker.stop is not None:  # a local pool's worker: its shared event, cheap to read
        return pool_worker.stop.is_set
    try:
        from distributed import Event, get_worker

        get_worker()
    except (ImportError, ValueError):
        return None
    event = Event(name)
    last = [time.monotonic(), False]

    def should_stop() -> bool:
        now = time.monotonic()
        if not last[1] and now - last[0] >= STOP_POLL:
            last[0] = now
            last[1] = event.is_set()
        return bool(last[1])

    return should_stop


def render_cell(cell: Cell, environment: bytes | None = None, stop: str | None = None,
                threads: int = 1) -> np.ndarray:
    """The task: the cell's displayed-before-view image, float32 (H, W, 3) linear, glare applied as
    the study's workers apply it. ``environment`` is the bytes of the cell's environment image;
    ``stop`` names the study's stop event (a cancelled study ends its running renders between bands)."""
    from ..freeform.traced import render_scene
    from ..images import glare

    scene = worker_scene(cell, environment)
    result = render_scene(scene, cell.width, cell.height, should_stop=stop_flag(stop), threads=threads,
                           keep_passes=False)
    return glare.apply(result.image, scene)


def worker_scene(cell: Cell, environment: bytes | None) -> dict:
    """The cell's scene as this worker renders it: its environment image and its curves the copies
    of the bytes sent (whatever folder the design came from: this worker may not see it)."""
    if cell.curves:
        from ..scene.beside import with_curves_at

        curves = {keys: _materialise(digest, _suffix(keys), data) for keys, digest, data in cell.curves}
        cell = Cell(with_curves_at(cell.scene, curves), cell.width, cell.height, cell.environment, cell.suffix)
    if cell.environment is None:
        return cell.scene
    if environment is None:
        raise ValueError(f"cell {cell.key[:12]} sees an environment image that was not sent with it")
    scene = copy.deepcopy(cell.scene)
    scene["environment"]["world"] = "file"
    scene["environment"]["file"] = _materialise(cell.environment, cell.suffix, environment)
    return scene


# ---------------------------------------------------------------------------------------------
# A large cell in bands of rows

# A cell of at least this many eye rays (pixels x samples) is sent as several tasks, each a run of
# its bands of rows of about this many rays: a print-size variant (1920 px at 64 samples, 236
# million rays) becomes some 30 tasks that many workers share. Bands are traced alone, so the rows
# are those of the whole render, bit for bit (the band pool relies on the same).
BAND_TASK_RAYS = 8_000_000


def band_groups(cell: Cell) -> list[list[tuple[int, int, int]]]:
    """The cell's bands ((index, y0, y1), ``schedule.band_rows``) in runs of about
    ``BAND_TASK_RAYS`` eye rays; one run for a cell below that."""
    from ..raytrace.engine import make_context
    from ..raytrace.engine.schedule import band_rows

    if "freeform" in cell.scene:  # its meshes' tracer renders a whole cell (``render_cell``)
        return [[]]
    ctx = make_context(cell.scene, cell.width, cell.height)
    rays_per_row = cell.width * ctx.samples
    groups: list[list[tuple[int, int, int]]] = [[]]
    rays = 0
    for index, (y0, y1) in enumerate(band_rows(ctx)):
        if groups[-1] and rays + (y1 - y0) * rays_per_row > BAND_TASK_RAYS:
            groups.append([])
            rays = 0
        groups[-1].append((index, y0, y1))
        rays += (y1 - y0) * rays_per_row
    return groups


def render_bands(cell: Cell, bands: list[tuple[int, int, int]], environment: bytes | None = None,
                 stop: str | None = None) -> list[tuple[int, int, np.ndarray]]:
    """The task for part of a large cell: (y0, y1, rows (y1 - y0, W, 3) float32) of each band, traced
    as ``render_passes`` traces them (no glare: that needs the whole image, ``assemble``)."""
    from ..raytrace.engine import RenderCancelled, make_context
    from ..raytrace.engine.schedule import BandImage, worker_bands

    scene = worker_scene(cell, environment)
    ctx = make_context(scene, cell.width, cell.height)
    queued = list(bands)
    rows = {index: (y0, y1) for index, y0, y1 in bands}
    stopped = stop_flag(stop) or (lambda: False)

    def take() -> tuple[int, int, int] | None:
        if stopped():
            raise RenderCancelled("render cancelled")
        return queued.pop(0) if queued else None

    out = []
    for index, band in worker_bands(ctx, take, stopped):
        y0, y1 = rows[index]
        image = BandImage.of(band, False).image
        out.append((y0, y1, image.reshape(y1 - y0, cell.width, 3)))
    return out


def assemble(cell: Cell, parts: list[list[tuple[int, int, np.ndarray]]]) -> np.ndarray:
    """The cell's image from its bands' rows, glare applied as ``render_cell`` applies it."""
    from ..images import glare

    image = np.zeros((cell.height, cell.width, 3), dtype=np.float32)
    for part in parts:
        for y0, y1, rows in part:
            image[y0:y1] = rows
    return glare.apply(image, cell.scene)

"""The render entry: a scene in, the image and its contribution passes out (docs/model.md §5.2).

Rays are traced backward from the eye, one per pixel through its centre (the paper's setting),
or, with ``image.samples`` N > 1, N per pixel placed by the pixel filter (``pixel_filter``), the
pixel being their mean; adaptive sampling (``adaptive``) traces all N only where a first few
disagree. At every dielectric surface a ray branches into a reflected and a transmitted ray (the
ray-tracing tree of Fig. 7); each carries its accumulated attenuation k, and luminance is added to
the pixel as k × the value found, so the tree is never stored (docs/model.md §5). All live rays of one
generation are processed together as arrays (``walk``); the image is worked in bands of rows to
bound memory (``schedule``), and the last few branches of a band are traced along with the next
band's rays (``carried``).
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field

import numpy as np

from .. import pixel_filter
from ..camera import make_camera
from . import schedule
from .adaptive import ADAPTIVE_THRESHOLD
from .context import Context
from .rays import PASS_NAMES, BySource
from .schedule import BandImage, BandsElsewhere, band_rows, never


@dataclass
class RenderResult:
    image: np.ndarray
    passes: dict[str, np.ndarray]
    stats: dict = field(default_factory=dict)


class Film:
    """The image a render fills in band by band (and each pass, when kept), and the render's
    statistics; each band goes on to the caller's ``on_rows`` and ``on_band`` as it arrives."""

    def __init__(self, width: int, height: int, keep_passes: bool,
                 on_rows: Callable[[int, int, np.ndarray], None] | None = None,
                 on_band: Callable[[int, int, np.ndarray, dict[str, np.ndarray]], None] | None = None,
                 names: tuple[str, ...] = PASS_NAMES):
        self.width, self.height, self.keep_passes = width, height, keep_passes
        self.on_rows, self.on_band = on_rows, on_band
        self.names = names  # the planes kept: the passes, or the sources (``rays.BySource``)
        self.passes = np.zeros((len(names) if keep_passes else 0, height, width, 3), dtype=np.float32)
        self.image = np.zeros((height, width, 3), dtype=np.float32)
        self.stats = {"segments": 0, "max_depth": 0, "cut_at_depth": 0, "transitions": set(), "busy_pixels": 0}
        self.workers: set[int] = set()  # the processes that traced bands (0: this one)

    def add(self, y0: int, y1: int, band: BandImage) -> None:
        """The rows ``y0:y1`` traced."""
        if self.keep_passes:
            self.passes[:, y0:y1] = band.passes.reshape(len(self.names), y1 - y0, self.width, 3)
        self.image[y0:y1] = band.image.reshape(y1 - y0, self.width, 3)
        self.stats["segments"] += band.segments
        self.stats["busy_pixels"] += band.busy
        self.stats["max_depth"] = max(self.stats["max_depth"], band.max_depth)
        self.stats["cut_at_depth"] += band.cut_at_depth
        self.stats["transitions"] |= band.transitions
        self.workers.add(band.process)
        if self.on_rows is not None:
            self.on_rows(y0, y1, self.image[y0:y1])
        if self.on_band is not None:
            self.on_band(y0, y1, self.image[y0:y1],
                         {name: self.passes[i, y0:y1] for i, name in enumerate(self.names)} if self.keep_passes
                         else {})

    def expose(self, traced: Iterator[tuple[int, int, BandImage]], n_bands: int,
               progress: Callable[[float], None] | None) -> None:
        """Every band of ``traced`` (``n_bands`` in all) added, ``progress(fraction)`` after each."""
        for done, (y0, y1, band) in enumerate(traced, start=1):
            self.add(y0, y1, band)
            if progress is not None:
                progress(done / n_bands)

    def result(self, samples: int, seconds: float) -> RenderResult:
        stats = self.stats
        stats["seconds"] = seconds
        stats["width"], stats["height"], stats["samples"] = self.width, self.height, samples
        stats["worker_processes"] = len(self.workers - {0})  # how many of a pool's processes traced bands
        passes = dict(zip(self.names, self.passes, strict=False)) if self.keep_passes else {}
        return RenderResult(self.image, passes, stats)


def render_passes(scene: dict, width: int | None = None, height: int | None = None, *,
                  progress: Callable[[float], None] | None = None,
                  should_stop: Callable[[], bool] | None = None,
                  on_rows: Callable[[int, int, np.ndarray], None] | None = None,
                  on_band: Callable[[int, int, np.ndarray, dict[str, np.ndarray]], None] | None = None,
                  threads: int | None = None, record_transitions: bool = False,
                  keep_passes: bool = True, samples: int | None = None,
                  filter_name: str = pixel_filter.DEFAULT_FILTER, world_seen: bool = True,
                  adaptive_threshold: float | None = None, pool: BandsElsewhere | None = None,
                  bands: int | None = None, by_source: bool = False) -> RenderResult:
    """Render a normalised scene; returns the image and its contribution passes (docs/model.md §5.2).

    ``width``/``height`` override the scene's image size (the camera's field of view still
    spans the fitted side). Bands of rows are rendered on ``threads`` threads (numpy releases
    the GIL); ``progress(fraction)``, ``on_rows(row_start, row_stop, rows)`` and
    ``on_band(row_start, row_stop, rows, pass_rows)`` (the same with each pass's rows, an empty
    dict without ``keep_passes``) are called from the calling thread as bands finish;
    ``should_stop()`` is polled between bands. ``samples`` overrides the scene's samples per
    pixel; ``filter_name`` is the pixel filter of more than one sample (``pixel_filter.FILTERS``).
    ``world_seen=False`` leaves out what eye rays that miss everything see (a transparent film):
    the surroundings still light the lamp and show in it.
    ``adaptive_threshold`` (default ``ADAPTIVE_THRESHOLD``) spends the samples where the image
    changes (``adaptive``); 0 traces every sample of every pixel.
    ``pool`` (``band_pool.shared()``) traces the bands in worker processes when it is running and
    free, and ``threads`` > 1: the same image bit for bit, without the threads' contention for
    the interpreter; otherwise, and with no pool, bands run on threads of this process.

    A scene whose ``light_model`` is "photometric" is traced on ``bands`` wavelength bands
    (None: ``spectral.DEFAULT_BANDS``) and its image and passes are CIE XYZ with Y in cd/m²
    (``stats["light_model"]`` says which); the paper mode's are linear RGB.

    ``by_source`` keeps, instead of the passes, each source's light (``rays.BySource``): the
    ``surroundings`` and ``lamp0``, ``lamp1``, ... (what each lamp's bulb or LED dies emit), from the
    same rays, summing to the image (the light states of ``measures.states``, from one walk).
    """
    width = int(width or scene["image"]["width"])
    height = int(height or scene["image"]["height"])
    start = time.perf_counter()
    ctx = make_context(scene, width, height, record_transitions=record_transitions, samples=samples,
                       filter_name=filter_name, adaptive_threshold=adaptive_threshold, world_seen=world_seen,
                       bands=bands, by_source=by_source)
    band_count = bands
    bands = band_rows(ctx)
    threads = max(1, min(threads or os.cpu_count() or 1, len(bands)))
    film = Film(width, height, keep_passes, on_rows, on_band, ctx.planes.names)

    def on_threads(some: list[tuple[int, int]]) -> Iterator[tuple[int, int, BandImage]]:
        for y0, y1, band in schedule.traced_bands(ctx, some, max(1, min(threads, len(some))), should_stop or never):
            yield y0, y1, BandImage.of(band, keep_passes)

    if pool is not None and threads > 1:
        options = {"record_transitions": record_transitions, "samples": ctx.samples, "filter_name": filter_name,
                   "adaptive_threshold": ctx.adaptive_threshold, "world_seen": world_seen,
                   "keep_passes": keep_passes, "bands": band_count, "by_source": by_source}
        traced = pool.traced_bands(scene, width, height, options, bands, threads, should_stop or never, on_threads)
    else:
        traced = on_threads(bands)
    film.expose(traced, len(bands), progress)
    result = film.result(ctx.samples, time.perf_counter() - start)
    result.stats["light_model"] = "paper" if ctx.photometric is None else "photometric"
    if ctx.photometric is not None:
        result.stats["bands"] = ctx.channels
        result.stats["band_edges_nm"] = ctx.photometric.bands.edges_nm.tolist()
    return result


def make_context(scene: dict, width: int, height: int, *, record_transitions: bool = False,
                 samples: int | None = None, filter_name: str = pixel_filter.DEFAULT_FILTER,
                 adaptive_threshold: float | None = None, world_seen: bool = True,
                 bands: int | None = None, by_source: bool = False) -> Context:
    """Everything constant during one render of ``scene`` at ``width`` x ``height`` (the
    arguments as ``render_passes`` takes them): built alike in this process and in a worker
    process of a ``band_pool``, so that both trace the same bands to the same values."""
    # A document an earlier version wrote, or an image section a caller built, has no samples: 1.
    samples = int(samples or scene["image"].get("samples", 1))
    pixel_filter.filter_support(filter_name)  # an unknown filter fails here, before any work
    adaptive_threshold = ADAPTIVE_THRESHOLD if adaptive_threshold is None else float(adaptive_threshold)
    ctx = Context(scene, make_camera(scene["camera"], width, height), record_transitions, samples, filter_name,
                  adaptive_threshold, bands)
    ctx.world_seen = world_seen
    if by_source:
        ctx.planes = BySource(len(scene["lamps"]))
    return ctx


def lens_pixels(scene: dict, width: int, height: int) -> np.ndarray:
    """(height, width) int: the lamp whose lens the eye ray through each pixel's centre meets first,
    -1 where none (the body, the background; every pixel of a free-form design), found by geometry
    (``eyes.lens_seen``), so an unlit lens counts as a lens."""
    from ..camera import eye_rays
    from .eyes import lens_seen

    ctx = make_context(scene, width, height, samples=1)
    o, d = eye_rays(ctx.camera, np.arange(width * height))
    return lens_seen(ctx, o, d).reshape(height, width)


def render(scene: dict, width: int | None = None, height: int | None = None, *,
           progress: Callable[[float], None] | None = None,
           should_stop: Callable[[], bool] | None = None) -> np.ndarray:
    """Render a normalised scene: float32 (H, W, 3), top row first, linear RGB."""
    return render_passes(scene, width, height, progress=progress, should_stop=should_stop, keep_passes=False).image


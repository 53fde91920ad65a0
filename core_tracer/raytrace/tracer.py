"""The improved ray tracing of the paper as a numpy wavefront.

Rays are traced backward from the eye, one per pixel through its centre (the paper's setting),
or, with ``image.samples`` N > 1, N per pixel placed by the pixel filter (``pixel_filter``),
the pixel being their mean; adaptive sampling (``_trace_adaptive``) traces all N only where a
first few disagree, and lets the pixels of flat regions keep the mean of those few. At every dielectric
surface a ray branches into a reflected and a transmitted ray (the ray-tracing tree of Fig. 7);
each carries its accumulated attenuation k, and luminance is added to the pixel as k × the
value found, so the tree is never stored (docs/model.md §5). All live rays of one generation are
processed together as arrays; the image is worked in bands of rows to bound memory, and the last
few branches of a band are traced along with the next band's rays (``_carrying_tails``; with more
than one sample per pixel, those of each group of samples along with the next group's,
``_carrying_samples``).
"""

from __future__ import annotations

import math
import os
import queue
import sys
import threading
import time
from collections import deque
from collections.abc import Callable, Generator, Iterator
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np

from ..scene.derived import body_wraps
from . import optics, pixel_filter, sunlight
from . import paths as P
from .camera import Camera, eye_rays, make_camera
from .lamp_table import LampTable
from .lighting import Lighting
from .parts import body_box, outer_face, parts_for, reflector
from .parts.base import Segments, put_rows, rows
from .parts.cylinder_lens import outward_normal

if TYPE_CHECKING:
    from .band_pool import BandPool

CUTOFF = 1e-3  # paper §3.4: a branch whose accumulated attenuation falls below 0.1 % is dropped
MAX_DEPTH = 64  # safety net on the number of segments along one branch
TILE_RAYS = 65536  # eye rays per band of rows: bounds memory whatever the image size (benchmarks/bench_tracer.py)
PILOT_SAMPLES = 4  # samples per pixel traced first by adaptive sampling (``pilot_samples``)
# Adaptive sampling's agreement, a fraction of a pixel's brightness: on the four-lamp preset at 16
# samples and 512x512 it leaves every pixel within 7e-4 of the image's peak (the mean within 1e-5
# of the image's mean) of taking all samples everywhere, while tracing about a third fewer segments
# (benchmarks/bench_samples.py, tests/raytrace/test_adaptive_sampling.py).
ADAPTIVE_THRESHOLD = 0.01

PASS_NAMES = ("lens_surface", "bulb", "reflector_constant", "reflector_scatter", "socket", "side_wall",
              "body", "background")
(LENS_SURFACE, BULB_PASS, REFLECTOR_CONSTANT, REFLECTOR_SCATTER, SOCKET_PASS, SIDE_WALL_PASS, BODY_PASS,
 BACKGROUND_PASS) = range(len(PASS_NAMES))


class RenderCancelled(Exception):
    """Raised when ``should_stop()`` asked the render to stop."""


@dataclass
class RenderResult:
    image: np.ndarray
    passes: dict[str, np.ndarray]
    stats: dict = field(default_factory=dict)


@dataclass
class _Rays:
    """One generation of live rays inside the lamps (local lamp coordinates)."""

    pix: np.ndarray  # pixel index within the band
    lamp: np.ndarray
    o: np.ndarray
    d: np.ndarray
    k: np.ndarray  # accumulated attenuation, RGB
    medium: np.ndarray  # paths.IN_LENS / IN_AIR
    src: np.ndarray  # surface the segment starts on
    parent: np.ndarray  # path class of the segment that spawned this one
    branch: np.ndarray  # paths.REFLECTED / TRANSMITTED
    seen_reflector: np.ndarray

    def __len__(self) -> int:
        return len(self.pix)

    def take(self, sel: np.ndarray) -> _Rays:
        if sel.dtype == bool:
            if sel.all():
                return self
            sel = np.nonzero(sel)[0]
        return _Rays(*(rows(getattr(self, f), sel) for f in _RAY_FIELDS))


_RAY_FIELDS = ("pix", "lamp", "o", "d", "k", "medium", "src", "parent", "branch", "seen_reflector")


class _Unrecorded:
    """The rays' parent classes and branches when the render records no transitions: they only feed
    ``_Band.note``, so nothing is computed or gathered for them; every gather of this is itself."""

    def take(self, *_args, **_kwargs) -> _Unrecorded:
        return self

    def __getitem__(self, _key) -> _Unrecorded:
        return self


UNRECORDED = _Unrecorded()


def _tags(cls: np.ndarray | _Unrecorded, branch: int, n: int) -> np.ndarray | _Unrecorded:
    """The ``branch`` of ``n`` children whose parents' classes are ``cls`` (UNRECORDED: none kept)."""
    return UNRECORDED if cls is UNRECORDED else np.full(n, branch, np.int8)


def _concat(parts: list[_Rays]) -> _Rays:
    fields = ([getattr(p, f) for p in parts] for f in _RAY_FIELDS)
    return _Rays(*(UNRECORDED if any(a is UNRECORDED for a in each) else np.concatenate(each) for each in fields))


class _Context(Lighting):
    """Everything constant during one render."""

    def __init__(self, scene: dict, camera: Camera, record_transitions: bool, samples: int, filter_name: str,
                 adaptive_threshold: float = 0.0):
        super().__init__(scene)
        self.camera = camera
        self.samples = samples
        self.filter_name = filter_name
        self.adaptive_threshold = adaptive_threshold
        self.lamps = LampTable.from_scene(scene)
        self.parts = parts_for(self.lamps)  # the parts a ray can meet, in PARTS's order
        self.plates = bool(self.lamps.ring_count.any())  # else no ray meets a prism plate or its housing
        body = scene["body"]
        self.box_lo, self.box_hi = body_box.body_box(body)
        self.window = body_box.screen_window(camera, self.box_lo, self.box_hi)  # the pixels that can see the body
        self.wraps = body_wraps(scene)  # the curved ends of the front, none for flat lenses
        self.body = body
        self.phantom_lamps = sunlight.PhantomLamps.of(self.sun, self.lamps)  # T_sun and the outline per lamp
        self.phantom = scene["light"].get("phantom", False) and bool(self.phantom_lamps.lets_in.any())
        self.record = record_transitions


def add_to_pass(acc: np.ndarray, pix: np.ndarray, values: np.ndarray) -> None:
    """Add ``values`` (N, 3) to the pixels ``pix`` of one pass ``acc`` (pixels, 3), repeats summed.

    One count over the (pixel, channel) bins of the pixels spanned, each bin summing its values in
    ray order, then added to the pass: the same sums as one count per channel. A few rays spread
    over many pixels (the deep branches of a band) are counted over the pixels they reach alone:
    the same sums, without adding zeros to every pixel between."""
    if len(pix) == 0:
        return
    first, last = int(pix.min()), int(pix.max()) + 1
    if 4 * len(pix) < last - first:
        pixels, slot = _distinct(pix)
        sums = rows(acc, pixels)
        sums += _bin_sums(slot, values, len(pixels))
        put_rows(acc, pixels, sums)
    else:
        acc[first:last] += _bin_sums(pix - first, values, last - first)


def _distinct(pix: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``np.unique(pix, return_inverse=True)`` for pixel indices (|pix| < 2^31): the distinct
    pixels, ascending, and each ray's slot among them. One sort of (pixel, ray) packed into one
    integer instead of numpy's argsort, in about two thirds of its time (the deep branches' calls)."""
    n = len(pix)
    key = np.left_shift(pix, 32, dtype=np.int64)
    key |= np.arange(n)
    key.sort()
    ascending = key >> 32
    new = np.empty(n, bool)
    new[0] = True
    np.not_equal(ascending[1:], ascending[:-1], out=new[1:])
    slot = np.empty(n, np.intp)
    key &= 0xFFFFFFFF  # the rays in pixel order
    slot[key] = np.cumsum(new) - 1
    return ascending[new], slot


def _bin_sums(slot: np.ndarray, values: np.ndarray, n_slots: int) -> np.ndarray:
    """Per slot (n_slots, 3), the sum of the ``values`` of its rays in ray order."""
    # bin 3 slot + channel, a column at a time (numpy broadcasts slowly over rows of three)
    bins = np.empty((len(slot), 3), dtype=np.intp)
    np.multiply(slot, 3, out=bins[:, 0])
    np.add(bins[:, 0], 1, out=bins[:, 1])
    np.add(bins[:, 0], 2, out=bins[:, 2])
    weights = np.broadcast_to(values, bins.shape)
    return np.bincount(bins.ravel(), weights=weights.ravel(), minlength=3 * n_slots).reshape(n_slots, 3)


class _Band:
    """Accumulates the passes of one band of pixels and the band's statistics."""

    def __init__(self, n_pixels: int, ctx: _Context, acc: np.ndarray | None = None):
        self.n = n_pixels
        self.acc = np.zeros((len(PASS_NAMES), n_pixels, 3)) if acc is None else acc
        self.segments = 0
        self.max_depth = 0
        self.busy = 0  # pixels that took every sample (adaptive sampling)
        self.transitions: set[tuple[int, int, int]] = set()
        self.ctx = ctx

    def add(self, pass_id: int, pix: np.ndarray, values: np.ndarray) -> None:
        add_to_pass(self.acc[pass_id], pix, values)

    def note(self, pix: np.ndarray, parent: np.ndarray, branch: np.ndarray, child: np.ndarray) -> None:
        """Record the transitions (parent class, branch, child class) of the rays at slots ``pix``."""
        if self.ctx.record and len(child):
            codes = np.unique(parent.astype(np.int64) * 10000 + branch.astype(np.int64) * 100 + child)
            self.transitions.update((int(c) // 10000, (int(c) // 100) % 100, int(c) % 100) for c in codes)


def render_passes(scene: dict, width: int | None = None, height: int | None = None, *,
                  progress: Callable[[float], None] | None = None,
                  should_stop: Callable[[], bool] | None = None,
                  on_rows: Callable[[int, int, np.ndarray], None] | None = None,
                  on_band: Callable[[int, int, np.ndarray, dict[str, np.ndarray]], None] | None = None,
                  threads: int | None = None, record_transitions: bool = False,
                  keep_passes: bool = True, samples: int | None = None,
                  filter_name: str = pixel_filter.DEFAULT_FILTER, world_seen: bool = True,
                  adaptive_threshold: float | None = None, pool: BandPool | None = None) -> RenderResult:
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
    changes (``_trace_adaptive``); 0 traces every sample of every pixel.
    ``pool`` (``band_pool.shared()``) traces the bands in worker processes when it is running and
    free, and ``threads`` > 1: the same image bit for bit, without the threads' contention for
    the interpreter; otherwise, and with no pool, bands run on threads of this process.
    """
    width = int(width or scene["image"]["width"])
    height = int(height or scene["image"]["height"])
    start = time.perf_counter()
    ctx = make_context(scene, width, height, record_transitions=record_transitions, samples=samples,
                       filter_name=filter_name, adaptive_threshold=adaptive_threshold, world_seen=world_seen)
    passes = np.zeros((len(PASS_NAMES) if keep_passes else 0, height, width, 3), dtype=np.float32)
    image = np.zeros((height, width, 3), dtype=np.float32)
    bands = band_rows(ctx)
    threads = max(1, min(threads or os.cpu_count() or 1, len(bands)))
    stats = {"segments": 0, "max_depth": 0, "transitions": set(), "busy_pixels": 0}
    workers: set[int] = set()

    def finish(y0: int, y1: int, band: BandImage) -> None:
        if keep_passes:
            passes[:, y0:y1] = band.passes.reshape(len(PASS_NAMES), y1 - y0, width, 3)
        image[y0:y1] = band.image.reshape(y1 - y0, width, 3)
        stats["segments"] += band.segments
        stats["busy_pixels"] += band.busy
        stats["max_depth"] = max(stats["max_depth"], band.max_depth)
        stats["transitions"] |= band.transitions
        workers.add(band.process)
        if on_rows is not None:
            on_rows(y0, y1, image[y0:y1])
        if on_band is not None:
            on_band(y0, y1, image[y0:y1], {name: passes[i, y0:y1] for i, name in enumerate(PASS_NAMES)}
                    if keep_passes else {})

    def on_threads(some: list[tuple[int, int]]) -> Iterator[tuple[int, int, BandImage]]:
        for y0, y1, band in _traced_bands(ctx, some, max(1, min(threads, len(some))), should_stop or _never):
            yield y0, y1, BandImage.of(band, keep_passes)

    if pool is not None and threads > 1:
        options = {"record_transitions": record_transitions, "samples": ctx.samples, "filter_name": filter_name,
                   "adaptive_threshold": ctx.adaptive_threshold, "world_seen": world_seen,
                   "keep_passes": keep_passes}
        traced = pool.traced_bands(scene, width, height, options, bands, threads, should_stop or _never, on_threads)
    else:
        traced = on_threads(bands)
    for done, (y0, y1, band) in enumerate(traced, start=1):
        finish(y0, y1, band)
        if progress is not None:
            progress(done / len(bands))
    stats["seconds"] = time.perf_counter() - start
    stats["width"], stats["height"], stats["samples"] = width, height, ctx.samples
    stats["worker_processes"] = len(workers - {0})  # how many of a pool's processes traced bands
    return RenderResult(image, dict(zip(PASS_NAMES, passes, strict=False)) if keep_passes else {}, stats)


def make_context(scene: dict, width: int, height: int, *, record_transitions: bool = False,
                 samples: int | None = None, filter_name: str = pixel_filter.DEFAULT_FILTER,
                 adaptive_threshold: float | None = None, world_seen: bool = True) -> _Context:
    """Everything constant during one render of ``scene`` at ``width`` x ``height`` (the
    arguments as ``render_passes`` takes them): built alike in this process and in a worker
    process of a ``band_pool``, so that both trace the same bands to the same values."""
    # A document an earlier version wrote, or an image section a caller built, has no samples: 1.
    samples = int(samples or scene["image"].get("samples", 1))
    pixel_filter.filter_support(filter_name)  # an unknown filter fails here, before any work
    adaptive_threshold = ADAPTIVE_THRESHOLD if adaptive_threshold is None else float(adaptive_threshold)
    ctx = _Context(scene, make_camera(scene["camera"], width, height), record_transitions, samples, filter_name,
                   adaptive_threshold)
    ctx.world_seen = world_seen
    return ctx


def band_rows(ctx: _Context) -> list[tuple[int, int]]:
    """The image's bands of rows, (y0, y1) each, top first."""
    width, height, samples = ctx.camera.width, ctx.camera.height, ctx.samples
    # Adaptive sampling traces the pilot samples of a band at once, then those of its neighbours in
    # the rows above and below it that it needs, then the rest of its busy pixels. The band and those
    # two rows fit one group of rays.
    if ctx.adaptive_threshold > 0 and len(pilot_samples(samples)) < samples:
        rows_per_band = max(1, TILE_RAYS // (width * len(pilot_samples(samples))) - 2)
    else:
        rows_per_band = max(1, TILE_RAYS // (width * samples))
    return [(y, min(height, y + rows_per_band)) for y in range(0, height, rows_per_band)]


@dataclass
class BandImage:
    """What a traced band gives the image: its pixels' sum of passes (pixels, 3) and, when the
    passes are kept, each pass (passes, pixels, 3), float32 as the image stores them, and the
    band's statistics. Small enough to send from a worker process."""

    image: np.ndarray
    passes: np.ndarray | None
    segments: int
    busy: int
    max_depth: int
    transitions: set[tuple[int, int, int]]
    process: int = 0  # the id of the worker process that traced it; 0: this process

    @classmethod
    def of(cls, band: _Band, keep_passes: bool) -> BandImage:
        # the passes summed in float64, then stored in float32: as the image always was
        return cls(band.acc.sum(axis=0).astype(np.float32), band.acc.astype(np.float32) if keep_passes else None,
                   band.segments, band.busy, band.max_depth, band.transitions)


def worker_bands(ctx: _Context, take: Callable[[], tuple[int, int, int] | None],
                 stopped: Callable[[], bool]) -> Iterator[tuple[int, _Band]]:
    """One worker's bands, taken one by one from ``take()`` ((index, y0, y1), None when there are
    no more) and yielded as (index, band) as each completes, the deep branches of each band (or
    group of samples) traced along with the next one's rays; ``stopped()`` ends the work within a
    generation."""
    yield from (_carrying_tails if ctx.samples == 1 else _carrying_samples)(ctx, take, stopped)


def _never() -> bool:
    return False


# The interpreter's switch interval while bands run on several threads, in seconds (Python's is
# 5 ms). A band's last generations trace a few rays each: their numpy calls are too small to release
# the GIL, so that band keeps the interpreter for a whole switch interval each time the other thread,
# tracing many rays, wants it back between two of its numpy calls; with 5 ms that thread all but
# stops while the other finishes its deep branches (benchmarks/bench_viewport.py).
SWITCH_INTERVAL = 2e-4
_switch_lock = threading.Lock()
_switch_users = [0, 0.0]  # renders on several threads running now, and the interval before the first


@contextmanager
def short_switch_interval() -> Iterator[None]:
    """``SWITCH_INTERVAL`` (if shorter) while any render runs bands on several threads; the
    interval it found is restored when the last one ends."""
    with _switch_lock:
        if _switch_users[0] == 0:
            _switch_users[1] = sys.getswitchinterval()
            sys.setswitchinterval(min(SWITCH_INTERVAL, _switch_users[1]))
        _switch_users[0] += 1
    try:
        yield
    finally:
        with _switch_lock:
            _switch_users[0] -= 1
            if _switch_users[0] == 0:
                sys.setswitchinterval(_switch_users[1])


def _traced_bands(ctx: _Context, bands: list[tuple[int, int]], threads: int,
                  should_stop: Callable[[], bool]) -> Iterator[tuple[int, int, _Band]]:
    """Trace the bands, at most ``threads`` at a time (in the calling thread when 1), and yield
    them in order; ``should_stop()`` is polled before starting a band and after each finishes
    (with one sample per pixel, before the first and as each completes: ``_carried_bands``)."""
    traced = _carried_bands if ctx.samples == 1 else _traced_bands_on
    if threads > 1:
        with short_switch_interval():
            yield from traced(ctx, bands, threads, should_stop)
    else:
        yield from traced(ctx, bands, 1, should_stop)


def _traced_bands_on(ctx: _Context, bands: list[tuple[int, int]], threads: int,
                     should_stop: Callable[[], bool]) -> Iterator[tuple[int, int, _Band]]:
    pool = ThreadPoolExecutor(max_workers=threads) if threads > 1 else None
    pending, running = deque(bands), deque()
    try:
        while pending or running:
            while pending and len(running) < threads:
                if should_stop():
                    raise RenderCancelled("render cancelled")
                y0, y1 = pending.popleft()
                running.append((y0, y1, pool.submit(_trace_band, ctx, y0, y1) if pool else _trace_band(ctx, y0, y1)))
            y0, y1, band = running.popleft()
            band = band.result() if pool else band
            if should_stop():
                raise RenderCancelled("render cancelled")
            yield y0, y1, band
    finally:
        if pool is not None:
            pool.shutdown(wait=True, cancel_futures=True)


# ---------------------------------------------------------------------------------------------
# Carrying the tails of bands (one sample per pixel)

# Below this many live rays, a worker stops tracing its band alone: the rays left (the band's deep
# branches) are carried into the wavefront of the next band it takes (benchmarks/bench_viewport.py).
CARRY_RAYS = 4096


@dataclass
class _Tail:
    """A band of rows whose branches are being traced, and where its slots are in the wavefront."""

    index: int  # the band's place in the image's list of bands
    first_pixel: int  # the image index of the band's first pixel
    band: _Band
    lo: int  # its slots in the wavefront's accumulator: lo:hi
    hi: int
    pixels: np.ndarray | None = None  # the band's pixels (image indices) at those slots; None: all, in order
    depth: int = 1  # generations traced, counted as ``_trace_rays`` does

    def image_pixels(self, slots: np.ndarray) -> np.ndarray:
        return slots - self.lo + self.first_pixel if self.pixels is None else self.pixels[slots - self.lo]

    def put_back(self, acc: np.ndarray) -> None:
        """Copy the passes of the pixels carried in ``acc`` back to the band's own accumulator."""
        if self.pixels is not None:
            self.band.acc[:, self.pixels - self.first_pixel] = acc[:, self.lo:self.hi]


class _Wavefront(_Band):
    """The passes of the rays one worker traces together: each band in ``tails`` owns the slots
    ``lo:hi`` of ``acc`` (the band just started all its pixels, an earlier band the pixels its
    carried rays can still reach), so ``add`` needs no splitting; transitions go to their band."""

    def __init__(self, ctx: _Context, acc: np.ndarray, tails: list[_Tail]):
        super().__init__(acc.shape[1], ctx, acc)
        self.tails = tails

    def note(self, pix: np.ndarray, parent: np.ndarray, branch: np.ndarray, child: np.ndarray) -> None:
        if self.ctx.record and len(child):
            for tail in self.tails:
                sel = np.nonzero((pix >= tail.lo) & (pix < tail.hi))[0]
                tail.band.note(pix[sel], parent[sel], branch[sel], child[sel])


def _carrying_tails(ctx: _Context, take: Callable[[], tuple[int, int, int] | None],
                    stopped: Callable[[], bool]) -> Iterator[tuple[int, _Band]]:
    """One worker's bands (``take()`` gives the next band's (index, y0, y1), None when there are no
    more), yielded as (index, band) as each band's last branch ends, not necessarily in order.

    Why carried: a band's last generations trace a few deep branches each (total internal
    reflections in clear lenses), many numpy calls on a few rays each, too short to release the GIL,
    so a second thread all but stops while one thread finishes a band alone. Once fewer than
    ``CARRY_RAYS`` rays are left, the worker starts its next band and traces those rays in the same
    generations, first; only its last band's tail is traced alone. Every value is the same bit for
    bit as tracing the bands apart: every operation on the rays is row by row, a band's rays keep
    their order among the others, each band sums into its own slots in ray order (``add_to_pass``),
    and each band counts its own depth (it stops at ``MAX_DEPTH`` as it would alone)."""
    tails: list[_Tail] = []
    wave: _Wavefront | None = None
    rays: _Rays | None = None
    more = True
    while True:
        job = take() if more else None
        if job is not None:
            wave, rays = _next_wavefront(ctx, tails, wave, rays, *job)
        elif not tails:
            return
        else:
            more = False  # trace what is left to the end
        while True:
            if stopped():
                return
            ended, counts, rays = _end_tails(tails, wave, rays)
            for tail in ended:
                yield tail.index, tail.band
            if not tails or (more and len(rays) < CARRY_RAYS):
                break
            counts = _rays_per_tail(tails, rays.pix) if ended else counts
            for tail, count in zip(tails, counts, strict=True):
                tail.band.segments += count
                tail.depth += 1
            rays = _step(ctx, wave, rays)


def _end_tails(tails: list[_Tail], wave: _Wavefront, rays: _Rays) -> tuple[list[_Tail], list[int], _Rays]:
    """Take out of ``tails`` the bands (or groups) whose branches have all ended, or reached
    ``MAX_DEPTH`` (as ``_trace_rays``'s loop ends): their passes go back to their own accumulators
    and the rays of those cut at the depth leave the wavefront. Returns them, every tail's count of
    rays before (``_rays_per_tail``) and the rays left."""
    counts = _rays_per_tail(tails, rays.pix)
    ended = [(tail, count) for tail, count in zip(tails, counts, strict=True) if count == 0 or tail.depth >= MAX_DEPTH]
    for tail, count in ended:
        tails.remove(tail)
        tail.put_back(wave.acc)
        tail.band.max_depth = tail.depth
        if count:  # MAX_DEPTH: its rays go no further
            rays = rays.take((rays.pix < tail.lo) | (rays.pix >= tail.hi))
    return [tail for tail, _ in ended], counts, rays


def _rays_per_tail(tails: list[_Tail], pix: np.ndarray) -> list[int]:
    """How many of the rays at slots ``pix`` each band in ``tails`` has."""
    if len(tails) <= 1:
        return [len(pix)] * len(tails)
    bounds = [tail.hi for tail in tails[:-1]]
    if tails[-1].pixels is None:  # the band just started, after the carried slots: most rays are its own
        earlier = pix < tails[-1].lo
        carried = pix[earlier] if len(tails) > 2 else None
        n_carried = int(np.count_nonzero(earlier)) if carried is None else len(carried)
        counts = [n_carried] if carried is None else np.bincount(np.searchsorted(bounds, carried, side="right"),
                                                                 minlength=len(tails) - 1).tolist()
        return [*counts, len(pix) - n_carried]
    return np.bincount(np.searchsorted(bounds, pix, side="right"), minlength=len(tails)).tolist()


def _next_wavefront(ctx: _Context, tails: list[_Tail], wave: _Wavefront | None, rays: _Rays | None,
                    index: int, y0: int, y1: int) -> tuple[_Wavefront, _Rays]:
    """The wavefront of the band ``index`` (rows y0:y1) and of the rays carried from ``wave``: the
    pixels those rays can still reach come first (their passes copied from their bands), then the
    new band's; the carried rays come first, then the new band's eye rays' first branches."""
    width = ctx.camera.width
    pixels = np.arange(y0 * width, y1 * width)
    wave, parts = _carried_wavefront(ctx, tails, wave, rays, index, y0 * width, len(pixels))
    band, m = tails[-1].band, tails[-1].lo
    slots = _slots_seeing_body(ctx, y0, y1)
    if slots is None:
        slots = np.arange(len(pixels))
    else:  # the others add nothing (black background, or a film): their eye rays still count as segments
        band.segments += len(pixels) - len(slots)
    band.segments += len(slots)
    if len(slots):
        parts.append(_first_hits(ctx, wave, *eye_rays(ctx.camera, pixels[slots]), m + slots))
    if not parts:
        return wave, _no_rays()
    return wave, _concat(parts) if len(parts) > 1 else parts[0]


def _carried_wavefront(ctx: _Context, tails: list[_Tail], wave: _Wavefront | None, rays: _Rays | None, index: int,
                       first_pixel: int, n: int) -> tuple[_Wavefront, list[_Rays]]:
    """A wavefront of the slots the rays carried from ``wave`` can still reach (their passes copied
    from their bands), then ``n`` slots of a new band ``index`` whose first pixel is ``first_pixel``
    (appended to ``tails``); and the carried rays, moved to their new slots (none: an empty list)."""
    carried_pixels = np.zeros(0, dtype=np.int64)
    if tails:
        image_pix = np.empty(len(rays), dtype=np.int64)
        for tail in tails:
            sel = np.nonzero((rays.pix >= tail.lo) & (rays.pix < tail.hi))[0]
            image_pix[sel] = tail.image_pixels(rays.pix[sel])
            tail.put_back(wave.acc)
        carried_pixels = np.unique(image_pix)
    m = len(carried_pixels)
    acc = np.zeros((len(PASS_NAMES), m + n, 3))
    for tail in tails:
        tail.lo, tail.hi = np.searchsorted(carried_pixels, [tail.first_pixel, tail.first_pixel + tail.band.n])
        tail.pixels = carried_pixels[tail.lo:tail.hi]
        acc[:, tail.lo:tail.hi] = tail.band.acc[:, tail.pixels - tail.first_pixel]
    tails.append(_Tail(index, first_pixel, _Band(n, ctx, acc[:, m:]), m, m + n))
    wave = _Wavefront(ctx, acc, tails)
    return wave, [replace(rays, pix=np.searchsorted(carried_pixels, image_pix))] if m else []


def _no_rays() -> _Rays:
    return _Rays(*(np.zeros(0, dtype=np.int64) for _ in _RAY_FIELDS))


@dataclass
class _Group:
    """A group of eye rays a band's sampling asked for (``_sample_rays``), being traced."""

    index: int  # the band's place in the image's list of bands
    band: _Band
    requests: _Requests  # the band's sampling, sent ``rays`` once traced
    rays: _Band  # every ray's slot, those that miss the body's box already looked up
    toward: np.ndarray | None  # the rays traced (``_rays_toward_body``; None: all), in the wavefront's tail
    o: np.ndarray  # their origins and directions
    d: np.ndarray


def _carrying_samples(ctx: _Context, take: Callable[[], tuple[int, int, int] | None],
                      stopped: Callable[[], bool]) -> Iterator[tuple[int, _Band]]:
    """``_carrying_tails`` for more than one sample per pixel: one worker's bands (``take()`` gives
    the next band's (index, y0, y1), None when there are no more), yielded as (index, band) as each
    band's sampling ends, not necessarily in order.

    A band's sampling asks for groups of eye rays one after another (``_sample_rays``: adaptive
    sampling its pilot samples, then, once those are traced, the rest of its busy pixels' samples).
    Once fewer than ``CARRY_RAYS`` rays are left in the wavefront, the next group starts in it: a
    group a band asked for when its last one ended, else the first of the next band taken. So the
    deep branches of one group share their generations with the next group's rays; only the worker's
    last group's tail is traced alone. Bit for bit as tracing each group alone
    (``_traced_at_once``), as ``_carrying_tails`` is: each group has its own slots (one per ray) and
    counts its own depth."""
    tails: list[_Tail] = []
    tracing: dict[int, _Group] = {}  # by their tails' index
    ready: deque[_Group] = deque()
    wave: _Wavefront | None = None
    rays = _no_rays()
    next_slot = 0  # groups' slots are numbered on from one group to the next (``_Tail.first_pixel``)
    more = True
    while True:
        while len(rays) < CARRY_RAYS and (ready or more):
            if not ready:
                job = take()
                if job is None:
                    more = False
                else:
                    index, y0, y1 = job
                    band = _Band((y1 - y0) * ctx.camera.width, ctx)
                    yield from _ask(ctx, index, band, _sample_rays(ctx, band, y0, y1), None, ready)
                continue
            group = ready.popleft()
            n = len(group.o)
            wave, parts = _carried_wavefront(ctx, tails, wave, rays, next_slot, next_slot, n)
            tracing[next_slot] = group
            tail = tails[-1]
            tail.band.segments += n
            parts.append(_first_hits(ctx, wave, group.o, group.d, tail.lo + np.arange(n)))
            rays = _concat(parts) if len(parts) > 1 else parts[0]
            next_slot += n
        if not tails:
            return
        if stopped():
            return
        ended, counts, rays = _end_tails(tails, wave, rays)
        for tail in ended:
            group = tracing.pop(tail.index)
            if group.toward is None:
                traced = tail.band
            else:
                traced = group.rays
                _put_traced(traced, group.toward, tail.band)
            yield from _ask(ctx, group.index, group.band, group.requests, traced, ready)
        if ended:
            continue  # room for the next group, perhaps
        for tail, count in zip(tails, counts, strict=True):
            tail.band.segments += count
            tail.depth += 1
        rays = _step(ctx, wave, rays)


def _ask(ctx: _Context, index: int, band: _Band, requests: _Requests, traced: _Band | None,
         ready: deque[_Group]) -> Iterator[tuple[int, _Band]]:
    """Send ``traced`` (None: nothing yet) to the sampling of the band ``index`` and queue in
    ``ready`` the group of eye rays it asks for next; yields (index, band) when it asks for none."""
    while True:
        try:
            o, d = requests.send(traced)
        except StopIteration:
            yield index, band
            return
        rays = _Band(len(o), ctx)
        toward = _rays_toward_body(ctx, rays, o, d)
        if toward is None or len(toward):
            if toward is not None:
                o, d = o[toward], d[toward]
            ready.append(_Group(index, band, requests, rays, toward, o, d))
            return
        traced = rays  # every ray missed the body's box


def _carried_bands(ctx: _Context, bands: list[tuple[int, int]], threads: int,
                   should_stop: Callable[[], bool]) -> Iterator[tuple[int, int, _Band]]:
    """``_traced_bands`` with tails carried (``_carrying_tails``): each of ``threads`` workers
    takes the next band from one queue; bands are yielded in order as they complete (those that
    complete early wait). ``should_stop()`` is polled in the calling thread before the first band,
    as each band completes and before each is yielded; then the workers stop within a generation."""
    if should_stop():
        raise RenderCancelled("render cancelled")
    queued = deque(enumerate(bands))
    stop = threading.Event()

    def take() -> tuple[int, int, int] | None:
        if stop.is_set():
            return None
        try:
            index, (y0, y1) = queued.popleft()  # one atomic step: safe between threads
        except IndexError:
            return None
        return index, y0, y1

    pool = ThreadPoolExecutor(max_workers=threads) if threads > 1 else None
    try:
        if pool is None:
            completed = _carrying_tails(ctx, take, _never)
        else:
            completed = _completed_on(pool, threads, lambda: _carrying_tails(ctx, take, stop.is_set))
        in_order = InOrder(bands, should_stop)
        for index, band in completed:
            if index != in_order.next_index and should_stop():
                raise RenderCancelled("render cancelled")
            yield from in_order.add(index, band)
    finally:
        stop.set()
        if pool is not None:
            pool.shutdown(wait=True, cancel_futures=True)


class InOrder:
    """Bands that complete in any order, handed on in the image's order: ``add(index, band)``
    yields (y0, y1, band) for each band now next in line; ``should_stop()`` is polled before each
    (``RenderCancelled``)."""

    def __init__(self, bands: list[tuple[int, int]], should_stop: Callable[[], bool]):
        self.bands = bands
        self.should_stop = should_stop
        self.next_index = 0
        self._waiting: dict = {}

    def add(self, index: int, band) -> Iterator[tuple[int, int, object]]:
        self._waiting[index] = band
        while self.next_index in self._waiting:
            if self.should_stop():
                raise RenderCancelled("render cancelled")
            y0, y1 = self.bands[self.next_index]
            yield y0, y1, self._waiting.pop(self.next_index)
            self.next_index += 1


def _completed_on(pool: ThreadPoolExecutor, threads: int,
                  worker: Callable[[], Iterator[tuple[int, _Band]]]) -> Iterator[tuple[int, _Band]]:
    """What ``threads`` runs of ``worker()`` on ``pool`` yield, as they yield it; a worker's
    exception is raised here."""
    done: queue.SimpleQueue = queue.SimpleQueue()

    def run() -> None:
        try:
            for item in worker():
                done.put(item)
        except BaseException as error:  # handed to the calling thread, raised there
            done.put(error)
        else:
            done.put(None)

    for _ in range(threads):
        pool.submit(run)
    for _ in range(threads):
        while (item := done.get()) is not None:
            if isinstance(item, BaseException):
                raise item
            yield item


def render(scene: dict, width: int | None = None, height: int | None = None, *,
           progress: Callable[[float], None] | None = None,
           should_stop: Callable[[], bool] | None = None) -> np.ndarray:
    """Render a normalised scene: float32 (H, W, 3), top row first, linear RGB."""
    return render_passes(scene, width, height, progress=progress, should_stop=should_stop, keep_passes=False).image


# ---------------------------------------------------------------------------------------------
# One band of rows


def _trace_band(ctx: _Context, y0: int, y1: int) -> _Band:
    cam = ctx.camera
    pixels = np.arange(y0 * cam.width, y1 * cam.width)
    band = _Band(len(pixels), ctx)
    if ctx.samples == 1:  # the paper's setting: one ray through each pixel centre
        slots = _slots_seeing_body(ctx, y0, y1)
        if slots is None:
            _trace_rays(ctx, band, *eye_rays(cam, pixels))
        else:  # the others add nothing (black background, or a film): their eye rays still count as segments
            band.segments += len(pixels) - len(slots)
            band.max_depth = 1
            if len(slots):
                _trace_rays(ctx, band, *eye_rays(cam, pixels[slots]), slots)
        return band
    _traced_at_once(ctx, _sample_rays(ctx, band, y0, y1))
    return band


# The sampling of a band of more than one sample per pixel asks for its eye rays a group at a time:
# it yields a group's origins and directions and is sent them traced (a fresh ``_Band``, ray i in
# slot i). Nothing else of a group depends on how it is traced: alone (``_traced_at_once``) or in
# the wavefront of other groups' rays (``_carrying_samples``).
_Requests = Generator[tuple[np.ndarray, np.ndarray], _Band, None]


def _sample_rays(ctx: _Context, band: _Band, y0: int, y1: int) -> _Requests:
    """The samples of rows ``y0:y1`` into ``band``: adaptive sampling (``_trace_adaptive``), or every
    sample of every pixel."""
    if ctx.adaptive_threshold > 0 and len(pilot_samples(ctx.samples)) < ctx.samples:
        yield from _trace_adaptive(ctx, band, y0, y1)
        return
    pixels = np.arange(y0 * ctx.camera.width, y1 * ctx.camera.width)
    # Samples in groups of at most TILE_RAYS rays (a wide row at many samples takes several),
    # each ray counted in its own slot (pixel-major), summed per pixel in sample order: the same
    # sums whatever the threads.
    for count, o, d in sample_groups(ctx.camera, pixels, ctx.samples, ctx.filter_name):
        group = yield o, d
        per_ray = group.acc.reshape(len(PASS_NAMES), len(pixels), count, 3)
        band.acc += _over_samples(np.add, per_ray.transpose(2, 0, 1, 3))
        band.segments += group.segments
        band.max_depth = max(band.max_depth, group.max_depth)
        band.transitions |= group.transitions
    # The samples are placed by the filter (importance sampling), so the pixel is their plain mean.
    band.acc /= ctx.samples


def _traced_at_once(ctx: _Context, requests: _Requests) -> None:
    """Trace each group of eye rays a band's sampling asks for alone (``_trace_eye_rays``)."""
    group = None
    while True:
        try:
            o, d = requests.send(group)
        except StopIteration:
            return
        group = _Band(len(o), ctx)
        _trace_eye_rays(ctx, group, o, d)


def sample_groups(cam: Camera, pixels: np.ndarray, samples: int,
                  filter_name: str) -> Iterator[tuple[int, np.ndarray, np.ndarray]]:
    """Every sample of ``pixels`` as eye rays, in groups of at most ``TILE_RAYS`` rays (a wide row at
    many samples takes several): per group its sample count and the rays' origins and directions,
    pixel-major (ray i * count + s is sample s0 + s of pixel i), placed by the pixel filter."""
    per_group = max(1, TILE_RAYS // len(pixels))
    for s0 in range(0, samples, per_group):
        count = min(samples, s0 + per_group) - s0
        offsets = pixel_filter.grid_offsets(filter_name, pixels, np.arange(s0, s0 + count), samples, sample_major=False)
        yield (count, *eye_rays(cam, np.repeat(pixels, count), offsets))


def pilot_samples(samples: int) -> np.ndarray:
    """The samples (indices into a pixel's ``samples``) that adaptive sampling traces first:
    ``PILOT_SAMPLES`` spread evenly over the stratified set, so that they cover the filter's
    support in x (stratified) and in y (the radical inverse of spread indices)."""
    count = min(PILOT_SAMPLES, samples)
    return np.unique(np.round(np.linspace(0, samples - 1, count)).astype(np.int64))


def _per_sample(ctx: _Context, band: _Band, pixels: np.ndarray,
                sample_ids: np.ndarray) -> Generator[tuple[np.ndarray, np.ndarray], _Band, np.ndarray]:
    """Trace the samples ``sample_ids`` of every pixel (asked for in groups of at most TILE_RAYS rays,
    whole pixels to a group, as ``_sample_rays``): returns each ray's passes, sample-major (samples,
    passes, pixels, 3), so that one sample of every pixel is one block (a view of the traced group's
    passes when one group holds every pixel: no copy); the band's statistics take the rays' counts.
    Every ray has its own slot, so the order of the rays changes no value."""
    count = len(sample_ids)
    per_group = max(1, TILE_RAYS // count)
    values = None
    for i0 in range(0, len(pixels), per_group):
        group_pixels = pixels[i0:i0 + per_group]
        ray_pixels = np.tile(group_pixels, count)
        offsets = pixel_filter.grid_offsets(ctx.filter_name, group_pixels, sample_ids, ctx.samples, sample_major=True)
        group = yield eye_rays(ctx.camera, ray_pixels, offsets)
        traced = group.acc.reshape(len(PASS_NAMES), count, len(group_pixels), 3).transpose(1, 0, 2, 3)
        if len(group_pixels) == len(pixels):
            values = traced
        else:
            if values is None:
                values = np.empty((count, len(PASS_NAMES), len(pixels), 3))
            values[:, :, i0:i0 + len(group_pixels)] = traced
        band.segments += group.segments
        band.max_depth = max(band.max_depth, group.max_depth)
        band.transitions |= group.transitions
    return values


def _trace_adaptive(ctx: _Context, band: _Band, y0: int, y1: int) -> _Requests:
    """Adaptive sampling of rows ``y0:y1`` (its eye rays asked for as ``_sample_rays``). The pilot
    samples (``pilot_samples``) are traced for every pixel: a pixel whose 3 x 3 neighbourhood's pilot
    samples all agree in every pass to ``adaptive_threshold`` of its brightness lies in a flat part
    of the image and keeps their mean. Every other pixel (an edge, a crease, a bulb image in a
    lenslet) traces the rest of its samples and is their sum in sample order over the count,
    exactly as without adaptive sampling.

    The neighbours of the band's first and last rows in the rows just outside it are traced only
    where they can still decide something: next to the pixels there that agree within the band
    (a neighbour only widens the spread, so a pixel the band finds busy stays busy).

    (A second round, keeping pixels whose first two quarters of samples agreed, was tried and
    dropped: thin creases that both quarters miss made whole pixels wrong.)"""
    width = ctx.camera.width
    pilot = pilot_samples(ctx.samples)
    pixels = np.arange(y0 * width, y1 * width)
    pilot_values = yield from _per_sample(ctx, band, pixels, pilot)
    # Each pass's least and greatest pilot sample over the pixel's 3 x 3 neighbourhood, on the passes'
    # own planes (passes, rows, columns, 3): no transposed copies.
    shape = (len(PASS_NAMES), y1 - y0, width, 3)
    low = _neighbourhood(_over_samples(np.minimum, pilot_values).reshape(shape), np.minimum)
    high = _neighbourhood(_over_samples(np.maximum, pilot_values).reshape(shape), np.maximum)
    per_pixel = (len(PASS_NAMES), -1, 3)  # views of the same planes, a pixel per column
    pilot_mean = _over_samples(np.add, pilot_values) / len(pilot)
    threshold = ctx.adaptive_threshold * pilot_mean.sum(axis=0).max(axis=1)
    busy = _spread(high.reshape(per_pixel), low.reshape(per_pixel)) > threshold
    yield from _outside_rows(ctx, band, y0, y1, pilot, low, high, busy, threshold)  # (widens low, high in place)
    low, high = low.reshape(per_pixel), high.reshape(per_pixel)
    band.acc[:] = pilot_mean
    band.busy = int(busy.sum())
    rest = np.setdiff1d(np.arange(ctx.samples), pilot)
    if ctx.background_seen and ctx.world_seen:
        # Busy pixels whose whole neighbourhood's pilot samples saw only the world (a textured sky):
        # their other samples are looked up in it rather than traced (``_world_samples``, which
        # traces any whose rays meet the body after all).
        world = busy & ~_any_but_background(high) & ~_any_but_background(low)
        busy &= ~world
        busy[_world_samples(ctx, band, pixels, np.flatnonzero(world), pilot, pilot_values)] = True
    busy = np.flatnonzero(busy)
    chunk = max(1, TILE_RAYS // len(rest))
    for c0 in range(0, len(busy), chunk):
        idx = busy[c0:c0 + chunk]
        traced = yield from _per_sample(ctx, band, pixels[idx], rest)
        by_sample = {int(k): traced[i] for i, k in enumerate(rest)}
        by_sample.update({int(k): pilot_values[i][:, idx] for i, k in enumerate(pilot)})
        total = by_sample[0].copy()
        for k in range(1, ctx.samples):  # in sample order, as ``_over_samples`` and the full path
            total += by_sample[k]
        band.acc[:, idx] = total / ctx.samples


def _spread(high: np.ndarray, low: np.ndarray) -> np.ndarray:
    """Per pixel of (passes, pixels, 3) neighbourhood extremes: the greatest spread over its passes
    and channels (some pass and channel spreads beyond a threshold exactly where this does)."""
    return np.maximum.reduce(high - low, axis=0).max(axis=1)


def _outside_rows(ctx: _Context, band: _Band, y0: int, y1: int, pilot: np.ndarray, low: np.ndarray,
                  high: np.ndarray, busy: np.ndarray, threshold: np.ndarray) -> _Requests:
    """The band's first and last rows' neighbours just outside it (``_trace_adaptive``): their pilot
    samples traced next to the pixels there that are not busy yet, then those pixels' neighbourhood
    extremes ``low`` and ``high`` (passes, rows, columns, 3) widened by them and ``busy`` (per pixel of
    the band) decided again, in place."""
    width, height = ctx.camera.width, ctx.camera.height
    edges = []  # (the row outside, its neighbour row in the band, that row's calm pixels, the columns next to them)
    for outside, row in ((y0 - 1, 0), (y1, y1 - y0 - 1)):
        if 0 <= outside < height:
            calm = np.flatnonzero(~busy[row * width:(row + 1) * width])
            if len(calm):
                near = np.unique(np.concatenate([calm[calm > 0] - 1, calm, calm[calm < width - 1] + 1]))
                edges.append((outside, row, calm, near))
    if not edges:
        return
    neighbours = np.concatenate([outside * width + near for outside, _, _, near in edges])
    values = yield from _per_sample(ctx, band, neighbours, pilot)
    least, most = _over_samples(np.minimum, values), _over_samples(np.maximum, values)
    start = 0
    for _, row, calm, near in edges:
        at = np.full(width, -1)
        at[near] = np.arange(start, start + len(near))
        start += len(near)
        row_low, row_high = low[:, row, calm], high[:, row, calm]
        for step in (-1, 0, 1):
            column = calm + step
            inside = np.flatnonzero((column >= 0) & (column < width))
            source = at[column[inside]]
            row_low[:, inside] = np.minimum(row_low[:, inside], least[:, source])
            row_high[:, inside] = np.maximum(row_high[:, inside], most[:, source])
        low[:, row, calm], high[:, row, calm] = row_low, row_high
        pixel = row * width + calm
        busy[pixel] = _spread(row_high, row_low) > threshold[pixel]


def _any_but_background(planes: np.ndarray) -> np.ndarray:
    """Per pixel of (passes, pixels, 3) ``planes``: whether a pass other than the background's is not 0."""
    found = np.zeros(planes.shape[1:], dtype=bool)
    for pass_id, plane in enumerate(planes):
        if pass_id != BACKGROUND_PASS:
            found |= plane != 0
    return found[:, 0] | found[:, 1] | found[:, 2]


def _world_samples(ctx: _Context, band: _Band, pixels: np.ndarray, idx: np.ndarray, pilot: np.ndarray,
                   pilot_values: np.ndarray) -> np.ndarray:
    """The samples other than the pilot ones of the pixels ``idx`` (indices into ``pixels``), whose
    neighbourhood's pilot samples saw only the world: an eye ray that misses the body's box sees
    just the world (``_first_hits``), so where all of a pixel's rays miss it the world's radiance
    of each, summed with the pilot samples' in sample order, is the pixel (the values tracing them
    gives). Returns the indices of ``idx`` a ray of which meets the box after all: trace those."""
    rest = np.setdiff1d(np.arange(ctx.samples), pilot)
    chunk = max(1, TILE_RAYS // len(rest))
    met = []
    for c0 in range(0, len(idx), chunk):
        part = idx[c0:c0 + chunk]
        offsets = pixel_filter.grid_offsets(ctx.filter_name, pixels[part], rest, ctx.samples, sample_major=True)
        o, d = eye_rays(ctx.camera, np.tile(pixels[part], len(rest)), offsets)
        # Only the rays of pixels whose samples can reach the body's picture are tested against its box.
        toward = np.zeros(len(part), dtype=bool)
        near = np.flatnonzero(_near_body(ctx, pixels[part]))
        if len(near):
            rays = (np.arange(len(rest))[:, None] * len(part) + near).ravel()
            t_near, t_far, _ = body_box.hit_box(rows(o, rays), rows(d, rays), ctx.box_lo, ctx.box_hi)
            toward[near] = ((t_near <= t_far) & (t_near > 0)).reshape(len(rest), len(near)).any(axis=0)
        by_sample = np.empty((ctx.samples, len(part), 3))
        by_sample[rest] = ctx.sky(d).reshape(len(rest), len(part), 3)
        by_sample[pilot] = pilot_values[:, BACKGROUND_PASS][:, part]
        total = by_sample[0].copy()
        for k in range(1, ctx.samples):  # in sample order, as the traced pixels
            total += by_sample[k]
        seen = ~toward
        band.acc[BACKGROUND_PASS, part[seen]] = total[seen] / ctx.samples
        band.segments += len(rest) * int(seen.sum())
        band.max_depth = max(band.max_depth, 1)
        met.append(part[toward])
    return np.concatenate(met) if met else np.zeros(0, dtype=np.int64)


def _near_body(ctx: _Context, pixels: np.ndarray) -> np.ndarray:
    """Whether the samples of each of ``pixels`` can meet the body's box: the pixels within the
    filter's reach of ``body_box.screen_window`` (every pixel where there is no window). The rays
    of the others pass outside the picture of the box's corners, so they miss it."""
    if ctx.window is None:
        return np.ones(len(pixels), dtype=bool)
    first_col, last_col, first_row, last_row = ctx.window
    reach = math.ceil(pixel_filter.filter_support(ctx.filter_name))
    row, col = np.divmod(pixels, ctx.camera.width)
    return ((col >= first_col - reach) & (col <= last_col + reach)
            & (row >= first_row - reach) & (row <= last_row + reach))


def _trace_eye_rays(ctx: _Context, band: _Band, o: np.ndarray, d: np.ndarray) -> None:
    """``_trace_rays`` of the eye rays of samples (ray i adds to slot i of the fresh ``band``), the
    rays that miss the body's box taken apart (``_rays_toward_body``). The same values in every slot:
    a ray's branches keep their order whatever other rays are traced with them."""
    toward = _rays_toward_body(ctx, band, o, d)
    if toward is None:
        _trace_rays(ctx, band, o, d)
    elif len(toward):
        traced = _Band(len(toward), ctx)
        _trace_rays(ctx, traced, o[toward], d[toward])
        _put_traced(band, toward, traced)


def _rays_toward_body(ctx: _Context, band: _Band, o: np.ndarray, d: np.ndarray) -> np.ndarray | None:
    """The eye rays ``o, d`` (ray i of slot i of the fresh ``band``) that meet the body's box, to be
    traced; the others see only the world (``_first_hits``), looked up here at once. None: trace
    them all (too few miss to be worth the copies)."""
    t_near, t_far, _ = body_box.hit_box(o, d, ctx.box_lo, ctx.box_hi)
    toward = (t_near <= t_far) & (t_near > 0)
    miss = np.nonzero(~toward)[0]
    if len(miss) < len(o) // 8:
        return None
    if ctx.background_seen and ctx.world_seen:
        _put_slots(band.acc[BACKGROUND_PASS], miss, ctx.sky(d[miss]))
    band.segments += len(miss)
    band.max_depth = max(band.max_depth, 1)
    return np.nonzero(toward)[0]


def _put_traced(band: _Band, toward: np.ndarray, traced: _Band) -> None:
    """The traced rays ``toward`` (``_rays_toward_body``) into their slots of ``band``."""
    for acc, values in zip(band.acc, traced.acc, strict=True):
        _put_slots(acc, toward, values)
    band.segments += traced.segments
    band.max_depth = max(band.max_depth, traced.max_depth)
    band.transitions |= traced.transitions


_SLOT = np.dtype((np.void, 3 * 8))  # one slot of a pass, its three float64 channels as one item


def _put_slots(acc: np.ndarray, slots: np.ndarray, values: np.ndarray) -> None:
    """``acc[slots] = values`` for (N, 3) float64 rows: each row copied as one 24-byte item, about
    twice as fast as numpy's scatter of rows (the same bytes)."""
    acc.view(_SLOT)[slots, 0] = np.ascontiguousarray(values, dtype=np.float64).view(_SLOT)[:, 0]


def _over_samples(combine: np.ufunc, values: np.ndarray) -> np.ndarray:
    """``combine`` (np.add, np.minimum, np.maximum) of sample-major (samples, passes, pixels, 3)
    values over the samples, in sample order: bit for bit what the full path's sum over the
    samples gives."""
    out = values[0].copy()
    for k in range(1, len(values)):
        combine(out, values[k], out=out)
    return out


def _neighbourhood(values: np.ndarray, combine: np.ufunc) -> np.ndarray:
    """``combine`` (np.minimum or np.maximum) of each pixel's 3 x 3 neighbourhood, for (..., rows,
    columns, channels) arrays; the image's border pixels have fewer neighbours."""
    # Each row's pixels as one run of columns x channels: the neighbour across is ``channels`` values
    # along it, so every step combines long contiguous runs.
    channels = values.shape[-1]
    values = np.ascontiguousarray(values).reshape(*values.shape[:-2], -1)
    out = values.copy()
    combine(out[..., 1:, :], values[..., :-1, :], out=out[..., 1:, :])
    combine(out[..., :-1, :], values[..., 1:, :], out=out[..., :-1, :])
    rows = out.copy()
    combine(out[..., channels:], rows[..., :-channels], out=out[..., channels:])
    combine(out[..., :-channels], rows[..., channels:], out=out[..., :-channels])
    return out.reshape(*out.shape[:-1], -1, channels)


def _slots_seeing_body(ctx: _Context, y0: int, y1: int) -> np.ndarray | None:
    """The pixels of the band of rows [y0, y1) (slots, from its first pixel) whose eye rays can
    meet the body, where the others add nothing (a black background or a transparent film): those
    outside ``body_box.screen_window``. None: every pixel."""
    if ctx.window is None or (ctx.background_seen and ctx.world_seen):
        return None
    first_col, last_col, first_row, last_row = ctx.window
    rows = np.arange(max(y0, first_row), min(y1, last_row + 1)) - y0
    cols = np.arange(first_col, last_col + 1)
    return (rows[:, None] * ctx.camera.width + cols).ravel()


def _trace_rays(ctx: _Context, band: _Band, o: np.ndarray, d: np.ndarray, slots: np.ndarray | None = None) -> None:
    """Trace eye rays ``o, d`` (ray i adds to slot i of ``band``, or to ``slots[i]``) to the end of
    every branch."""
    band.segments += len(o)
    rays = _first_hits(ctx, band, o, d, np.arange(len(o)) if slots is None else slots)
    depth = 1
    while len(rays) and depth < MAX_DEPTH:
        band.segments += len(rays)
        rays = _step(ctx, band, rays)
        depth += 1
    band.max_depth = depth


def _first_hits(ctx: _Context, band: _Band, o: np.ndarray, d: np.ndarray, pix: np.ndarray) -> _Rays:
    """Classify the eye rays (paper §3.1), ray i of the band's slot ``pix[i]``: background, body,
    or lens (①)."""
    n = len(o)
    if ctx.wraps:
        return _first_hits_wrapped(ctx, band, o, d, pix)
    t_near, t_far, face = body_box.hit_box(o, d, ctx.box_lo, ctx.box_hi)
    hit_box = (t_near <= t_far) & (t_near > 0)

    if ctx.background_seen and ctx.world_seen:
        band.add(BACKGROUND_PASS, pix[~hit_box], ctx.sky(d[~hit_box]))

    # Only rays entering the front face can reach a lens: find their points there.
    front = np.nonzero(hit_box & (face == 1) & (d[:, 1] > 0))[0]
    p = rows(o, front) + t_near[front, None] * rows(d, front)
    L = ctx.lamps
    lamp_front = outer_face.lens_at(p[:, 0], p[:, 2], L)
    lamp = np.full(n, -1)
    lamp[front] = lamp_front
    on_lens = lamp >= 0
    on_body = hit_box & ~on_lens

    # Body: equation (1) with the face's outward normal.
    b = np.nonzero(on_body)[0]
    normal = np.zeros((len(b), 3))
    normal[np.arange(len(b)), face[b]] = -np.sign(d[b, face[b]])
    body = ctx.body
    band.add(BODY_PASS, pix[b], ctx.shade(normal, -rows(d, b), np.asarray(body["color"]), body["specular"],
                                          body["shininess"]))

    # Lens outer face (①): Fresnel split; the reflected branch is shaded by eq. (1) (§3.2.3).
    s = np.nonzero(on_lens)[0]
    li = lamp[s]
    ds = rows(d, s)
    local = p[lamp_front >= 0] - np.stack([L.center[li, 0], np.zeros(len(s)), L.center[li, 1]], axis=1)
    local[:, 1] = 0.0
    return _into_lenses(ctx, band, pix[s], li, ds, np.tile(outer_face.NORMAL, (len(s), 1)), ds[:, 1], local)


def _into_lenses(ctx: _Context, band: _Band, s: np.ndarray, li: np.ndarray, ds: np.ndarray,
                 face_normal: np.ndarray, cos_i: np.ndarray, local: np.ndarray) -> _Rays:
    """Eye rays ``s`` meeting the outer face of lamps ``li`` (①) at ``local`` (lamp frame) with the
    face's outward ``face_normal``: the Fresnel split, the reflected branch shaded by eq. (1) and
    mirroring the surroundings (§3.2.3), the transmitted rays into the lens."""
    L = ctx.lamps
    ior = L.ior[li]
    r = optics.fresnel_reflectance(cos_i, 1.0, ior)
    surface = ctx.shade(face_normal, -ds, L.lens_diffuse[li], L.lens_specular[li], L.lens_shininess[li])
    if ctx.environment is not None:  # the outer face mirrors the surroundings
        surface = surface + ctx.sky(optics.reflect(ds, face_normal))
    band.add(LENS_SURFACE, s, r[:, None] * surface)
    if ctx.background_seen and ctx.environment is None:
        band.add(BACKGROUND_PASS, s, r[:, None] * ctx.background)
    ones = np.ones(len(s), dtype=np.int8)
    band.note(s, ones, ones * P.REFLECTED, ones * P.LENS_OUTER_TO_OUTSIDE)

    k = np.repeat((1.0 - r)[:, None], 3, axis=1)
    d_in = optics.refract(ds, face_normal, 1.0 / ior)
    rays = _Rays(pix=s, lamp=li, o=local, d=d_in, k=k, medium=np.full(len(s), P.IN_LENS, np.int8),
                 src=np.full(len(s), P.OUTER, np.int8),
                 parent=np.full(len(s), P.OUTSIDE_TO_LENS, np.int8) if ctx.record else UNRECORDED,
                 branch=np.full(len(s), P.TRANSMITTED, np.int8) if ctx.record else UNRECORDED,
                 seen_reflector=np.zeros(len(s), bool))
    return rays.take(_alive(k))


def _first_hits_wrapped(ctx: _Context, band: _Band, o: np.ndarray, d: np.ndarray, pix: np.ndarray) -> _Rays:
    """``_first_hits`` for a body whose front curves round to the side (cylindrical lenses): the
    same classification, with the curved panel's normals and the cylindrical outer faces'."""
    n = len(o)
    t_near, hit_body, face, normal = body_box.hit_body(o, d, ctx.box_lo, ctx.box_hi, ctx.wraps)
    if ctx.background_seen and ctx.world_seen:
        band.add(BACKGROUND_PASS, pix[~hit_body], ctx.sky(d[~hit_body]))
    front = np.nonzero(hit_body & (((face == 1) & (d[:, 1] > 0)) | (face == body_box.CURVED_FRONT)))[0]
    p = rows(o, front) + t_near[front, None] * rows(d, front)
    L = ctx.lamps
    lamp = np.full(n, -1)
    lamp[front] = outer_face.lens_at(p[:, 0], p[:, 2], L)
    on_lens = lamp >= 0
    b = np.nonzero(hit_body & ~on_lens)[0]
    body = ctx.body
    band.add(BODY_PASS, pix[b], ctx.shade(rows(normal, b), -rows(d, b), np.asarray(body["color"]), body["specular"],
                                           body["shininess"]))

    s = np.nonzero(on_lens)[0]
    li = lamp[s]
    ds = rows(d, s)
    local = o[s] + t_near[s, None] * ds - np.stack([L.center[li, 0], np.zeros(len(s)), L.center[li, 1]], axis=1)
    flat = L.cylindrical[li] == 0
    local[flat, 1] = 0.0
    face_normal = np.tile(outer_face.NORMAL, (len(s), 1))
    curved = np.nonzero(~flat)[0]
    face_normal[curved] = outward_normal(local[curved], L.cyl_axis_x[li[curved]], L.cyl_radius[li[curved]])
    cos_i = np.clip(-optics.dot(ds, face_normal), 0.0, 1.0)
    return _into_lenses(ctx, band, pix[s], li, ds, face_normal, cos_i, local)


# Per part that gives normals: its surface id, the rays it was given (None: all) and their normals.
_Normals = list[tuple[int, np.ndarray | None, np.ndarray]]


def _intersect(ctx: _Context, rays: _Rays) -> tuple[np.ndarray, np.ndarray, _Normals]:
    """Nearest surface of every ray among the parts its medium can reach (``parts.PARTS``, in
    order; ties keep the earlier part): (t, surface id, the normals out of the lens material that
    the parts gave, the lens faces': ``_normals_at`` reads those of the rays that need them)."""
    n = len(rays)
    t_best = np.full(n, np.inf)
    surface = np.full(n, P.NOTHING, np.int8)
    normals: _Normals = []
    reaching: dict[tuple[int, ...], tuple[np.ndarray | None, Segments]] = {}
    for media, run in _runs_of_media(ctx.parts):
        if media not in reaching:
            reaching[media] = _reaching(rays, media)
        idx, seg = reaching[media]
        if len(seg.o) == 0:
            continue
        # The nearest hits of the rays reaching this run of parts (the air's reflector, bulb and
        # socket), kept apart and updated in place: one gather and one scatter for the run.
        t_run = t_best if idx is None else t_best.take(idx)
        surface_run = surface if idx is None else surface.take(idx)
        for part in run:
            t, part_normal = part.intersect(seg, ctx.lamps, t_run)
            np.copyto(surface_run, part.SURFACE, where=t < t_run)
            # t where t < t_run: fmin is that select, the run's t never being NaN (it starts at inf
            # and only takes a part's t that is smaller), and faster than copyto with where=.
            np.fmin(t_run, t, out=t_run)
            if part_normal is not None:
                normals.append((part.SURFACE, idx, part_normal))
        if idx is not None:
            t_best[idx] = t_run
            surface[idx] = surface_run
    return t_best, surface, normals


def _runs_of_media(parts: tuple) -> list[tuple[tuple[int, ...], list]]:
    """``parts`` in order, those next to each other that the same media reach grouped: (media, parts)."""
    runs: list[tuple[tuple[int, ...], list]] = []
    for part in parts:
        if runs and runs[-1][0] == part.MEDIA:
            runs[-1][1].append(part)
        else:
            runs.append((part.MEDIA, [part]))
    return runs


def _normals_at(normals: _Normals, m: np.ndarray, surface_m: np.ndarray) -> np.ndarray:
    """The normals (len(m), 3) where the segments ``m`` end, on the surfaces ``surface_m``: each
    from the part that surface is (the nearest part, so the last that gave the ray a normal)."""
    normal = np.zeros((len(m), 3))
    for sid, idx, part_normal in normals:
        sel = np.nonzero(surface_m == sid)[0]
        if len(sel) and part_normal.strides[0] == 0:  # one normal for all (the flat outer face)
            for axis in range(3):
                normal[sel, axis] = part_normal[0, axis]
        elif len(sel):
            at = m.take(sel) if idx is None else np.searchsorted(idx, m.take(sel))  # idx is sorted
            put_rows(normal, sel, rows(part_normal, at))
    return normal


def _reaching(rays: _Rays, media: tuple[int, ...]) -> tuple[np.ndarray | None, Segments]:
    """The rays travelling in one of ``media``: their indices (None for all) and their segments."""
    if {P.IN_LENS, P.IN_AIR} <= set(media):
        idx = None
    elif len(media) == 1:
        idx = np.nonzero(rays.medium == media[0])[0]
    else:  # the prism plate's parts: the air and the plate
        idx = np.nonzero(np.isin(rays.medium, media))[0]
    if idx is None or len(idx) == len(rays):
        return None, Segments(rays.o, rays.d, rays.lamp, rays.src, rays.medium)
    return idx, Segments(rows(rays.o, idx), rows(rays.d, idx), rays.lamp.take(idx), rays.src.take(idx),
                         rays.medium.take(idx))


def _step(ctx: _Context, band: _Band, rays: _Rays) -> _Rays:
    """Trace one generation: find each segment's end, add its luminance, spawn the children."""
    L = ctx.lamps
    t, surface, normals = _intersect(ctx, rays)
    # The path classes only feed the transitions a render records (``_Band.note``).
    cls = _path_class(rays.medium, rays.src, surface) if ctx.record else UNRECORDED
    band.note(rays.pix, rays.parent, rays.branch, cls)

    k = rays.k
    lens = np.nonzero(rays.medium == P.IN_LENS)[0]
    if len(lens):
        k = k.copy()
        put_rows(k, lens, rows(k, lens) * optics.absorption(rows(L.absorption, rays.lamp.take(lens)), t.take(lens)))
    plate = np.nonzero(rays.medium == P.IN_PLATE)[0] if ctx.plates else ()
    if len(plate):  # eq. (2) inside the prism plate too
        k = k.copy() if k is rays.k else k
        put_rows(k, plate, rows(k, plate) * optics.absorption(rows(L.plate_absorption, rays.lamp.take(plate)),
                                                              t.take(plate)))

    for sid, pass_id, color in ((P.WALL, SIDE_WALL_PASS, L.wall_color), (P.BULB, BULB_PASS, L.bulb_intensity),
                                (P.SOCKET, SOCKET_PASS, L.socket_color)):
        m = np.nonzero(surface == sid)[0]
        if len(m):
            band.add(pass_id, rays.pix.take(m), rows(k, m) * rows(color, rays.lamp.take(m)))

    m = np.nonzero(surface == P.HOUSING)[0] if ctx.plates else ()  # a plate lamp's housing ends the path
    if len(m):
        band.add(SIDE_WALL_PASS, rays.pix.take(m), rows(k, m) * rows(L.housing_color, rays.lamp.take(m)))

    # Only the rays that go on need their end point (their t is finite).
    children: list[_Rays] = []
    m = np.nonzero(surface == P.REFLECTOR)[0]
    if len(m):
        d, hit = _end_points(rays, t, m)
        children.append(_reflector(ctx, band, rays, m, rows(k, m), d, hit, cls.take(m)))
    m = np.nonzero((surface == P.OUTER) | (surface == P.CUT))[0]
    if len(m):
        d, hit = _end_points(rays, t, m)
        surface_m = surface.take(m)
        children.extend(_dielectric(ctx, band, rays, m, rows(k, m), d, hit, cls.take(m), surface_m,
                                    _normals_at(normals, m, surface_m)))
    m = np.nonzero((surface == P.PLATE_FRONT) | (surface == P.RINGS))[0] if ctx.plates else ()
    if len(m):
        d, hit = _end_points(rays, t, m)
        surface_m = surface.take(m)
        children.extend(_plate(rays, m, rows(k, m), d, hit, cls.take(m), surface_m, _normals_at(normals, m, surface_m),
                               L))
    if not children:
        return rays.take(np.zeros(0, dtype=np.int64))
    return _concat(children) if len(children) > 1 else children[0]


def _end_points(rays: _Rays, t: np.ndarray, m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The directions of the segments ``m`` and where they end: o + t d."""
    d = rows(rays.d, m)
    return d, rows(rays.o, m) + optics.scaled(d, t.take(m))


def _path_class(medium: np.ndarray, src: np.ndarray, surface: np.ndarray) -> np.ndarray:
    """``paths.CLASS_OF[medium, src, surface]`` as one flat look-up: numpy's indexing by three
    small-integer arrays is several times slower."""
    code = medium.astype(np.intp)
    code *= P.CLASS_OF.shape[1]
    code += src
    code *= P.CLASS_OF.shape[2]
    code += surface
    return P.CLASS_OF.take(code)


def _alive(k: np.ndarray) -> np.ndarray:
    """The branches whose accumulated attenuation is still above the cut-off in some channel."""
    return np.maximum(np.maximum(k[:, 0], k[:, 1]), k[:, 2]) >= CUTOFF


def _reflector(ctx: _Context, band: _Band, rays: _Rays, m: np.ndarray, k: np.ndarray, d: np.ndarray,
               hit: np.ndarray, cls: np.ndarray) -> _Rays:
    """A reflector hit (③ ④): the first-hit constant, Blinn's scatter (eq. 3), then the mirror ray
    where it stays above the cut-off."""
    L = ctx.lamps
    li = rays.lamp.take(m)
    pix = rays.pix.take(m)
    first = np.nonzero(~rays.seen_reflector.take(m))[0]
    band.add(REFLECTOR_CONSTANT, pix.take(first), rows(k, first) * rows(L.reflector_color, li.take(first)))
    normal = reflector.reflector_normal(hit, L.focal.take(li))
    to_bulb = optics.normalize(rows(L.bulb_center, li) - hit)
    scatter = optics.blinn(normal, -d, to_bulb, L.scatter.take(li), L.scatter_shininess.take(li))
    band.add(REFLECTOR_SCATTER, pix, optics.scaled(k, scatter) * rows(L.bulb_intensity, li))
    if ctx.phantom:  # the sun's light scattered back out of the lamp (sunlight.phantom)
        band.add(REFLECTOR_SCATTER, pix, k * sunlight.phantom(ctx.sun, ctx.phantom_lamps, li, hit, normal, -d))
    k = optics.scaled(k, L.reflectance.take(li))
    go = np.nonzero(_alive(k))[0]
    n = len(go)
    return _Rays(pix=pix.take(go), lamp=li.take(go), o=rows(hit, go), d=optics.reflect(rows(d, go), rows(normal, go)),
                 k=rows(k, go), medium=np.full(n, P.IN_AIR, np.int8), src=np.full(n, P.REFLECTOR, np.int8),
                 parent=cls.take(go), branch=_tags(cls, P.REFLECTED, n), seen_reflector=np.ones(n, bool))


def _dielectric(ctx: _Context, band: _Band, rays: _Rays, m: np.ndarray, k: np.ndarray, d: np.ndarray,
                hit: np.ndarray, cls: np.ndarray, surface: np.ndarray, out_normal: np.ndarray) -> list[_Rays]:
    """A lens surface hit from either side: Fresnel split into the reflected and transmitted rays
    that stay above the cut-off; ``out_normal`` points out of the lens material (-y on the outer
    face, the cap's on the cuts)."""
    L = ctx.lamps
    li = rays.lamp.take(m)
    pix = rays.pix.take(m)
    medium = rays.medium.take(m)
    seen = rays.seen_reflector.take(m)
    from_lens = medium == P.IN_LENS
    # Toward the incident side: the normal negated for rays inside the lens (a sign flip is exact).
    facing = optics.scaled(out_normal, np.where(from_lens, -1.0, 1.0))
    cos_facing = -optics.dot(d, facing)
    cos_i = np.clip(cos_facing, 0.0, 1.0)
    ior = L.ior.take(li)
    n1 = np.where(from_lens, ior, 1.0)
    n2 = np.where(from_lens, 1.0, ior)
    r = optics.fresnel_reflectance(cos_i, n1, n2)
    src = surface  # OUTER or CUT: the surface hit is where the children start
    k_r = optics.scaled(k, r)
    go = np.nonzero(_alive(k_r))[0]
    # The mirror ray, optics.reflect(d, facing) with d·facing = -cos_facing known already.
    d_r = optics.normalize(rows(d, go) + optics.scaled(rows(facing, go), 2.0 * cos_facing.take(go)))
    out = [_Rays(pix=pix.take(go), lamp=li.take(go), o=rows(hit, go), d=d_r, k=rows(k_r, go),
                 medium=medium.take(go), src=src.take(go), parent=cls.take(go),
                 branch=_tags(cls, P.REFLECTED, len(go)), seen_reflector=seen.take(go))]
    k_t = optics.scaled(k, 1.0 - r)
    partial = r < 1.0
    if ctx.background_seen or ctx.record:
        # ⑩: out through the outer face, to the background (ends).
        lv = np.nonzero(partial & (surface == P.OUTER))[0]
        if ctx.background_seen:
            d_lv = rows(d, lv)
            out_d = (optics.refract(d_lv, rows(facing, lv), n1.take(lv) / n2.take(lv))
                     if ctx.environment is not None else d_lv)
            band.add(BACKGROUND_PASS, pix.take(lv), rows(k_t, lv) * ctx.sky(out_d))
        if ctx.record:
            band.note(pix.take(lv), cls.take(lv), np.full(len(lv), P.TRANSMITTED),
                      np.full(len(lv), P.LENS_OUTER_TO_OUTSIDE))
    # The transmitted rays into the lens or out of it at a cut, above the cut-off.
    tc = np.nonzero(partial & (surface != P.OUTER) & _alive(k_t))[0]
    if len(tc):
        eta = n1.take(tc) / n2.take(tc)
        out.append(_Rays(pix=pix.take(tc), lamp=li.take(tc), o=rows(hit, tc),
                         d=optics.refract(rows(d, tc), rows(facing, tc), eta, cos_facing.take(tc)),
                         k=rows(k_t, tc), medium=np.where(from_lens.take(tc), np.int8(P.IN_AIR), np.int8(P.IN_LENS)),
                         src=src.take(tc), parent=cls.take(tc), branch=_tags(cls, P.TRANSMITTED, len(tc)),
                         seen_reflector=seen.take(tc)))
    return out


def _plate(rays: _Rays, m: np.ndarray, k: np.ndarray, d: np.ndarray, hit: np.ndarray, cls: np.ndarray,
           surface: np.ndarray, out_normal: np.ndarray, L: LampTable) -> list[_Rays]:
    """A prism-plate face hit from either side (README, the prism plate): the Fresnel split of
    the lens's faces (docs/model.md §5) with the plate's index; ``out_normal`` points out of the plate
    material. Nothing leaves the lamp here, so both branches go on where above the cut-off."""
    scaled = optics.scaled
    li = rays.lamp.take(m)
    medium = rays.medium.take(m)
    from_plate = medium == P.IN_PLATE
    # toward the incident side: the normal negated for rays inside the plate (a sign flip is exact)
    facing = scaled(out_normal, np.where(from_plate, -1.0, 1.0))
    cos_i = np.clip(-optics.dot(d, facing), 0.0, 1.0)
    ior = L.plate_ior.take(li)
    n1 = np.where(from_plate, ior, 1.0)
    n2 = np.where(from_plate, 1.0, ior)
    r = optics.fresnel_reflectance(cos_i, n1, n2)
    pix, seen = rays.pix.take(m), rays.seen_reflector.take(m)
    k_r = scaled(k, r)
    go = np.nonzero(_alive(k_r))[0]
    out = [_Rays(pix=pix[go], lamp=li[go], o=rows(hit, go), d=optics.reflect(rows(d, go), rows(facing, go)),
                 k=rows(k_r, go), medium=medium[go], src=surface[go], parent=cls[go],
                 branch=_tags(cls, P.REFLECTED, len(go)), seen_reflector=seen[go])]
    k_t = scaled(k, 1.0 - r)
    tc = np.nonzero((r < 1.0) & _alive(k_t))[0]
    if len(tc):
        into = ~from_plate[tc]
        eta = np.where(into, 1.0 / ior[tc], ior[tc])  # n1 / n2: 1 / n into the plate, n / 1 out of it
        d_t = optics.refract(rows(d, tc), rows(facing, tc), eta)
        out.append(_Rays(pix=pix[tc], lamp=li[tc], o=rows(hit, tc), d=d_t, k=rows(k_t, tc),
                         medium=np.where(into, P.IN_PLATE, P.IN_AIR).astype(np.int8),
                         src=surface[tc], parent=cls[tc], branch=_tags(cls, P.TRANSMITTED, len(tc)),
                         seen_reflector=seen[tc]))
    return out

"""Bands of rows and who traces them: one after another, on threads of this process with the
deep branches of each carried into the next (``carried``), or handed to a ``band_pool``'s worker
processes; either way they come back in the image's order (``InOrder``).
"""

from __future__ import annotations

import queue
import sys
import threading
from collections import deque
from collections.abc import Callable, Iterator
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from ..camera import eye_rays
from . import sampling
from .adaptive import sample_rays
from .carried import carrying_samples, carrying_tails
from .context import Context
from .eyes import slots_seeing_body
from .rays import Band
from .sampling import pilot_samples, traced_at_once
from .walk import trace_rays


class RenderCancelled(Exception):
    """Raised when ``should_stop()`` asked the render to stop."""


class BandsElsewhere(Protocol):
    """Traces a render's bands out of this process (``band_pool.BandPool``)."""

    def traced_bands(self, scene: dict, width: int, height: int, options: dict, bands: list[tuple[int, int]],
                     workers: int, should_stop: Callable[[], bool],
                     fallback: Callable[[list[tuple[int, int]]], Iterator[tuple[int, int, BandImage]]],
                     ) -> Iterator[tuple[int, int, BandImage]]: ...


def band_rows(ctx: Context) -> list[tuple[int, int]]:
    """The image's bands of rows, (y0, y1) each, top first."""
    width, height, samples = ctx.camera.width, ctx.camera.height, ctx.samples
    # Adaptive sampling traces the pilot samples of a band at once, then those of its neighbours in
    # the rows above and below it that it needs, then the rest of its busy pixels. The band and those
    # two rows fit one group of rays.
    if ctx.adaptive_threshold > 0 and len(pilot_samples(samples)) < samples:
        rows_per_band = max(1, sampling.TILE_RAYS // (width * len(pilot_samples(samples))) - 2)
    else:
        rows_per_band = max(1, sampling.TILE_RAYS // (width * samples))
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
    cut_at_depth: int = 0  # branches ended at the depth limit (``Band.cut_at_depth``)

    @classmethod
    def of(cls, band: Band, keep_passes: bool) -> BandImage:
        """``band``'s image and passes (R, G, B; photometric: CIE XYZ in cd/m², ``Band.add``)."""
        acc = band.acc
        # the passes summed in float64, then stored in float32: as the image always was
        return cls(acc.sum(axis=0).astype(np.float32), acc.astype(np.float32) if keep_passes else None,
                   band.segments, band.busy, band.max_depth, band.transitions, cut_at_depth=band.cut_at_depth)


def worker_bands(ctx: Context, take: Callable[[], tuple[int, int, int] | None],
                 stopped: Callable[[], bool]) -> Iterator[tuple[int, Band]]:
    """One worker's bands, taken one by one from ``take()`` ((index, y0, y1), None when there are
    no more) and yielded as (index, band) as each completes, the deep branches of each band (or
    group of samples) traced along with the next one's rays; ``stopped()`` ends the work within a
    generation."""
    yield from (carrying_tails if ctx.samples == 1 else carrying_samples)(ctx, take, stopped)


def never() -> bool:
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


def traced_bands(ctx: Context, bands: list[tuple[int, int]], threads: int,
                  should_stop: Callable[[], bool]) -> Iterator[tuple[int, int, Band]]:
    """Trace the bands, at most ``threads`` at a time (in the calling thread when 1), and yield
    them in order; ``should_stop()`` is polled before starting a band and after each finishes
    (with one sample per pixel, before the first and as each completes: ``_carried_bands``)."""
    traced = _carried_bands if ctx.samples == 1 else bands_on_threads
    if threads > 1:
        with short_switch_interval():
            yield from traced(ctx, bands, threads, should_stop)
    else:
        yield from traced(ctx, bands, 1, should_stop)


def bands_on_threads(ctx: Context, bands: list[tuple[int, int]], threads: int,
                     should_stop: Callable[[], bool]) -> Iterator[tuple[int, int, Band]]:
    """The ``bands`` each traced alone (``trace_band``), at most ``threads`` at a time (in the
    calling thread when 1), yielded in order; ``should_stop()`` is polled before starting a band
    and after each finishes."""
    pool = ThreadPoolExecutor(max_workers=threads) if threads > 1 else None
    pending, running = deque(bands), deque()
    try:
        while pending or running:
            while pending and len(running) < threads:
                if should_stop():
                    raise RenderCancelled("render cancelled")
                y0, y1 = pending.popleft()
                running.append((y0, y1, pool.submit(trace_band, ctx, y0, y1) if pool else trace_band(ctx, y0, y1)))
            y0, y1, band = running.popleft()
            band = band.result() if pool else band
            if should_stop():
                raise RenderCancelled("render cancelled")
            yield y0, y1, band
    finally:
        if pool is not None:
            pool.shutdown(wait=True, cancel_futures=True)


def _carried_bands(ctx: Context, bands: list[tuple[int, int]], threads: int,
                   should_stop: Callable[[], bool]) -> Iterator[tuple[int, int, Band]]:
    """``traced_bands`` with tails carried (``carrying_tails``): each of ``threads`` workers
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
            completed = carrying_tails(ctx, take, never)
        else:
            completed = _completed_on(pool, threads, lambda: carrying_tails(ctx, take, stop.is_set))
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
                  worker: Callable[[], Iterator[tuple[int, Band]]]) -> Iterator[tuple[int, Band]]:
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


def trace_band(ctx: Context, y0: int, y1: int) -> Band:
    """The rows ``y0:y1`` traced alone, to the end of every branch."""
    cam = ctx.camera
    pixels = np.arange(y0 * cam.width, y1 * cam.width)
    band = Band(len(pixels), ctx)
    if ctx.samples == 1:  # the paper's setting: one ray through each pixel centre
        slots = slots_seeing_body(ctx, y0, y1)
        if slots is None:
            trace_rays(ctx, band, *eye_rays(cam, pixels))
        else:  # the others add nothing (black background, or a film): their eye rays still count as segments
            band.segments += len(pixels) - len(slots)
            band.max_depth = 1
            if len(slots):
                trace_rays(ctx, band, *eye_rays(cam, pixels[slots]), slots)
        return band
    traced_at_once(ctx, sample_rays(ctx, band, y0, y1))
    return band

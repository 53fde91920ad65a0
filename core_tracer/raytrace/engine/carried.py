"""Carried wavefronts: the last few branches of a band (or of a group of samples) traced along
with the next one's rays, so that a worker never traces a band's deep branches alone
(``carrying_tails``, ``carrying_samples``).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Iterator
from dataclasses import dataclass, replace

import numpy as np

from ..camera import eye_rays
from . import walk
from .adaptive import sample_rays
from .context import Context
from .eyes import put_traced, rays_toward_body, slots_seeing_body
from .rays import Band, Rays, concat, no_rays
from .sampling import Requests

# Below this many live rays, a worker stops tracing its band alone: the rays left (the band's deep
# branches) are carried into the wavefront of the next band it takes (benchmarks/bench_viewport.py).
CARRY_RAYS = 4096


@dataclass
class _Tail:
    """A band of rows whose branches are being traced, and where its slots are in the wavefront."""

    index: int  # the band's place in the image's list of bands
    first_pixel: int  # the image index of the band's first pixel
    band: Band
    lo: int  # its slots in the wavefront's accumulator: lo:hi
    hi: int
    pixels: np.ndarray | None = None  # the band's pixels (image indices) at those slots; None: all, in order
    depth: int = 1  # generations traced, counted as ``trace_rays`` does

    def image_pixels(self, slots: np.ndarray) -> np.ndarray:
        return slots - self.lo + self.first_pixel if self.pixels is None else self.pixels[slots - self.lo]

    def put_back(self, acc: np.ndarray) -> None:
        """Copy the passes of the pixels carried in ``acc`` back to the band's own accumulator."""
        if self.pixels is not None:
            self.band.acc[:, self.pixels - self.first_pixel] = acc[:, self.lo:self.hi]


class _Wavefront(Band):
    """The passes of the rays one worker traces together: each band in ``tails`` owns the slots
    ``lo:hi`` of ``acc`` (the band just started all its pixels, an earlier band the pixels its
    carried rays can still reach), so ``add`` needs no splitting; transitions go to their band."""

    def __init__(self, ctx: Context, acc: np.ndarray, tails: list[_Tail]):
        super().__init__(acc.shape[1], ctx, acc)
        self.tails = tails

    def note(self, pix: np.ndarray, parent: np.ndarray, branch: np.ndarray, child: np.ndarray) -> None:
        if self.record and len(child):
            for tail in self.tails:
                sel = np.nonzero((pix >= tail.lo) & (pix < tail.hi))[0]
                tail.band.note(pix[sel], parent[sel], branch[sel], child[sel])


def carrying_tails(ctx: Context, take: Callable[[], tuple[int, int, int] | None],
                    stopped: Callable[[], bool]) -> Iterator[tuple[int, Band]]:
    """One worker's bands (``take()`` gives the next band's (index, y0, y1), None when there are no
    more), yielded as (index, band) as each band's last branch ends, not necessarily in order.

    Why carried: a band's last generations trace a few deep branches each (total internal
    reflections in clear lenses), many numpy calls on a few rays each, too short to release the GIL,
    so a second thread all but stops while one thread finishes a band alone. Once fewer than
    ``CARRY_RAYS`` rays are left, the worker starts its next band and traces those rays in the same
    generations, first; only its last band's tail is traced alone. Every value is the same bit for
    bit as tracing the bands apart: every operation on the rays is row by row, a band's rays keep
    their order among the others, each band sums into its own slots in ray order (``add_to_pass``),
    and each band counts its own depth (it stops at ``walk.depth_limit`` as it would alone)."""
    tails: list[_Tail] = []
    wave: _Wavefront | None = None
    rays: Rays | None = None
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
            ended, counts, rays = _end_tails(tails, wave, rays, walk.depth_limit(ctx))
            for tail in ended:
                yield tail.index, tail.band
            if not tails or (more and len(rays) < CARRY_RAYS):
                break
            counts = _rays_per_tail(tails, rays.pix) if ended else counts
            for tail, count in zip(tails, counts, strict=True):
                tail.band.segments += count
                tail.depth += 1
            rays = walk.next_generation(ctx, wave, rays)


def _end_tails(tails: list[_Tail], wave: _Wavefront, rays: Rays, limit: int) -> tuple[list[_Tail], list[int], Rays]:
    """Take out of ``tails`` the bands (or groups) whose branches have all ended, or reached
    the depth ``limit`` (``walk.depth_limit``, as ``trace_rays``'s loop ends): their passes go back
    to their own accumulators and the rays of those cut at the depth leave the wavefront. Returns
    them, every tail's count of rays before (``_rays_per_tail``) and the rays left."""
    counts = _rays_per_tail(tails, rays.pix)
    ended = [(tail, count) for tail, count in zip(tails, counts, strict=True)
             if count == 0 or tail.depth >= limit]
    for tail, count in ended:
        tails.remove(tail)
        tail.put_back(wave.acc)
        tail.band.max_depth = tail.depth
        if count:  # the depth limit: its rays go no further
            tail.band.cut_at_depth += count
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


def _next_wavefront(ctx: Context, tails: list[_Tail], wave: _Wavefront | None, rays: Rays | None,
                    index: int, y0: int, y1: int) -> tuple[_Wavefront, Rays]:
    """The wavefront of the band ``index`` (rows y0:y1) and of the rays carried from ``wave``: the
    pixels those rays can still reach come first (their passes copied from their bands), then the
    new band's; the carried rays come first, then the new band's eye rays' first branches."""
    width = ctx.camera.width
    pixels = np.arange(y0 * width, y1 * width)
    wave, parts = _carried_wavefront(ctx, tails, wave, rays, index, y0 * width, len(pixels))
    band, first_slot = tails[-1].band, tails[-1].lo
    slots = slots_seeing_body(ctx, y0, y1)
    if slots is None:
        slots = np.arange(len(pixels))
    else:  # the others add nothing (black background, or a film): their eye rays still count as segments
        band.segments += len(pixels) - len(slots)
    band.segments += len(slots)
    if len(slots):
        parts.append(walk.first_generation(ctx, wave, *eye_rays(ctx.camera, pixels[slots]), first_slot + slots))
    if not parts:
        return wave, no_rays()
    return wave, concat(parts) if len(parts) > 1 else parts[0]


def _carried_wavefront(ctx: Context, tails: list[_Tail], wave: _Wavefront | None, rays: Rays | None, index: int,
                       first_pixel: int, n: int) -> tuple[_Wavefront, list[Rays]]:
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
    n_carried = len(carried_pixels)
    acc = np.zeros((ctx.planes.count, n_carried + n, ctx.pass_channels))
    for tail in tails:
        tail.lo, tail.hi = np.searchsorted(carried_pixels, [tail.first_pixel, tail.first_pixel + tail.band.n])
        tail.pixels = carried_pixels[tail.lo:tail.hi]
        acc[:, tail.lo:tail.hi] = tail.band.acc[:, tail.pixels - tail.first_pixel]
    tails.append(_Tail(index, first_pixel, Band(n, ctx, acc[:, n_carried:]), n_carried, n_carried + n))
    wave = _Wavefront(ctx, acc, tails)
    return wave, [replace(rays, pix=np.searchsorted(carried_pixels, image_pix))] if n_carried else []


@dataclass
class _Group:
    """A group of eye rays a band's sampling asked for (``sample_rays``), being traced."""

    index: int  # the band's place in the image's list of bands
    band: Band
    requests: Requests  # the band's sampling, sent ``rays`` once traced
    rays: Band  # every ray's slot, those that miss the body's box already looked up
    toward: np.ndarray | None  # the rays traced (``rays_toward_body``; None: all), in the wavefront's tail
    o: np.ndarray  # their origins and directions
    d: np.ndarray


def carrying_samples(ctx: Context, take: Callable[[], tuple[int, int, int] | None],
                      stopped: Callable[[], bool]) -> Iterator[tuple[int, Band]]:
    """``carrying_tails`` for more than one sample per pixel: one worker's bands (``take()`` gives
    the next band's (index, y0, y1), None when there are no more), yielded as (index, band) as each
    band's sampling ends, not necessarily in order.

    A band's sampling asks for groups of eye rays one after another (``sample_rays``: adaptive
    sampling its pilot samples, then, once those are traced, the rest of its busy pixels' samples).
    Once fewer than ``CARRY_RAYS`` rays are left in the wavefront, the next group starts in it: a
    group a band asked for when its last one ended, else the first of the next band taken. So the
    deep branches of one group share their generations with the next group's rays; only the worker's
    last group's tail is traced alone. Bit for bit as tracing each group alone
    (``traced_at_once``), as ``carrying_tails`` is: each group has its own slots (one per ray) and
    counts its own depth."""
    tails: list[_Tail] = []
    tracing: dict[int, _Group] = {}  # by their tails' index
    ready: deque[_Group] = deque()
    wave: _Wavefront | None = None
    rays = no_rays()
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
                    band = Band((y1 - y0) * ctx.camera.width, ctx)
                    yield from _ask(ctx, index, band, sample_rays(ctx, band, y0, y1), None, ready)
                continue
            group = ready.popleft()
            n = len(group.o)
            wave, parts = _carried_wavefront(ctx, tails, wave, rays, next_slot, next_slot, n)
            tracing[next_slot] = group
            tail = tails[-1]
            tail.band.segments += n
            parts.append(walk.first_generation(ctx, wave, group.o, group.d, tail.lo + np.arange(n)))
            rays = concat(parts) if len(parts) > 1 else parts[0]
            next_slot += n
        if not tails:
            return
        if stopped():
            return
        ended, counts, rays = _end_tails(tails, wave, rays, walk.depth_limit(ctx))
        for tail in ended:
            group = tracing.pop(tail.index)
            if group.toward is None:
                traced = tail.band
            else:
                traced = group.rays
                put_traced(traced, group.toward, tail.band)
            yield from _ask(ctx, group.index, group.band, group.requests, traced, ready)
        if ended:
            continue  # room for the next group, perhaps
        for tail, count in zip(tails, counts, strict=True):
            tail.band.segments += count
            tail.depth += 1
        rays = walk.next_generation(ctx, wave, rays)


def _ask(ctx: Context, index: int, band: Band, requests: Requests, traced: Band | None,
         ready: deque[_Group]) -> Iterator[tuple[int, Band]]:
    """Send ``traced`` (None: nothing yet) to the sampling of the band ``index`` and queue in
    ``ready`` the group of eye rays it asks for next; yields (index, band) when it asks for none."""
    while True:
        try:
            o, d = requests.send(traced)
        except StopIteration:
            yield index, band
            return
        rays = Band(len(o), ctx)
        toward = rays_toward_body(ctx, rays, o, d)
        if toward is None or len(toward):
            if toward is not None:
                o, d = o[toward], d[toward]
            ready.append(_Group(index, band, requests, rays, toward, o, d))
            return
        traced = rays  # every ray missed the body's box

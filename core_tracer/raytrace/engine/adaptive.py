"""Which samples a band traces: every sample of every pixel, or adaptive sampling, which traces
a few pilot samples everywhere and the rest only where those of a pixel's neighbourhood disagree
(``sample_rays``).
"""

from __future__ import annotations

import math

import numpy as np

from .. import pixel_filter
from ..camera import eye_rays
from ..parts import body_box
from ..parts.base import rows
from . import sampling
from .context import Context
from .edges import edge_samples, emitter_light, holding_edges, wanted
from .rays import BACKGROUND_PASS, Band
from .sampling import Requests, over_samples, pilot_samples, sample_groups

# Adaptive sampling's agreement, a fraction of a pixel's brightness: on the four-lamp preset at 16
# samples and 512x512 it leaves every pixel within 7e-4 of the image's peak (the mean within 1e-5
# of the image's mean) of taking all samples everywhere, while tracing about a third fewer segments
# (benchmarks/bench_samples.py, tests/raytrace/test_adaptive_sampling.py).
ADAPTIVE_THRESHOLD = 0.01


def sample_rays(ctx: Context, band: Band, y0: int, y1: int) -> Requests:
    """The samples of rows ``y0:y1`` into ``band``: adaptive sampling (``_trace_adaptive``), or every
    sample of every pixel."""
    if ctx.adaptive_threshold > 0 and len(pilot_samples(ctx.samples)) < ctx.samples:
        yield from _trace_adaptive(ctx, band, y0, y1)
        return
    pixels = np.arange(y0 * ctx.camera.width, y1 * ctx.camera.width)
    # Samples in groups of at most sampling.TILE_RAYS rays (a wide row at many samples takes several),
    # each ray counted in its own slot (pixel-major), summed per pixel in sample order: the same
    # sums whatever the threads.
    edging = wanted(ctx)  # edge samples asked for: the emitter pass's extremes kept (``edges``)
    low, high = np.full(len(pixels), np.inf), np.zeros(len(pixels))
    for count, o, d in sample_groups(ctx.camera, pixels, ctx.samples, ctx.filter_name):
        group = yield o, d
        per_ray = group.acc.reshape(ctx.planes.count, len(pixels), count, ctx.pass_channels)
        band.acc += over_samples(np.add, per_ray.transpose(2, 0, 1, 3))
        if edging:
            light = emitter_light(per_ray, sample_major=False)
            np.minimum(low, light.min(axis=0), out=low)
            np.maximum(high, light.max(axis=0), out=high)
        band.segments += group.segments
        band.max_depth = max(band.max_depth, group.max_depth)
        band.cut_at_depth += group.cut_at_depth
        band.transitions |= group.transitions
    # The samples are placed by the filter (importance sampling), so the pixel is their plain mean.
    band.acc /= ctx.samples
    if edging:
        yield from edge_samples(ctx, band, pixels, holding_edges(ctx, y1 - y0, low, high))


def _trace_adaptive(ctx: Context, band: Band, y0: int, y1: int) -> Requests:
    """Adaptive sampling of rows ``y0:y1`` (its eye rays asked for as ``sample_rays``). The pilot
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
    pilot_values = yield from sampling.per_sample(ctx, band, pixels, pilot)
    # Each pass's least and greatest pilot sample over the pixel's 3 x 3 neighbourhood, on the passes'
    # own planes (passes, rows, columns, channels): no transposed copies.
    shape = (ctx.planes.count, y1 - y0, width, ctx.pass_channels)
    low = _neighbourhood(over_samples(np.minimum, pilot_values).reshape(shape), np.minimum)
    high = _neighbourhood(over_samples(np.maximum, pilot_values).reshape(shape), np.maximum)
    per_pixel = (ctx.planes.count, -1, ctx.pass_channels)  # views of the same planes, a pixel per column
    pilot_mean = over_samples(np.add, pilot_values) / len(pilot)
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
        background = ctx.planes.of(BACKGROUND_PASS)
        world = busy & ~_any_but_background(high, background) & ~_any_but_background(low, background)
        busy &= ~world
        busy[_world_samples(ctx, band, pixels, np.flatnonzero(world), pilot, pilot_values)] = True
    busy = np.flatnonzero(busy)
    edging = wanted(ctx)  # edge samples asked for: the emitter pass's extremes kept (``edges``)
    if edging:
        light = emitter_light(pilot_values, sample_major=True)
        low, high = light.min(axis=0), light.max(axis=0)
    chunk = max(1, sampling.TILE_RAYS // len(rest))
    for c0 in range(0, len(busy), chunk):
        idx = busy[c0:c0 + chunk]
        traced = yield from sampling.per_sample(ctx, band, pixels[idx], rest)
        by_sample = {int(k): traced[i] for i, k in enumerate(rest)}
        by_sample.update({int(k): pilot_values[i][:, idx] for i, k in enumerate(pilot)})
        total = by_sample[0].copy()
        for k in range(1, ctx.samples):  # in sample order, as ``over_samples`` and the full path
            total += by_sample[k]
        band.acc[:, idx] = total / ctx.samples
        if edging:
            light = emitter_light(traced, sample_major=True)
            low[idx] = np.minimum(low[idx], light.min(axis=0))
            high[idx] = np.maximum(high[idx], light.max(axis=0))
    if edging:
        yield from edge_samples(ctx, band, pixels, holding_edges(ctx, y1 - y0, low, high))


def _spread(high: np.ndarray, low: np.ndarray) -> np.ndarray:
    """Per pixel of (passes, pixels, channels) neighbourhood extremes: the greatest spread over its passes
    and channels (some pass and channel spreads beyond a threshold exactly where this does)."""
    return np.maximum.reduce(high - low, axis=0).max(axis=1)


def _outside_rows(ctx: Context, band: Band, y0: int, y1: int, pilot: np.ndarray, low: np.ndarray,
                  high: np.ndarray, busy: np.ndarray, threshold: np.ndarray) -> Requests:
    """The band's first and last rows' neighbours just outside it (``_trace_adaptive``): their pilot
    samples traced next to the pixels there that are not busy yet, then those pixels' neighbourhood
    extremes ``low`` and ``high`` (passes, rows, columns, channels) widened by them and ``busy`` (per pixel of
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
    values = yield from sampling.per_sample(ctx, band, neighbours, pilot)
    least, most = over_samples(np.minimum, values), over_samples(np.maximum, values)
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


def _any_but_background(planes: np.ndarray, background: int) -> np.ndarray:
    """Per pixel of (planes, pixels, channels) ``planes``: whether a plane other than the background's
    (``background``; a render of light states has it hold all the surroundings, the body too, which
    ``_world_samples`` then finds by its box) is not 0."""
    found = np.zeros(planes.shape[1:], dtype=bool)
    for plane_id, plane in enumerate(planes):
        if plane_id != background:
            found |= plane != 0
    return found.any(axis=1)


def _world_samples(ctx: Context, band: Band, pixels: np.ndarray, idx: np.ndarray, pilot: np.ndarray,
                   pilot_values: np.ndarray) -> np.ndarray:
    """The samples other than the pilot ones of the pixels ``idx`` (indices into ``pixels``), whose
    neighbourhood's pilot samples saw only the world: an eye ray that misses the body's box sees
    just the world (``first_hits``), so where all of a pixel's rays miss it the world's radiance
    of each, summed with the pilot samples' in sample order, is the pixel (the values tracing them
    gives). Returns the indices of ``idx`` a ray of which meets the box after all: trace those."""
    rest = np.setdiff1d(np.arange(ctx.samples), pilot)
    chunk = max(1, sampling.TILE_RAYS // len(rest))
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
        by_sample = np.empty((ctx.samples, len(part), ctx.pass_channels))
        by_sample[rest] = ctx.sky_seen(d).reshape(len(rest), len(part), ctx.pass_channels)
        by_sample[pilot] = pilot_values[:, ctx.planes.of(BACKGROUND_PASS)][:, part]
        total = by_sample[0].copy()
        for k in range(1, ctx.samples):  # in sample order, as the traced pixels
            total += by_sample[k]
        seen = ~toward
        band.acc[ctx.planes.of(BACKGROUND_PASS), part[seen]] = total[seen] / ctx.samples
        band.segments += len(rest) * int(seen.sum())
        band.max_depth = max(band.max_depth, 1)
        met.append(part[toward])
    return np.concatenate(met) if met else np.zeros(0, dtype=np.int64)


def _near_body(ctx: Context, pixels: np.ndarray) -> np.ndarray:
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

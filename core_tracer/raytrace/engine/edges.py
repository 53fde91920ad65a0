"""Edge samples (issue 34, "clean bulb edges"): more samples where a pixel holds the edge of an
emitter's image. A bulb or an LED die seen through a lens's cuts and off the reflector makes many
images smaller than a pixel, hard-edged: a sample sees the source or not, and at N samples under
the 3-pixel filter that hit-or-miss is almost all of a lit lens's error. Light elsewhere is smooth.

After a band's samples are traced, a pixel *holds an edge* when its own samples of the emitter pass
(``BULB_PASS``: the bulb and the LED dies) disagree: the brightest is lit (at least ``EDGE_SHARE``
of the brightest source) and the dimmest below ``EDGE_CONTRAST`` of it. Those pixels (and their
neighbours within ``EDGE_REACH``) take K x N more samples (K: the scene's ``image.edge_samples``,
off by default; ``EDGE_SAMPLES`` suggested), placed by the filter on the stratified pattern of that
count (``pixel_filter.grid_offsets``), traced along the main branches only (``main_branches``: a lens
ray's tree is tens of segments, its main branches a few), and the emitter pass becomes a control
variate (``main_edge_samples``):

    L = mean_N(L_tree) - mean_N(L_main) + mean_{N + K N}(L_main)

Its expectation is the N samples' (the image's); only the noise changes. With ``MAIN_SHARE`` 0 the
edge samples are whole trees and each pixel the mean of its N + K N samples (no better than as many
samples everywhere on the four-lamp night preset: benchmarks/RESULTS.md, "Bulb edges").

A pixel that adaptive sampling left with its pilot samples has mean_N(L_tree) of those; the
neighbours taken are those inside the band (the rows just outside it are another band's).
"""

from __future__ import annotations

import numpy as np

from .. import pixel_filter
from ..camera import eye_rays
from .context import Context
from .rays import BULB_PASS, BY_PASS, Band
from .sampling import TILE_RAYS, Requests, over_samples, per_sample
from .walk import depth_limit, first_generation, next_generation

# The K a designer is offered first (``image.edge_samples``, 0 by default): more samples per sample where a
# pixel holds an emitter's edge (K = 1 would repeat the N samples: K >= 2). Chosen on the four-lamp night
# photometric preset at 8 samples
# (benchmarks/bench_bulb_edges.py, RESULTS.md).
EDGE_SAMPLES = 8
EDGE_CONTRAST = 0.5  # the dimmest sample of the emitter pass below this share of the brightest: an edge
EDGE_REACH = 0  # pixels: the neighbours of an edge pixel that take edge samples too
MAIN_SHARE = 0.3  # edge samples follow the branches of throughput k at least this (0: whole trees)
EDGE_SHARE = 0.05  # the brightest sample of the emitter pass at least this share of the brightest source: it matters


def wanted(ctx: Context) -> bool:
    """Whether this render takes edge samples: asked for (``image.edge_samples`` >= 2) with several
    samples a pixel, and the band keeping the passes (a walk that keeps each source's light apart,
    ``rays.BySource``, takes none: its images add up to a render without them)."""
    return ctx.edge_samples >= 2 and ctx.samples >= 2 and ctx.planes is BY_PASS


def emitter_light(values: np.ndarray, sample_major: bool) -> np.ndarray:
    """The emitter pass of per-sample ``values`` summed over its channels, (samples, pixels): from
    sample-major (samples, passes, pixels, channels) or pixel-major (passes, pixels, samples, channels)."""
    if sample_major:
        return values[:, BULB_PASS].sum(axis=-1)
    return values[BULB_PASS].sum(axis=-1).T


def brightest_source(ctx: Context) -> float:
    """The luminance of the brightest source (a lit bulb, an LED die head-on), its channels summed as
    ``emitter_light`` sums a sample's: a sample of it through the optics is that times the path's
    throughput."""
    lamps = ctx.lamps
    return float(max(lamps.bulb_radiance.sum(axis=1).max(initial=0.0),
                     lamps.led_radiance.sum(axis=1).max(initial=0.0) if ctx.leds else 0.0))


def holding_edges(ctx: Context, rows: int, low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """The pixels of a band of ``rows`` rows (flat indices) that take edge samples: those whose
    samples of the emitter pass span ``low`` to ``high`` with ``high`` at least ``EDGE_SHARE`` of the
    brightest source (the images that weigh: a path's throughput of that share or more) and ``low``
    below ``EDGE_CONTRAST`` of ``high``, and their neighbours within ``EDGE_REACH`` in the band."""
    mixed = (high > 0.0) & (high >= EDGE_SHARE * brightest_source(ctx)) & (low < EDGE_CONTRAST * high)
    near = mixed.reshape(rows, ctx.camera.width).copy()
    for _ in range(EDGE_REACH):
        grown = near.copy()
        grown[1:] |= near[:-1]
        grown[:-1] |= near[1:]
        near = grown.copy()
        near[:, 1:] |= grown[:, :-1]
        near[:, :-1] |= grown[:, 1:]
    return np.flatnonzero(near)


def edge_samples(ctx: Context, band: Band, pixels: np.ndarray, edges: np.ndarray) -> Requests:
    """Trace K x N more samples of the pixels ``pixels[edges]``, whose ``band.acc``
    holds the mean of their N samples, and make each the mean of all N + K N (module docstring).
    With ``MAIN_SHARE`` > 0 the edge samples follow the main branches only (``main_edge_samples``)."""
    if not wanted(ctx) or not len(edges):
        return
    if MAIN_SHARE > 0.0:
        main_edge_samples(ctx, band, pixels[edges], edges)
        return
    extra = ctx.edge_samples * ctx.samples
    ids = np.arange(extra)
    chunk = max(1, TILE_RAYS // extra)
    for c0 in range(0, len(edges), chunk):
        idx = edges[c0:c0 + chunk]
        traced = yield from per_sample(ctx, band, pixels[idx], ids, count=extra)
        band.acc[:, idx] = (band.acc[:, idx] * ctx.samples + over_samples(np.add, traced)) / (ctx.samples + extra)


def main_branches(ctx: Context, band: Band, o: np.ndarray, d: np.ndarray) -> None:
    """Trace the eye rays ``o, d`` (ray i into slot i of ``band``) along their main branches only: a
    ray whose throughput k (its greatest channel) falls below ``MAIN_SHARE`` ends there, with all
    its descendants (k only falls along a path: Fresnel factors and reflectances are at most 1)."""
    band.segments += len(o)
    rays = first_generation(ctx, band, o, d, np.arange(len(o)))
    depth, limit = 1, depth_limit(ctx)
    while len(rays) and depth < limit:
        rays = rays.take(rays.k.max(axis=1) >= MAIN_SHARE)
        band.segments += len(rays)
        rays = next_generation(ctx, band, rays)
        depth += 1


def _main_light(ctx: Context, band: Band, pixels: np.ndarray, samples: np.ndarray, count: int) -> np.ndarray:
    """The emitter pass (pixels, channels) summed over the samples ``samples`` (of the pattern of
    ``count``) of each of ``pixels``, traced along their main branches (``main_branches``)."""
    offsets = pixel_filter.grid_offsets(ctx.filter_name, pixels, samples, count, sample_major=True)
    o, d = eye_rays(ctx.camera, np.tile(pixels, len(samples)), offsets)
    traced = Band(len(o), ctx)
    main_branches(ctx, traced, o, d)
    band.segments += traced.segments
    return traced.acc[BULB_PASS].reshape(len(samples), len(pixels), ctx.pass_channels).sum(axis=0)


def main_edge_samples(ctx: Context, band: Band, pixels: np.ndarray, idx: np.ndarray) -> None:
    """Edge samples along the main branches (``main_branches``) of the pixels ``pixels`` (slots
    ``idx`` of ``band``): their N samples again and K N more, traced so, correct the emitter pass as a
    control variate, the N samples' whole-tree light keeping what the main branches leave out:

        L = mean_N(L_tree) - mean_N(L_main) + mean_{N + K N}(L_main)

    whose expectation is mean_N(L_tree)'s (the image's), the hit-or-miss of the main branches now
    averaged over (K + 1) N samples."""
    n, extra = ctx.samples, ctx.edge_samples * ctx.samples
    chunk = max(1, TILE_RAYS // (n + extra))
    for c0 in range(0, len(idx), chunk):
        part = slice(c0, c0 + chunk)
        main_n = _main_light(ctx, band, pixels[part], np.arange(n), n)
        main_more = _main_light(ctx, band, pixels[part], np.arange(extra), extra)
        band.acc[BULB_PASS, idx[part]] += (main_n + main_more) / (n + extra) - main_n / n

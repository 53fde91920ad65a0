"""Samples of pixels as eye rays: in groups of at most ``TILE_RAYS`` rays, placed by the pixel
filter (``pixel_filter``), traced (``walk``) and summed per pixel in sample order.

A band's sampling (``adaptive.sample_rays``) asks for its eye rays a group at a time: it yields a
group's origins and directions and is sent them traced (a fresh ``Band``, ray i in slot i). Nothing
else of a group depends on how it is traced: alone (``traced_at_once``) or in the wavefront of other
groups' rays (``carried.carrying_samples``).
"""

from __future__ import annotations

from collections.abc import Generator, Iterator

import numpy as np

from .. import pixel_filter
from ..camera import Camera, eye_rays
from .context import Context
from .rays import Band
from .walk import trace_eye_rays

TILE_RAYS = 65536  # eye rays per band of rows: bounds memory whatever the image size (benchmarks/bench_tracer.py)
PILOT_SAMPLES = 4  # samples per pixel traced first by adaptive sampling (``pilot_samples``)

Requests = Generator[tuple[np.ndarray, np.ndarray], Band, None]



def traced_at_once(ctx: Context, requests: Requests) -> None:
    """Trace each group of eye rays a band's sampling asks for alone (``trace_eye_rays``)."""
    group = None
    while True:
        try:
            o, d = requests.send(group)
        except StopIteration:
            return
        group = Band(len(o), ctx)
        trace_eye_rays(ctx, group, o, d)


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


def per_sample(ctx: Context, band: Band, pixels: np.ndarray, sample_ids: np.ndarray,
               count: int | None = None) -> Generator[tuple[np.ndarray, np.ndarray], Band, np.ndarray]:
    """Trace the samples ``sample_ids`` (of the pattern of ``count`` samples, None: the render's)
    of every pixel (asked for in groups of at most TILE_RAYS rays,
    whole pixels to a group, as ``sample_rays``): returns each ray's passes, sample-major (samples,
    passes, pixels, channels), so that one sample of every pixel is one block (a view of the traced group's
    passes when one group holds every pixel: no copy); the band's statistics take the rays' counts.
    Every ray has its own slot, so the order of the rays changes no value."""
    pattern = ctx.samples if count is None else count
    count = len(sample_ids)
    per_group = max(1, TILE_RAYS // count)
    values = None
    for i0 in range(0, len(pixels), per_group):
        group_pixels = pixels[i0:i0 + per_group]
        ray_pixels = np.tile(group_pixels, count)
        offsets = pixel_filter.grid_offsets(ctx.filter_name, group_pixels, sample_ids, pattern, sample_major=True)
        group = yield eye_rays(ctx.camera, ray_pixels, offsets)
        traced = group.acc.reshape(ctx.planes.count, count, len(group_pixels), ctx.pass_channels).transpose(1, 0, 2, 3)
        if len(group_pixels) == len(pixels):
            values = traced
        else:
            if values is None:
                values = np.empty((count, ctx.planes.count, len(pixels), ctx.pass_channels))
            values[:, :, i0:i0 + len(group_pixels)] = traced
        band.segments += group.segments
        band.max_depth = max(band.max_depth, group.max_depth)
        band.cut_at_depth += group.cut_at_depth
        band.transitions |= group.transitions
    return values


def over_samples(combine: np.ufunc, values: np.ndarray) -> np.ndarray:
    """``combine`` (np.add, np.minimum, np.maximum) of sample-major (samples, passes, pixels, channels)
    values over the samples, in sample order: bit for bit what the full path's sum over the
    samples gives."""
    out = values[0].copy()
    for k in range(1, len(values)):
        combine(out, values[k], out=out)
    return out

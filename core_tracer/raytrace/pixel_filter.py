"""Where a pixel's samples go: stratified, deterministic positions shaped by a pixel filter.

A pixel with N > 1 samples traces N eye rays through points around its centre and takes their
plain mean. The points are distributed by the pixel filter itself (importance sampling, as
Cycles does with its filter table), so the mean is the filter-weighted average of the image
around the pixel. The filter is separable: each axis maps a uniform number through the inverse
of the 1-D filter's cumulative distribution.

The uniform numbers are a Hammersley set of N points, stratified in x ((i + 1/2) / N) and in y
(the base-2 radical inverse of i), shifted toroidally by an amount that depends only on the
pixel's index (a hash, no random state): the same image on every run and with any number of
threads, and no repeating pattern from pixel to pixel that could show as moiré.
"""

from __future__ import annotations

from functools import cache

import numpy as np

# Cycles' default pixel filter is Blackman-Harris of width 1.5 px; its filter table doubles the
# width before evaluating the window, so the window spans offsets of -1.5 px to +1.5 px.
BLACKMAN_HARRIS_WIDTH = 1.5  # px, Cycles' "Pixel Filter" default
FILTERS = ("blackman-harris", "box")
DEFAULT_FILTER = "blackman-harris"
_TABLE_POINTS = 4097
_BUCKETS = 2**16  # equal buckets of the uniform numbers, a power of two (``offsets_of``)


def filter_support(name: str) -> float:
    """Half-width in pixels of the filter's support (offsets from the pixel centre)."""
    if name == "box":
        return 0.5
    if name == "blackman-harris":
        return BLACKMAN_HARRIS_WIDTH
    raise ValueError(f"unknown pixel filter {name!r}; allowed {', '.join(FILTERS)}")


def filter_weight(name: str, offset: np.ndarray) -> np.ndarray:
    """The 1-D filter at ``offset`` pixels from the centre (not normalised; 0 outside its support)."""
    half = filter_support(name)
    inside = np.abs(offset) <= half
    if name == "box":
        return inside.astype(np.float64)
    # Cycles' filter_func_blackman_harris with its width doubled: the four-term window over [-half, half].
    v = 2.0 * np.pi * (offset / (2.0 * half) + 0.5)
    w = 0.35875 - 0.48829 * np.cos(v) + 0.14128 * np.cos(2.0 * v) - 0.01168 * np.cos(3.0 * v)
    return np.where(inside, w, 0.0)


@cache
def _inverse_cdf_table(name: str) -> tuple[np.ndarray, np.ndarray]:
    """(cumulative distribution, offset) of the normalised 1-D filter, for ``np.interp``; made once
    per filter (the arrays are shared: never written)."""
    half = filter_support(name)
    x = np.linspace(-half, half, _TABLE_POINTS)
    f = filter_weight(name, x)
    cdf = np.concatenate([[0.0], np.cumsum((f[1:] + f[:-1]) * 0.5 * np.diff(x))])
    return cdf / cdf[-1], x


@cache
def _lookup_table(name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``_inverse_cdf_table`` with what finds a number's interval without a binary search: the
    slope of each interval (as ``np.interp`` computes it) and, for each of ``_BUCKETS`` equal
    buckets of [0, 1], the interval holding the bucket's start and whether another begins inside it."""
    cdf, x = _inverse_cdf_table(name)
    slopes = (x[1:] - x[:-1]) / (cdf[1:] - cdf[:-1])
    start = np.minimum(np.searchsorted(cdf, np.arange(_BUCKETS + 1) / _BUCKETS, side="right") - 1, len(slopes) - 1)
    return cdf, x, slopes, start[:-1], start[1:] != start[:-1]


def offsets_of(name: str, u: np.ndarray) -> np.ndarray:
    """Offsets in pixels whose density is the normalised filter, from uniform numbers ``u`` in [0, 1)."""
    if name == "box":
        return u - 0.5  # exact: the box's inverse distribution is linear
    cdf, x, slopes, start, split = _lookup_table(name)
    # np.interp(u, cdf, x), value for value: the interval j with cdf[j] <= u < cdf[j + 1] is the
    # bucket's own where the bucket lies inside one interval (most of them: u * 2^k is exact), found
    # by a binary search only where an interval ends inside the bucket; then np.interp's formula.
    bucket = (u * _BUCKETS).astype(np.int64)
    j = start.take(bucket)
    search = np.flatnonzero(split.take(bucket))
    if len(search):
        j[search] = np.minimum(np.searchsorted(cdf, u[search], side="right") - 1, len(slopes) - 1)
    return slopes.take(j) * (u - cdf.take(j)) + x.take(j)


def _radical_inverse_2(i: np.ndarray) -> np.ndarray:
    bits = i.astype(np.uint64)
    out = np.zeros(i.shape, dtype=np.float64)
    scale = 0.5
    while bits.any():
        out += (bits & np.uint64(1)).astype(np.float64) * scale
        bits = bits >> np.uint64(1)
        scale *= 0.5
    return out


def _hash_unit(index: np.ndarray, salt: int) -> np.ndarray:
    """A number in [0, 1) fixed by ``index`` and ``salt`` (splitmix64's finaliser)."""
    z = index.astype(np.uint64) * np.uint64(2) + np.uint64(salt) + np.uint64(0x9E3779B97F4A7C15)
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    z = z ^ (z >> np.uint64(31))
    return (z >> np.uint64(11)).astype(np.float64) / float(2**53)


def sample_offsets(name: str, pixels: np.ndarray, samples: np.ndarray, count: int) -> tuple[np.ndarray, np.ndarray]:
    """Offsets (dx right, dy down, in pixels) of sample ``samples[j]`` of ``count`` in pixel
    ``pixels[j]`` (global pixel indices)."""
    with np.errstate(over="ignore"):
        shift_x = _hash_unit(pixels, 1)
        shift_y = _hash_unit(pixels, 2)
    u = ((samples + 0.5) / count + shift_x) % 1.0
    v = (_radical_inverse_2(samples) + shift_y) % 1.0
    return offsets_of(name, u), offsets_of(name, v)


def grid_offsets(name: str, pixels: np.ndarray, samples: np.ndarray, count: int,
                 sample_major: bool) -> tuple[np.ndarray, np.ndarray]:
    """``sample_offsets`` of every sample ``samples`` of every pixel ``pixels``, flat: sample-major
    (ray s * len(pixels) + i is sample s of pixel i) or pixel-major (ray i * len(samples) + s).
    The same values, each pixel's shift and each sample's point computed once."""
    with np.errstate(over="ignore"):
        shift_x = _hash_unit(pixels, 1)
        shift_y = _hash_unit(pixels, 2)
    point_x = (samples + 0.5) / count
    point_y = _radical_inverse_2(samples)
    if sample_major:
        u = _wrapped(point_x[:, None] + shift_x)
        v = _wrapped(point_y[:, None] + shift_y)
    else:
        u = _wrapped(point_x + shift_x[:, None])
        v = _wrapped(point_y + shift_y[:, None])
    return offsets_of(name, u.reshape(-1)), offsets_of(name, v.reshape(-1))


def _wrapped(s: np.ndarray) -> np.ndarray:
    """``s % 1.0`` for sums ``s`` of two numbers in [0, 1), without numpy's slow float remainder: for
    s in [1, 2) both are s - 1, which is exact (Sterbenz), and s itself below 1."""
    s -= s >= 1.0
    return s

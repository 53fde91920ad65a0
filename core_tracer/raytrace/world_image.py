"""An environment image read within the memory budget: its header checked before any pixel is read,
its pixels read a strip of rows at a time straight into the padded layout the lookup uses, down-sampled
where it is larger than the world's share of the budget, and its values made finite.

The rules, each refused with one line naming the file (a ``SceneError`` on ``environment.file``):

- The header must declare a positive size of at most ``MAX_DECLARED_PIXELS`` (a 16384 x 8192 image)
  and at least one channel; a file whose header cannot be read is refused too. OpenImageIO's own
  messages are collected and put into that line, never printed.
- An image of more than ``MAX_PIXELS`` (8192 x 4096: its padded pixels, 16 bytes each, are an eighth
  of ``budget.MEMORY_BUDGET``) is area-averaged by a whole factor while it is read, to at most that.
- Radiance is finite and bounded: NaN and infinite pixels count as 0 (as Blender shows them black),
  and finite values are clamped to +-``MAX_RADIANCE`` (so that strength 10000 still leaves every
  sum in a float32 image finite).
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from ..scene.reading import SceneError
from ..scene.safe_text import printable

MAX_PIXELS = 8192 * 4096  # read at most this many pixels; larger images are area-averaged to it
MAX_DECLARED_PIXELS = 16384 * 8192  # a header declaring more is refused without reading on
MAX_RADIANCE = 1.0e9  # |pixel| after clamping (a real sun in an HDRI is below 1e6)
PADDED_BYTES = 16  # per pixel of the padded image: RGB and a 0, float32 (environment._padded)
STRIP_PIXELS = 1 << 20  # pixels of source read at once (and of the world's per-strip sums)
STRIP_BYTES_PER_PIXEL = 320  # the per-strip float64 temporaries (directions, weights, sums; measured: an
# 8192 x 4096 image peaks at 993 MB, its padded pixels 537 MB, the interpreter and OpenImageIO about 100)
FIELD = "environment.file"
LAYOUT = f"v1-{MAX_PIXELS}-{MAX_RADIANCE:g}"  # the reading rules: part of a cached image's name


def fail(path: str, why: str) -> SceneError:
    why = " ".join(str(why).split()) or "no pixels"  # OpenImageIO's message, on one line
    return SceneError(FIELD, f"{printable(path, 200)!r} cannot be read as an image ({printable(why, 300)}); "
                             "allowed an .exr or .hdr file")


def factor_for(width: int, height: int) -> int:
    """The whole factor an image of ``width`` x ``height`` is area-averaged by (1: read as it is)."""
    return max(1, math.ceil(math.sqrt(width * height / MAX_PIXELS)))


def peak_bytes(width: int, height: int) -> int:
    """Bytes the world of an image of this header size holds at its peak while it is made."""
    f = factor_for(width, height)
    w, h = -(-width // f), -(-height // f)
    return (w + 3) * (h + 3) * PADDED_BYTES + min(STRIP_PIXELS, w * h) * STRIP_BYTES_PER_PIXEL


def _oiio():
    from ..images.imageio import oiio_module  # OpenImageIO only when an image is read

    return oiio_module()


def header(path: str) -> tuple[int, int, int, int]:
    """(width, height, channels, tile height or 0) from the file's header, no pixel read; a
    ``SceneError`` for a header that cannot be read or declares an impossible or too large size."""
    oiio = _oiio()
    inp = oiio.ImageInput.open(path)
    if inp is None:
        raise fail(path, oiio.geterror() or "not an image")
    try:
        spec = inp.spec()
        width, height, channels, tile = spec.width, spec.height, spec.nchannels, spec.tile_height
    finally:
        inp.close()
    _check_size(path, width, height, channels)
    return width, height, channels, (tile if spec.tile_width else 0)


def _check_size(path: str, width: int, height: int, channels: int) -> None:
    if width < 1 or height < 1 or channels < 1:
        raise fail(path, f"its header declares {width}x{height} px, {channels} channels")
    if width * height > MAX_DECLARED_PIXELS:
        raise SceneError(FIELD, f"{printable(path, 200)!r} declares {width}x{height} px; allowed at most "
                                f"{MAX_DECLARED_PIXELS:,} px (16384x8192) in an environment image")


def read_padded(path: str) -> np.ndarray:
    """The image's RGB as ``environment._padded`` holds it, ((h + 3) * (w + 3), 4) float32, read a
    strip at a time (area-averaged by ``factor_for``), finite and clamped (module docstring)."""
    oiio = _oiio()
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        inp = oiio.ImageInput.open(path)
        if inp is None:
            raise fail(path, oiio.geterror() or "not an image")
        try:
            spec = inp.spec()
            width, height, channels = spec.width, spec.height, spec.nchannels
            _check_size(path, width, height, channels)
            tiled = spec.tile_width > 0
            return _read_strips(inp, oiio, path, width, height, channels, spec.tile_height if tiled else 0)
        finally:
            inp.close()


def _read_strips(inp, oiio, path: str, width: int, height: int, channels: int, tile: int) -> np.ndarray:
    f = factor_for(width, height)
    w, h = -(-width // f), -(-height // f)
    grid = np.zeros((h + 3, w + 3, 4), dtype=np.float32)
    # Rows read at once: whole groups of f (the averaging) and of the tile height (tiled files).
    step = f * (tile // math.gcd(f, tile) if tile else 1)
    step *= max(1, STRIP_PIXELS // (width * step))
    used = min(channels, 3)
    for y0 in range(0, height, step):
        y1 = min(height, y0 + step)
        if tile:
            strip = inp.read_tiles(0, 0, 0, width, y0, y1, 0, 1, 0, used, oiio.FLOAT)
        else:
            strip = inp.read_scanlines(0, 0, y0, y1, 0, 0, used, oiio.FLOAT)
        if strip is None or inp.has_error or getattr(strip, "shape", None) is None:
            raise fail(path, inp.geterror() or "no pixels")
        strip = np.asarray(strip, dtype=np.float32).reshape(y1 - y0, width, used)
        rgb = np.repeat(strip[..., :1], 3, axis=2) if used < 3 else strip
        rgb = np.nan_to_num(rgb, nan=0.0, posinf=0.0, neginf=0.0)
        np.clip(rgb, -MAX_RADIANCE, MAX_RADIANCE, out=rgb)
        if f > 1:
            rgb = _area_average(rgb, f)
        grid[1 + y0 // f:1 + y0 // f + len(rgb), 1:w + 1, :3] = rgb
    # The repeated border: row -1 is row h - 1, rows h and h + 1 are rows 0 and 1 (likewise columns).
    grid[0] = grid[h]
    grid[h + 1] = grid[1]
    grid[h + 2] = grid[(h + 1) % h + 1]
    grid[:, 0] = grid[:, w]
    grid[:, w + 1] = grid[:, 1]
    grid[:, w + 2] = grid[:, (w + 1) % w + 1]
    padded = grid.reshape(-1, 4)
    padded.setflags(write=False)
    return padded


def _area_average(rgb: np.ndarray, f: int) -> np.ndarray:
    """Means of f x f blocks of ``rgb`` (rows, width, 3); the last block of a row or column holds
    what is left."""
    rows, width = rgb.shape[:2]
    starts_y = np.arange(0, rows, f)
    starts_x = np.arange(0, width, f)
    sums = np.add.reduceat(np.add.reduceat(rgb.astype(np.float64), starts_y, axis=0), starts_x, axis=1)
    counts = np.outer(np.diff(np.append(starts_y, rows)), np.diff(np.append(starts_x, width)))
    return (sums / counts[..., None]).astype(np.float32)


def pixels_of(padded: np.ndarray, width: int, height: int) -> np.ndarray:
    """The (height, width, 3) view of the image inside its padded layout."""
    return padded.reshape(height + 3, width + 3, 4)[1:height + 1, 1:width + 1, :3]


def file_digest(path: str) -> str:
    """The SHA-256 of the file's bytes: what the world cache is keyed by."""
    import hashlib

    digest = hashlib.sha256()
    with open(path, "rb") as f:
        while chunk := f.read(1 << 20):
            digest.update(chunk)
    return digest.hexdigest()

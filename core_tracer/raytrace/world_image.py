"""An environment image read within the memory budget: its header checked before any pixel is read,
its pixels read a strip of rows at a time straight into the padded layout the lookup uses, down-sampled
where it is larger than the world's share of the budget, and its values made finite.

The rules, each refused with one line naming the file (a ``SceneError`` on ``environment.file``):

- The file must begin as an OpenEXR or a Radiance file does, and be read by OpenImageIO's reader of
  that format (no other reader is reached).
- The header must declare a positive size of at most ``MAX_DECLARED_PIXELS`` (a 16384 x 8192 image)
  and at least one channel, and what reading it holds at its peak (``peak_bytes``: the padded image,
  a strip of source rows in every channel, a tile, the world's per-strip sums) must be at most
  ``MAX_WORLD_BYTES``; a file whose header cannot be read is refused too. OpenImageIO's own
  messages are collected and put into that line, never printed.
- An image of more than ``MAX_PIXELS`` (8192 x 4096: its padded pixels, 16 bytes each, are an eighth
  of ``budget.MEMORY_BUDGET``) is area-averaged by a whole factor while it is read, to at most that.
- Radiance is finite and bounded: NaN and infinite pixels count as 0 (as Blender shows them black),
  and finite values are clamped to +-``MAX_RADIANCE`` (so that strength 10000 still leaves every
  sum in a float32 image finite).
"""

from __future__ import annotations

import contextlib
import math
import threading
import warnings
from collections.abc import Iterator

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
READ_BYTES_PER_PIXEL = 64  # a strip of source as read: float32 RGB, its finite copy, a grey image's
# repeat, the float64 sums of the area average; and 4 bytes a channel for the reader's native rows
MAX_WORLD_BYTES = 2 * 2**30  # half of budget.MEMORY_BUDGET: a 16384 x 8192 image needs about 1 GB
FIELD = "environment.file"
EXR_MAGIC = b"\x76\x2f\x31\x01"  # OpenEXR's first four bytes (OpenEXR file layout, "magic number")
HDR_MAGIC = b"#?"  # a Radiance picture's first line: "#?RADIANCE" or "#?RGBE"
FORMATS = ("openexr", "hdr")  # OpenImageIO's names of the two readers
# the reading rules, part of a cached image's name (v2: the data window's origin is honoured)
LAYOUT = f"v2-{MAX_PIXELS}-{MAX_RADIANCE:g}"


def fail(path: str, why: str) -> SceneError:
    why = " ".join(str(why).split()) or "no pixels"  # OpenImageIO's message, on one line
    return SceneError(FIELD, f"{printable(path, 200)!r} cannot be read as an image ({printable(why, 300)}); "
                             "allowed an .exr or .hdr file")


def factor_for(width: int, height: int) -> int:
    """The whole factor an image of ``width`` x ``height`` is area-averaged by (1: read as it is)."""
    return max(1, math.ceil(math.sqrt(width * height / MAX_PIXELS)))


def rows_read(width: int, f: int, tile_height: int) -> int:
    """Rows of source read at once: whole groups of ``f`` (the averaging) and of the tile height (a
    tiled file), as many as ``STRIP_PIXELS`` holds, at least one group."""
    step = f * (tile_height // math.gcd(f, tile_height) if tile_height else 1)
    return step * max(1, STRIP_PIXELS // (width * step))


def peak_bytes(width: int, height: int, channels: int = 3, tile_width: int = 0, tile_height: int = 0) -> int:
    """Bytes the world of an image of this header holds at its peak while it is made: the padded
    image, a strip of source rows (whole tiles wide, every channel) and one tile as the reader holds
    them, and the world's per-strip sums (``environment._strips``: at least one row)."""
    f = factor_for(width, height)
    w, h = -(-width // f), -(-height // f)
    read_width = -(-width // tile_width) * tile_width if tile_width else width
    read = min(height, rows_read(width, f, tile_height)) * read_width
    sums = min(w * h, max(STRIP_PIXELS, w))
    return ((w + 3) * (h + 3) * PADDED_BYTES + sums * STRIP_BYTES_PER_PIXEL
            + read * (READ_BYTES_PER_PIXEL + 4 * channels) + tile_width * tile_height * 4 * channels)


def _oiio():
    from ..images.imageio import oiio_module  # OpenImageIO only when an image is read

    return oiio_module()


def _said(message) -> str:
    """What OpenImageIO says (``message()``: a ``geterror``), as text: its messages quote a broken
    file's bytes, which pybind11 cannot decode when they are not UTF-8."""
    try:
        return message()
    except UnicodeDecodeError as e:
        raw = e.object if isinstance(e.object, bytes) else b""
        return raw.decode("utf-8", "backslashreplace")


_OPENING = threading.Lock()  # "openexr:core" is process-wide: set and put back by one opener at a time


@contextlib.contextmanager
def _opened(path: str) -> Iterator[tuple]:
    """(OpenImageIO, ImageInput, spec) of the image at ``path``, closed after. Only OpenImageIO's
    OpenEXR and Radiance readers are reached: the file's first bytes must be theirs (OpenImageIO
    would try every reader it has on anything else). OpenEXR files are read by OpenImageIO's reader
    on the OpenEXR core library ("openexr:core"), which hands every message back to the caller;
    the other one lets OpenEXR print to stderr. A path that is not UTF-8 (OpenImageIO takes only
    UTF-8 names) is opened here and given to it as /dev/fd/N."""
    oiio = _oiio()
    with open(path, "rb") as file:
        magic = file.read(len(EXR_MAGIC))
        if not magic.startswith((EXR_MAGIC, HDR_MAGIC)):
            raise fail(path, "it is neither an OpenEXR nor a Radiance file (its first bytes)")
        name = path
        try:
            path.encode("utf-8")
        except UnicodeEncodeError:
            name = f"/dev/fd/{file.fileno()}"
        with _OPENING, warnings.catch_warnings():
            warnings.simplefilter("ignore")
            core = oiio.get_int_attribute("openexr:core")
            oiio.attribute("openexr:core", 1)
            try:
                inp = oiio.ImageInput.open(name)
            finally:
                oiio.attribute("openexr:core", core)
    if inp is None:
        raise fail(path, _said(oiio.geterror) or "not an image")
    try:
        if inp.format_name() not in FORMATS:
            raise fail(path, f"OpenImageIO reads it as {inp.format_name()}")
        spec = inp.spec()
        if spec.deep or spec.depth != 1:
            raise fail(path, "it holds deep or volume data")
        _check_size(path, spec)
        yield oiio, inp, spec
    finally:
        inp.close()


def header(path: str) -> tuple[int, int, int, int, int]:
    """(width, height, channels, tile width, tile height; 0 and 0 for scanlines) from the file's
    header, no pixel read; a ``SceneError`` for a header that cannot be read or declares an
    impossible or too large image. ``peak_bytes(*header(path))`` is what reading it holds."""
    with _opened(path) as (_, _, spec):
        return _shape(spec)


def _shape(spec) -> tuple[int, int, int, int, int]:
    tiled = spec.tile_width > 0
    return (spec.width, spec.height, spec.nchannels, spec.tile_width if tiled else 0,
            spec.tile_height if tiled else 0)


def _check_size(path: str, spec) -> None:
    width, height, channels, tile_width, tile_height = _shape(spec)
    if width < 1 or height < 1 or channels < 1 or tile_width < 0 or tile_height < 0:
        raise fail(path, f"its header declares {width}x{height} px, {channels} channels")
    if width * height > MAX_DECLARED_PIXELS:
        raise SceneError(FIELD, f"{printable(path, 200)!r} declares {width}x{height} px; allowed at most "
                                f"{MAX_DECLARED_PIXELS:,} px (16384x8192) in an environment image")
    need = peak_bytes(width, height, channels, tile_width, tile_height)
    if need > MAX_WORLD_BYTES:
        tiles = f", tiles of {tile_width}x{tile_height} px" if tile_width else ""
        raise SceneError(FIELD, f"{printable(path, 200)!r} would take {need / 2**30:.1f} GB to read ({width}x{height} "
                                f"px, {channels} channels{tiles}); allowed at most {MAX_WORLD_BYTES / 2**30:.0f} GB "
                                "for an environment image (an equirectangular image of up to 16384x8192 px, "
                                "RGB or RGBA)")


def read_padded(path: str) -> np.ndarray:
    """The image's RGB as ``environment._padded`` holds it, ((h + 3) * (w + 3), 4) float32, read a
    strip at a time (area-averaged by ``factor_for``), finite and clamped (module docstring)."""
    with warnings.catch_warnings(), np.errstate(all="ignore"), _opened(path) as (oiio, inp, spec):
        warnings.simplefilter("ignore")
        tile = spec.tile_height if spec.tile_width > 0 else 0
        return _read_strips(inp, oiio, path, spec, tile)


def _read_strips(inp, oiio, path: str, spec, tile: int) -> np.ndarray:
    width, height, channels = spec.width, spec.height, spec.nchannels
    x, y = spec.x, spec.y  # the data window's corner: rows and columns are read by their coordinates
    f = factor_for(width, height)
    w, h = -(-width // f), -(-height // f)
    grid = np.zeros((h + 3, w + 3, 4), dtype=np.float32)
    step = rows_read(width, f, tile)
    used = min(channels, 3)
    for y0 in range(0, height, step):
        y1 = min(height, y0 + step)
        if tile:
            strip = inp.read_tiles(0, 0, x, x + width, y + y0, y + y1, spec.z, spec.z + 1, 0, used, oiio.FLOAT)
        else:
            strip = inp.read_scanlines(0, 0, y + y0, y + y1, spec.z, 0, used, oiio.FLOAT)
        if strip is None or inp.has_error or getattr(strip, "shape", None) is None:
            raise fail(path, _said(inp.geterror) or "no pixels")
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

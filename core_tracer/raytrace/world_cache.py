"""The world of an environment image, made once and shared: its padded pixels, its irradiance map,
its sun's direction and colour (``environment``), kept in a file that every process maps.

A render's parent makes the world (or finds it) and the band pool's workers and a study's workers
map the same files: the pages are the system's file cache, held once however many processes read
them. The file outlives the render, so the next render of the same image and turn skips the work.

The files live in a per-user cache folder (``$LAMP_STYLING_CACHE``, else ``$XDG_CACHE_HOME`` or
``~/.cache``, then ``lamp-styling/worlds``): the pixels in ``<SHA-256 of the image file>-<reading
rules>.image``, what the lookups compute from them in ``<SHA-256>-<turn>-<map layout>.turn`` (a
study that turns the world keeps its pixels once). They are written to a temporary name and
renamed (never seen half-written), checked when mapped (magic, header, size, CRC-32 of the data: a damaged file is
made again), and the folder is kept under ``MAX_CACHE_BYTES`` by removing the least recently used.
A folder that is not the user's own (or is writable by others), or that cannot be written, is not
used: the world is then made in memory, in each process that needs it, as before.
"""

from __future__ import annotations

import contextlib
import functools
import json
import mmap
import os
import stat
import struct
import time
import zlib
from dataclasses import dataclass

import numpy as np

from . import world_image

MAGIC = b"LAMPWLD1"
_HEAD = struct.Struct("<8sQ")  # magic, length of the JSON header that follows
ALIGN = 64
MAX_CACHE_BYTES = 1 << 30  # the folder's files in all; the least recently used go first
STALE_SECONDS = 3600.0  # a temporary file this old was left by a process that died
ENV_FOLDER = "LAMP_STYLING_CACHE"


@dataclass(frozen=True)
class World:
    """What the lookups of one image at one turn need (arrays read-only, maybe mapped from a file)."""

    padded: np.ndarray  # ((h + 3) * (w + 3), 4) float32: environment._padded
    width: int
    height: int
    irradiance: np.ndarray  # (IRRADIANCE_LAT + 1, IRRADIANCE_LON, 3) at strength 1
    sun_direction: np.ndarray  # (3,)
    sun_color: np.ndarray  # (3,)
    file: str | None = None  # the cache file it is mapped from

    @property
    def pixels(self) -> np.ndarray:
        return world_image.pixels_of(self.padded, self.width, self.height)


def cache_folder() -> str | None:
    """The cache folder, made if missing; None where it is not safe or cannot be made."""
    root = os.environ.get(ENV_FOLDER)
    if not root:
        base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
        root = os.path.join(base, "lamp-styling")
    folder = os.path.join(root, "worlds")
    try:
        os.makedirs(folder, mode=0o700, exist_ok=True)
        st = os.stat(folder, follow_symlinks=False)
    except OSError:
        return None
    if not stat.S_ISDIR(st.st_mode):
        return None
    if hasattr(os, "getuid") and (st.st_uid != os.getuid() or st.st_mode & 0o022):
        return None  # someone else could swap the files another process maps
    return folder


def world(path: str, rotation: float, layout: str, make, retouch: tuple[str, object] | None = None) -> World:
    """The world of the image at ``path`` turned by ``rotation``: from this process's memory, from
    the cache files, or made and stored. The pixels (``world_image.read_padded``) are kept by the
    image's content alone, what ``make(pixels (h, w, 3), rotation)`` -> (irradiance, sun direction,
    sun colour) computes by content, turn and ``layout`` (the map's size).

    ``retouch`` = (tag, padded_of): the world's pixels are ``padded_of(pixels)`` instead (kept by
    content and tag: the image without its sun, ``environment.sunless``); ``make`` still gets the
    image as read, and must apply the same retouch where it wants it (``layout`` names it)."""
    st = os.stat(path)
    return _world(path, st.st_mtime_ns, st.st_size, rotation, layout, make, retouch)


@functools.lru_cache(maxsize=4)
def _world(path: str, mtime_ns: int, size: int, rotation: float, layout: str, make,
           retouch: tuple[str, object] | None) -> World:
    folder = cache_folder()
    digest = world_image.file_digest(path)[:40]
    image_name = f"{digest}-{world_image.LAYOUT}.image"
    turn_name = f"{digest}-{rotation.hex()}-{layout}.turn"
    image, image_file = _cached(folder, image_name, lambda: _read(path), {"padded", "size"})
    width, height = (int(n) for n in image["size"])
    pixels = world_image.pixels_of(image["padded"], width, height)

    def turned() -> dict[str, np.ndarray]:
        irradiance, sun_direction, sun_color = make(pixels, rotation)
        return {"irradiance": irradiance, "sun_direction": sun_direction, "sun_color": sun_color}

    turn, _ = _cached(folder, turn_name, turned, {"irradiance", "sun_direction", "sun_color"})
    keep = {image_name, turn_name}
    if retouch is not None:
        tag, padded_of = retouch
        retouched_name = f"{digest}-{world_image.LAYOUT}-{tag}.image"
        image, image_file = _cached(folder, retouched_name,
                                    lambda: {"padded": padded_of(pixels), "size": np.array([width, height])},
                                    {"padded", "size"})
        keep.add(retouched_name)
    if folder is not None:
        _prune(folder, keep=keep)
    return World(image["padded"], width, height, turn["irradiance"], turn["sun_direction"], turn["sun_color"],
                 image_file)


def _read(path: str) -> dict[str, np.ndarray]:
    width, height = world_image.header(path)[:2]
    f = world_image.factor_for(width, height)
    return {"padded": world_image.read_padded(path), "size": np.array([-(-width // f), -(-height // f)])}


def _cached(folder: str | None, name: str, make, keys: set[str]) -> tuple[dict[str, np.ndarray], str | None]:
    """(the arrays ``keys`` of the cache file ``name``, mapped, and its path), made by ``make()`` and
    stored first if it is missing or damaged; made in memory (path None) without a usable folder."""
    if folder is None:
        return make(), None
    file = os.path.join(folder, name)
    mapped = _map(file, keys)
    if mapped is not None:
        return mapped, file
    arrays = make()
    try:
        _write(file, arrays)
    except OSError:
        return arrays, None
    del arrays  # the file's pages take the place of this copy: the workers then share these very pages
    mapped = _map(file, keys)
    return (mapped, file) if mapped is not None else (make(), None)


def _write(target: str, arrays: dict[str, np.ndarray]) -> None:
    import tempfile  # only when a world is stored

    arrays = {key: np.ascontiguousarray(a) for key, a in arrays.items()}
    table, offset = {}, 0
    for key, a in arrays.items():
        table[key] = [offset, list(a.shape), a.dtype.str]
        offset += -(-a.nbytes // ALIGN) * ALIGN
    crc = 0
    for a in arrays.values():
        crc = zlib.crc32(memoryview(a).cast("B"), crc)
    header = json.dumps({"arrays": table, "data_bytes": offset, "crc": crc}).encode()
    start = -(-(_HEAD.size + len(header)) // ALIGN) * ALIGN
    fd, temporary = tempfile.mkstemp(prefix=".tmp-", dir=os.path.dirname(target))
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(_HEAD.pack(MAGIC, len(header)) + header)
            for key, a in arrays.items():
                f.seek(start + table[key][0])
                f.write(memoryview(a).cast("B"))  # no copy of the pixels
            f.truncate(start + offset)
        os.replace(temporary, target)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(temporary)
        raise


def _map(file: str, keys: set[str]) -> dict[str, np.ndarray] | None:
    """The arrays ``keys`` in ``file``, views of a read-only mapping; None if it is missing or
    damaged (a damaged file is removed, to be made again)."""
    try:
        with open(file, "rb") as f:
            if os.fstat(f.fileno()).st_size < _HEAD.size:
                raise ValueError("short")
            data = mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ)
    except FileNotFoundError:
        return None
    except (OSError, ValueError):
        _discard(file)
        return None
    try:
        magic, length = _HEAD.unpack_from(data, 0)
        if magic != MAGIC or length > 1 << 16:
            raise ValueError("not a world file")
        header = json.loads(bytes(data[_HEAD.size:_HEAD.size + length]))
        start = -(-(_HEAD.size + length) // ALIGN) * ALIGN
        if len(data) != start + int(header["data_bytes"]):
            raise ValueError("wrong size")
        arrays, crc, a = {}, 0, None
        for key, (offset, shape, dtype) in header["arrays"].items():
            count = int(np.prod(shape))
            a = np.frombuffer(data, dtype=np.dtype(dtype), count=count, offset=start + int(offset)).reshape(shape)
            crc = zlib.crc32(memoryview(a).cast("B"), crc)
            arrays[key] = a
        if crc != header["crc"] or set(arrays) != keys:
            raise ValueError("damaged")
    except (ValueError, TypeError, KeyError, AttributeError, struct.error, OverflowError):
        arrays = a = None  # the views go first, then the mapping
        with contextlib.suppress(BufferError):
            data.close()
        _discard(file)
        return None
    with contextlib.suppress(OSError):
        os.utime(file)  # recently used: pruned last
    return arrays


def _discard(file: str) -> None:
    with contextlib.suppress(OSError):
        os.unlink(file)


def _prune(folder: str, keep: set[str]) -> None:
    """Remove the least recently used worlds beyond ``MAX_CACHE_BYTES`` and stale temporary files."""
    try:
        entries = [(e.stat().st_mtime, e.stat().st_size, e.path) for e in os.scandir(folder) if e.is_file()]
    except OSError:
        return
    now = time.time()
    total = 0
    for mtime, size, path in sorted(entries, reverse=True):
        name = os.path.basename(path)
        if name.startswith(".tmp-"):
            if now - mtime > STALE_SECONDS:
                _discard(path)
            continue
        total += size
        if total > MAX_CACHE_BYTES and name not in keep:
            _discard(path)


def clear_memory() -> None:
    """Forget the worlds this process holds (tests; the files stay)."""
    _world.cache_clear()

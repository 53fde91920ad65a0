"""The world of an environment image, made once and shared: its padded pixels, its irradiance map,
its sun's direction and colour (``environment``), kept in a file that every process maps.

A render's parent makes the world (or finds it) and the band pool's workers and a study's workers
map the same file: the pages are the system's file cache, held once however many processes read
them. The file outlives the render, so the next render of the same image and turn skips the work.

The files live in a per-user cache folder (``$LAMP_STYLING_CACHE``, else ``$XDG_CACHE_HOME`` or
``~/.cache``, then ``lamp-styling/worlds``), named by the SHA-256 of the image file's bytes, the
turn and the map's layout (``LAYOUT``). They are written to a temporary name and renamed (never
seen half-written), checked when mapped (magic, header, size, CRC-32 of the data: a damaged file is
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
import tempfile
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


def world(path: str, rotation: float, layout: str, make) -> World:
    """The world of the image at ``path`` turned by ``rotation``: from this process's memory, from
    the cache file, or made by ``make(padded, width, height, rotation)`` -> (irradiance, sun
    direction, sun colour) and stored. ``layout`` names what ``make`` computes (the map's size)."""
    st = os.stat(path)
    return _world(path, st.st_mtime_ns, st.st_size, rotation, layout, make)


@functools.lru_cache(maxsize=4)
def _world(path: str, mtime_ns: int, size: int, rotation: float, layout: str, make) -> World:
    folder = cache_folder()
    name = f"{world_image.file_digest(path)[:40]}-{rotation.hex()}-{layout}.world"
    if folder is not None:
        mapped = _map(os.path.join(folder, name))
        if mapped is not None:
            return mapped
    made = _made(path, rotation, make)
    if folder is None:
        return made
    target = os.path.join(folder, name)
    try:
        _write(target, made)
    except OSError:
        return made
    del made  # the file's pages take the place of this copy: the workers then share these very pages
    _prune(folder, keep=target)
    return _map(target) or _made(path, rotation, make)


def _made(path: str, rotation: float, make) -> World:
    padded, width, height = _made_padded(path)
    irradiance, sun_direction, sun_color = make(padded, width, height, rotation)
    return World(padded, width, height, irradiance, sun_direction, sun_color)


def _made_padded(path: str) -> tuple[np.ndarray, int, int]:
    width, height = world_image.header(path)[:2]
    f = world_image.factor_for(width, height)
    return world_image.read_padded(path), -(-width // f), -(-height // f)


def _arrays(w: World) -> dict[str, np.ndarray]:
    return {"padded": w.padded, "irradiance": np.asarray(w.irradiance, np.float64),
            "sun_direction": np.asarray(w.sun_direction, np.float64),
            "sun_color": np.asarray(w.sun_color, np.float64)}


def _write(target: str, w: World) -> None:
    arrays = _arrays(w)
    table, offset = {}, 0
    for key, a in arrays.items():
        table[key] = [offset, list(a.shape), a.dtype.str]
        offset += -(-a.nbytes // ALIGN) * ALIGN
    crc = 0
    for a in arrays.values():
        crc = zlib.crc32(memoryview(np.ascontiguousarray(a)).cast("B"), crc)
    header = json.dumps({"width": w.width, "height": w.height, "arrays": table, "data_bytes": offset,
                         "crc": crc}).encode()
    start = -(-(_HEAD.size + len(header)) // ALIGN) * ALIGN
    fd, temporary = tempfile.mkstemp(prefix=".tmp-", dir=os.path.dirname(target))
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(_HEAD.pack(MAGIC, len(header)) + header)
            for key, a in arrays.items():
                f.seek(start + table[key][0])
                f.write(memoryview(np.ascontiguousarray(a)).cast("B"))  # no copy of the pixels
            f.truncate(start + offset)
        os.replace(temporary, target)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(temporary)
        raise


def _map(file: str) -> World | None:
    """The world in ``file``, its arrays views of a read-only mapping; None if it is missing or
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
        arrays, crc = {}, 0
        for key in ("padded", "irradiance", "sun_direction", "sun_color"):
            offset, shape, dtype = header["arrays"][key]
            count = int(np.prod(shape))
            a = np.frombuffer(data, dtype=np.dtype(dtype), count=count, offset=start + int(offset)).reshape(shape)
            crc = zlib.crc32(memoryview(a).cast("B"), crc)
            arrays[key] = a
        if crc != header["crc"]:
            raise ValueError("damaged")
        width, height = int(header["width"]), int(header["height"])
        if arrays["padded"].shape != ((width + 3) * (height + 3), 4):
            raise ValueError("wrong shape")
    except (ValueError, TypeError, KeyError, struct.error, json.JSONDecodeError, OverflowError):
        data.close()
        _discard(file)
        return None
    with contextlib.suppress(OSError):
        os.utime(file)  # recently used: pruned last
    return World(arrays["padded"], width, height, arrays["irradiance"], arrays["sun_direction"],
                 arrays["sun_color"], file)


def _discard(file: str) -> None:
    with contextlib.suppress(OSError):
        os.unlink(file)


def _prune(folder: str, keep: str) -> None:
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
        if total > MAX_CACHE_BYTES and path != keep:
            _discard(path)


def clear_memory() -> None:
    """Forget the worlds this process holds (tests; the files stay)."""
    _world.cache_clear()

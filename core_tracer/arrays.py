"""Arrays read back from files (a light-states ``.npz``, a cache cell's ``.npy``), checked before
they are trusted (issue 33 item 1).

numpy's own ``np.load`` allocates what a file's header claims before it reads a byte of data, and an
``.npz`` member is inflated whole: a 1.7 MB file whose member says 1.7 GB costs 1.7 GB and a minute
before anything can refuse it. Here the sizes are counted first, from the zip's central directory
and each ``.npy`` header (a few hundred bytes), against what the caller expects and what it may
spend; only then is the data read, and a float array is refused if it holds NaN or inf.
"""

from __future__ import annotations

import io
import os
import stat
import tokenize  # numpy parses an .npy header with it: a damaged one raises its TokenError
import zipfile
import zlib
from collections.abc import Sequence
from typing import BinaryIO

import numpy as np
from numpy.lib import format as npy_format

MAX_NPY_HEADER = 10_000  # numpy's own default limit on an .npy header's size


class BadArray(ValueError):
    """An array file is not what its reader expects; the message says what is wrong, in words."""


def _header(fp: BinaryIO) -> tuple[tuple[int, ...], np.dtype, bool, int]:
    """(shape, dtype, Fortran order, bytes before the data) of an ``.npy`` stream at its start."""
    try:
        version = npy_format.read_magic(fp)
        if version == (1, 0):
            shape, fortran, dtype = npy_format.read_array_header_1_0(fp, max_header_size=MAX_NPY_HEADER)
        elif version in ((2, 0), (3, 0)):
            shape, fortran, dtype = npy_format.read_array_header_2_0(fp, max_header_size=MAX_NPY_HEADER)
        else:
            raise BadArray(f"npy version {version} is not one numpy writes")
    except (ValueError, EOFError, SyntaxError, TypeError, OverflowError, KeyError, tokenize.TokenError) as e:
        if isinstance(e, BadArray):
            raise
        raise BadArray("its array header cannot be read") from None
    if dtype.hasobject or dtype.fields is not None or dtype.subdtype is not None:
        raise BadArray(f"holds {dtype} values; allowed plain numbers")
    return tuple(int(n) for n in shape), dtype, bool(fortran), fp.tell()


def read_npy(fp: BinaryIO, size: int, *, dtype: str | np.dtype | None = None,
             shape: Sequence[int | None] | None = None, max_bytes: int | None = None,
             finite: bool = True) -> np.ndarray:
    """The array of an ``.npy`` stream of ``size`` bytes, after checking from its header alone that
    its data is exactly the rest of the stream, at most ``max_bytes``, of ``dtype`` and ``shape``
    (None in ``shape``: any length on that axis); then, for floats, that every value is finite
    (``finite``). Raises ``BadArray``."""
    found, kind, fortran, offset = _header(fp)
    if any(n < 0 for n in found):
        raise BadArray(f"its shape {found} is negative")
    nbytes = int(np.prod(found, dtype=object)) * kind.itemsize
    if max_bytes is not None and nbytes > max_bytes:
        raise BadArray(f"its header says {nbytes:,} bytes; allowed at most {max_bytes:,} here")
    if offset + nbytes != size:
        raise BadArray(f"its header says {nbytes:,} bytes of data but the file holds {size - offset:,}")
    if dtype is not None and kind != np.dtype(dtype):
        raise BadArray(f"holds {kind} values; allowed {np.dtype(dtype)}")
    if shape is not None and (len(found) != len(shape) or any(w is not None and w != n
                                                               for n, w in zip(found, shape, strict=False))):
        wanted = "x".join("any" if w is None else str(w) for w in shape)
        raise BadArray(f"holds an array of shape {'x'.join(map(str, found)) or 'scalar'}; allowed {wanted}")
    data = bytearray(nbytes)  # writable, so the array needs no copy
    view, got = memoryview(data), 0
    while got < nbytes:
        n = fp.readinto(view[got:])
        if not n:
            raise BadArray("is cut short")
        got += n
    array = np.frombuffer(data, dtype=kind)
    array = array.reshape(found[::-1]).transpose() if fortran else array.reshape(found)
    if finite and kind.kind in "fc" and not np.isfinite(array).all():
        raise BadArray("holds values that are not finite numbers (NaN or inf)")
    return array


def read_npy_file(path: str, **checks) -> np.ndarray:
    """``read_npy`` of a regular file on disk (its size from the file system; a FIFO or a device in
    its place is refused without blocking on it). Raises ``BadArray`` or ``OSError``."""
    fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    with os.fdopen(fd, "rb") as fp:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            raise BadArray("is not a regular file")
        size = fp.seek(0, io.SEEK_END)
        fp.seek(0)
        return read_npy(fp, size, **checks)


def npz_sizes(data: bytes, *, max_members: int, max_total: int) -> dict[str, int]:
    """Each member's inflated size (``name`` without ``.npy``) of an ``.npz`` held in ``data``, from the
    zip's central directory, before anything is inflated: at most ``max_members`` members and
    ``max_total`` bytes in all. Raises ``BadArray``."""
    try:
        with zipfile.ZipFile(io.BytesIO(data)) as archive:
            infos = archive.infolist()
    except (zipfile.BadZipFile, zipfile.LargeZipFile, OSError, ValueError, EOFError):
        raise BadArray("is not a zip archive numpy wrote") from None
    if len(infos) > max_members:
        raise BadArray(f"holds {len(infos)} members; allowed at most {max_members}")
    sizes: dict[str, int] = {}
    for info in infos:
        if not info.filename.endswith(".npy") or info.filename[:-4] in sizes or info.is_dir():
            raise BadArray(f"holds a member {info.filename[:80]!r} that numpy does not write")
        sizes[info.filename[:-4]] = info.file_size
    total = sum(sizes.values())
    if total > max_total:
        raise BadArray(f"inflates to {total:,} bytes (its zip directory says); allowed at most {max_total:,} here")
    return sizes


def read_npz_member(data: bytes, name: str, size: int, **checks) -> np.ndarray:
    """Member ``name`` of the ``.npz`` in ``data`` (``npz_sizes`` gave its ``size``), through
    ``read_npy``: the zip's reader stops at the size its directory says and checks the CRC."""
    try:
        with zipfile.ZipFile(io.BytesIO(data)) as archive, archive.open(name + ".npy") as fp:
            array = read_npy(fp, size, **checks)
            if fp.read(1):
                raise BadArray(f"member {name} holds more than its header says")
            return array
    except (zipfile.BadZipFile, zlib.error, OSError, EOFError, NotImplementedError, RuntimeError, KeyError):
        raise BadArray(f"member {name} cannot be inflated (damaged, or not a zip member numpy wrote)") from None

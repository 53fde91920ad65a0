"""PNG files written with the standard library alone (zlib), for pages drawn where OpenImageIO is
absent: a real Blender's Python has numpy and nothing else, and the worker processes it starts do not
see the OpenImageIO Blender bundles (BLENDER-NOTES.md).

The format (PNG specification, W3C Recommendation, third edition 2025, §5 and §11.2): the signature,
an IHDR chunk (width, height, bit depth 8, colour type 2 = RGB), one IDAT chunk of the zlib-deflated
scanlines (each after a filter-type byte, 0 = none) and IEND; each chunk is its length, type, data
and the CRC-32 of type and data.
"""

from __future__ import annotations

import os
import struct
import zlib

import numpy as np

from ..fileio import atomic_path

SIGNATURE = b"\x89PNG\r\n\x1a\n"


def _chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)


def png_bytes(rgb: np.ndarray, text: dict[str, str] | None = None) -> bytes:
    """An 8-bit RGB PNG of ``rgb`` (H, W, 3 uint8, top row first), with Latin-1 ``text`` chunks."""
    pixels = np.ascontiguousarray(rgb, dtype=np.uint8)
    if pixels.ndim != 3 or pixels.shape[2] != 3:
        raise ValueError(f"a PNG here is (height, width, 3) bytes; got shape {pixels.shape}")
    height, width = pixels.shape[:2]
    rows = np.concatenate([np.zeros((height, 1), np.uint8), pixels.reshape(height, width * 3)], axis=1)
    out = SIGNATURE + _chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
    for key, value in (text or {}).items():
        out += _chunk(b"tEXt", key.encode("latin-1", "replace")[:79] + b"\0" + value.encode("latin-1", "replace"))
    return out + _chunk(b"IDAT", zlib.compress(rows.tobytes(), 6)) + _chunk(b"IEND", b"")


def write_png(path: str | os.PathLike, rgb: np.ndarray, text: dict[str, str] | None = None) -> None:
    """``png_bytes`` written whole or not at all (``fileio.atomic_path``)."""
    data = png_bytes(rgb, text)
    with atomic_path(path) as tmp, open(tmp, "wb") as f:
        f.write(data)

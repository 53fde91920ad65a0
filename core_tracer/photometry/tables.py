"""The spectral tables shipped under ``data/`` (written by ``tools/make_spectral_data.py``), read once."""

from __future__ import annotations

import functools
import os

import numpy as np

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data")


@functools.cache
def table(name: str) -> tuple[np.ndarray, np.ndarray]:
    """(wavelengths in nm (N,), columns (N, C)) of the shipped table ``name``, as read-only arrays.

    The files are ``#`` comment lines, one header line, then ``nm,value,...`` rows."""
    with open(os.path.join(DATA, name), encoding="utf-8") as f:
        lines = [line for line in f.read().splitlines() if line and not line.startswith("#")]
    data = np.array([[float(v) for v in line.split(",")] for line in lines[1:]], dtype=np.float64)
    wavelengths, columns = data[:, 0].copy(), data[:, 1:].copy()
    wavelengths.flags.writeable = False
    columns.flags.writeable = False
    return wavelengths, columns

"""A cache cell is checked before it is trusted (issue 33 item 1): its size from the .npy header
before reading, shape, dtype, finiteness; a bad cell is dropped with one line and rendered again."""

from __future__ import annotations

import os

import hostile_files as H
import numpy as np
import pytest
from helpers import BASELINE, run_cli

from core_tracer.cluster.cache import CellCache

KEY = "ab" + "0" * 62
GOOD = np.linspace(0, 1, 4 * 6 * 3, dtype=np.float32).reshape(4, 6, 3)


def _tampered(cache: CellCache, data: bytes) -> str:
    path = cache.path(KEY)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "wb") as f:
        f.write(data)
    return path


def test_a_good_cell_reads_back(tmp_path):
    cache = CellCache(tmp_path)
    cache.put(KEY, GOOD)
    assert np.array_equal(cache.get(KEY, (6, 4)), GOOD)


@pytest.mark.parametrize("what, data, words", [
    ("nan", H.npy_bytes(np.where(GOOD > 0.5, np.nan, GOOD).astype(np.float32)), "not finite"),
    ("inf", H.npy_bytes(np.full((4, 6, 3), np.inf, np.float32)), "not finite"),
    ("size", H.npy_bytes(np.zeros((2, 2, 3), np.float32)), "allowed 4x6x3"),
    ("dtype", H.npy_bytes(GOOD.astype(np.float64)), "float64"),
    ("object", H.npy_bytes(np.array([None, {}], dtype=object)), "object"),
    ("huge header", H.npy_header((100000, 100000, 3)) + bytes(100), "allowed at most"),
    ("cut short", H.npy_bytes(GOOD)[:200], "file holds"),
    ("not npy", b"PK\x03\x04 a zip", "header"),
])
def test_a_bad_cell_is_dropped_with_one_line(tmp_path, capsys, what, data, words):
    cache = CellCache(tmp_path)
    path = _tampered(cache, data)
    assert cache.get(KEY, (6, 4)) is None
    assert not os.path.exists(path)
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and KEY[:12] in err and words in err and "rendering it again" in err


def test_a_folder_where_a_cell_should_be_is_dropped_too(tmp_path, capsys):
    cache = CellCache(tmp_path)
    os.makedirs(cache.path(KEY))
    assert cache.get(KEY, (6, 4)) is None and not os.path.exists(cache.path(KEY))
    assert "dropped" in capsys.readouterr().err


def test_a_non_finite_image_is_not_kept(tmp_path):
    cache = CellCache(tmp_path)
    cache.put(KEY, np.full((4, 6, 3), np.nan, np.float32))
    assert not os.path.exists(cache.path(KEY))


@pytest.mark.slow
def test_a_study_rerun_with_a_tampered_cell_renders_it_again_and_writes_a_finite_sheet(tmp_path):
    env = dict(os.environ, LAMP_STYLING_CACHE=str(tmp_path / "cache"))
    study = ("study", BASELINE, "--vary", "lens.ior=1.4,1.6", "--size", "24x24", "--workers", "1", "--engine",
             "dask")
    first = run_cli(*study, "-o", tmp_path / "a.exr", env=env)
    assert first.returncode == 0, first.stderr
    cells = [os.path.join(root, n) for root, _, names in os.walk(tmp_path / "cache" / "cells") for n in names]
    assert len(cells) == 2
    with open(cells[0], "wb") as f:
        f.write(H.npy_bytes(np.full((24, 24, 3), np.nan, np.float32)))
    with open(cells[1], "wb") as f:
        f.write(H.npy_bytes(np.zeros((3, 3, 3), np.float32)))
    again = run_cli(*study, "-o", tmp_path / "b.exr", env=env)
    assert again.returncode == 0, again.stderr
    assert "(2 rendered, 0 from the cache)" in again.stdout
    assert again.stderr.count("rendering it again") == 2 and "Traceback" not in again.stderr
    third = run_cli(*study, "-o", tmp_path / "c.exr", env=env)
    assert "(0 rendered, 2 from the cache)" in third.stdout and "rendering it again" not in third.stderr


def test_a_header_numpy_cannot_tokenize_is_dropped(tmp_path, capsys):
    """Found by the campaign: an unclosed brace in the header raised tokenize's TokenError."""
    data = H.npy_bytes(GOOD)
    end = data.index(b"}")
    cache = CellCache(tmp_path)
    _tampered(cache, data[:end] + b" " + data[end + 1:])
    assert cache.get(KEY, (6, 4)) is None and "header" in capsys.readouterr().err

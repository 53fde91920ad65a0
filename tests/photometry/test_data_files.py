"""The shipped spectral tables are exactly what tools/make_spectral_data.py writes from colour-science."""

from __future__ import annotations

import importlib.util
import os

import pytest

from core_tracer.photometry import tables

pytestmark = pytest.mark.filterwarnings("ignore")


def _generator(repo_root):
    spec = importlib.util.spec_from_file_location("make_spectral_data", repo_root / "tools" / "make_spectral_data.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_shipped_tables_equal_a_regeneration(repo_root, colour):
    expected = _generator(repo_root).tables()
    shipped = sorted(f for f in os.listdir(tables.DATA) if f.endswith(".csv"))
    assert shipped == sorted(expected)
    for name, text in expected.items():
        with open(os.path.join(tables.DATA, name), encoding="utf-8", newline="") as f:
            assert f.read() == text, f"{name} is stale: run tools/make_spectral_data.py"


def test_tables_are_small(repo_root):
    total = sum(os.path.getsize(os.path.join(tables.DATA, f)) for f in os.listdir(tables.DATA))
    assert total < 40_000  # 27.0 kB today


def test_reader_parses_what_was_written(colour):
    wavelengths, columns = tables.table("cie1931_2deg.csv")
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    assert (wavelengths == cmfs.wavelengths).all()
    assert abs(columns - cmfs.values).max() < 1e-15

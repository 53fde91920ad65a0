"""What the benchmarks share: the command line most of them start with (a preset and a few numbers).

A benchmark runs as a script from the repository (``.venv/bin/python benchmarks/bench_x.py``); it puts
the repository on ``sys.path`` itself, then imports this module as ``benchmarks.common``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def preset_path(name: str) -> str:
    """A shipped preset's file."""
    return str(ROOT / "presets" / name)


def arguments(doc: str, preset: str, **numbers: int | float) -> argparse.ArgumentParser:
    """The parser of a benchmark described by ``doc`` (its first line): ``--preset`` (default the
    shipped ``preset``) and one option per keyword, ``--runs 5`` for ``runs=5`` (``pixel_mm`` is
    ``--pixel-mm``), typed as its default."""
    parser = argparse.ArgumentParser(description=doc.splitlines()[0])
    parser.add_argument("--preset", default=preset_path(preset))
    for name, default in numbers.items():
        parser.add_argument("--" + name.replace("_", "-"), type=type(default), default=default)
    return parser

"""What the benchmarks share: the command line most of them start with (a preset and a few numbers).

A benchmark runs as a script from the repository (``.venv/bin/python benchmarks/bench_x.py``); it puts
the repository on ``sys.path`` itself, then imports this module as ``benchmarks.common``.
"""

from __future__ import annotations

import argparse
import importlib
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


def design_in_blender(bpy, package: str, document: dict):
    """Blender's scene holding the design ``document`` through the add-on loaded as ``package``, seen by
    its lamp camera; returns (the scene, the add-on's Compare module)."""
    comparison = importlib.import_module(f"{package}.lamp_addon.compare.comparison")
    design = importlib.import_module(f"{package}.lamp_addon.design.properties")
    lamp_camera = importlib.import_module(f"{package}.lamp_addon.design.lamp_camera")
    bl_scene = bpy.context.scene
    design.scene_to_design(bl_scene, document)
    bl_scene.camera, _ = lamp_camera.ensure_lamp_camera(bl_scene, frame=False)
    return bl_scene, comparison

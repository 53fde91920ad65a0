#!/usr/bin/env python3
"""Render a lamp preset with the Lamp Tracer and with Cycles; write the two side by side.

With Blender:
    blender --background --python tools/compare_preset.py -- PRESET.json -o out/compare.png [options]
With the bpy module (the project's .venv):
    .venv/bin/python tools/compare_preset.py PRESET.json -o out/compare.png [--samples N] [--size WxH]
        [--view AgX] [--exposure EV|auto]

The extension is used from this source tree through a temporary development repository
(``tools/dev_extension.py``; an already enabled Lamp Styling extension is used instead). The job
starts from an empty scene, so the preset's camera is the view. It prints both render times and the
per-channel differences.
Exit status: 0 done, 2 bad arguments or preset (one line on stderr).
"""

from __future__ import annotations

import argparse
import importlib
import os
import shutil
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from core_tracer.cli.common import add_display_arguments  # noqa: E402 (bpy-free: safe before Blender starts)
from tools import dev_extension  # noqa: E402

DEV_REPO = "lamp_styling_dev"
PROG = "compare_preset"
MAX_SIDE = 8192


def _size(text: str) -> tuple[int, int]:
    try:
        width, height = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not WIDTHxHEIGHT, e.g. 256x256") from None
    if not (1 <= width <= MAX_SIDE and 1 <= height <= MAX_SIDE):
        raise argparse.ArgumentTypeError(f"{text}: each side must be in [1, {MAX_SIDE}] px")
    return width, height


def _samples(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
    if not 1 <= value <= 65536:
        raise argparse.ArgumentTypeError(f"{value} is out of range; allowed [1, 65536]")
    return value


def parse_args(argv: list[str]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n\n")[0])
    parser.add_argument("preset", help="a lamp-scene/1 JSON file, e.g. presets/paper-baseline.json")
    parser.add_argument("-o", "--output", default=os.path.join("out", "compare.png"),
                        help="side-by-side image to write, .png (view transform, both halves at one exposure) or "
                             ".exr (linear); default out/compare.png")
    parser.add_argument("--samples", type=_samples, default=64, help="Cycles samples per pixel (default 64)")
    parser.add_argument("--size", type=_size, default=None,
                        help="render size WIDTHxHEIGHT (default: the preset's image size)")
    add_display_arguments(parser)
    return parser.parse_args(argv)


def script_argv(in_blender: bool) -> list[str]:
    """The script's own arguments: after ``--`` inside Blender, else everything after the script."""
    if "--" in sys.argv:
        return sys.argv[sys.argv.index("--") + 1:]
    return [] if in_blender else sys.argv[1:]


def main() -> int:
    in_blender = "bpy" in sys.modules  # Blender imports bpy before it runs a --python script
    args = parse_args(script_argv(in_blender))
    own_resources = None
    if not in_blender and "BLENDER_USER_RESOURCES" not in os.environ:
        # Keep Blender's configuration and extensions out of the user's home (set before import bpy).
        own_resources = tempfile.mkdtemp(prefix="lamp-blender-user-")
        os.environ["BLENDER_USER_RESOURCES"] = own_resources
    try:
        import bpy

        bpy.ops.wm.read_homefile(use_empty=True)  # an empty scene: the preset's camera is the view
        with dev_extension.enabled_from_source(bpy, DEV_REPO) as package:
            headless = importlib.import_module(f"{package}.lamp_addon.compare.headless")
            return headless.run(args.preset, args.output, samples=args.samples, size=args.size,
                                view=args.view, exposure=args.exposure, prog=PROG)
    finally:
        if own_resources is not None:
            shutil.rmtree(own_resources, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())

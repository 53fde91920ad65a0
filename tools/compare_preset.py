#!/usr/bin/env python3
"""Render a lamp preset with the Lamp Tracer and with Cycles; write the two side by side.

With Blender:
    blender --background --python tools/compare_preset.py -- PRESET.json -o out/compare.png [options]
With the bpy module (the project's .venv):
    .venv/bin/python tools/compare_preset.py PRESET.json -o out/compare.png [--samples N] [--size WxH]
        [--view AgX] [--exposure EV|auto]

The extension is used from this source tree through a temporary development repository (an
already enabled Lamp Styling extension is used instead). The job starts from an empty scene, so
the preset's camera is the view. It prints both render times and the per-channel differences.
Exit status: 0 done, 2 bad arguments or preset (one line on stderr).
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import os
import shutil
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from core_tracer.cli.common import add_display_arguments  # noqa: E402 (bpy-free: safe before Blender starts)

EXTENSION_ID = "lamp_styling"
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


@contextlib.contextmanager
def extension(bpy):
    """The enabled extension's package name (``bl_ext.<repo>.lamp_styling``): an enabled one, or this
    source tree through a temporary development repository, removed again afterwards."""
    import addon_utils

    prefs = bpy.context.preferences
    enabled = [a.module for a in prefs.addons if a.module.rsplit(".", 1)[-1] == EXTENSION_ID]
    if enabled:
        yield enabled[0]
        return
    folder = tempfile.mkdtemp(prefix="lamp-dev-repo-")
    try:
        try:
            os.symlink(ROOT, os.path.join(folder, EXTENSION_ID), target_is_directory=True)
        except OSError:  # no symlinks (Windows without the privilege): copy what the zip would hold
            shutil.copytree(ROOT, os.path.join(folder, EXTENSION_ID),
                            ignore=shutil.ignore_patterns(".*", "__pycache__", "tests", "tools", "out", "dist"))
        repo = prefs.extensions.repos.new(name=DEV_REPO, module=DEV_REPO, custom_directory=folder, source="USER")
        package = f"bl_ext.{DEV_REPO}.{EXTENSION_ID}"

        def fail(e: BaseException) -> None:
            raise e

        addon_utils.enable(package, default_set=True, handle_error=fail)
        try:
            yield package
        finally:
            prefs.extensions.repos.remove(repo)  # disables the repository's add-ons too
    finally:
        shutil.rmtree(folder, ignore_errors=True)


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
        with extension(bpy) as package:
            headless = importlib.import_module(f"{package}.lamp_addon.compare_headless")
            return headless.run(args.preset, args.output, samples=args.samples, size=args.size,
                                view=args.view, exposure=args.exposure, prog=PROG)
    finally:
        if own_resources is not None:
            shutil.rmtree(own_resources, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())

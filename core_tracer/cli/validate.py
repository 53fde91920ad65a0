"""``validate SCENE.json``: check a scene file without rendering it."""

from __future__ import annotations

import argparse

from ..scene.safe_text import printable
from .common import load_scene_file

HELP = "check a lamp-scene file and report the first problem"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scene", metavar="SCENE.json", help="the scene file")


def run(args: argparse.Namespace) -> int:
    scene = load_scene_file(args.scene)
    lamps = len(scene["lamps"])
    image = scene["image"]
    print(f"{printable(args.scene)}: valid {scene['schema']}, \"{printable(scene['name'])}\", "
          f"{lamps} lamp{'s' if lamps > 1 else ''}, "
          f"{image['width']}x{image['height']} px")
    return 0

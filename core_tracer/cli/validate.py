"""``validate SCENE.json``: check a scene file without rendering it."""

from __future__ import annotations

import argparse

from .common import load_scene_file

HELP = "check a lamp-scene/1 file and report the first problem"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scene", metavar="SCENE.json", help="the scene file")


def run(args: argparse.Namespace) -> int:
    scene = load_scene_file(args.scene)
    lamps = len(scene["lamps"])
    image = scene["image"]
    print(f"{args.scene}: valid {scene['schema']}, \"{scene['name']}\", {lamps} lamp{'s' if lamps > 1 else ''}, "
          f"{image['width']}x{image['height']} px")
    return 0

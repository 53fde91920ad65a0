"""``render SCENE.json -o OUT.exr|OUT.png``: trace a scene to an image file."""

from __future__ import annotations

import argparse
import os
import time

from ..images.imageio import image_format
from ..scene.validate import SceneError
from .common import add_display_arguments, ctrl_c_sets, load_scene_file, view_for

HELP = "render a scene to an .exr (linear, scene in the header) or .png (view transform, exposure) image"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scene", metavar="SCENE.json", help="the scene file")
    parser.add_argument("-o", "--output", required=True, metavar="OUT", help="image file, .exr or .png")
    parser.add_argument("--width", type=int, metavar="W", help="image width in pixels (overrides the scene)")
    parser.add_argument("--height", type=int, metavar="H", help="image height in pixels (overrides the scene)")
    parser.add_argument("--passes", metavar="DIR",
                        help="also write one .exr per contribution pass (lens surface, bulb, ...) into DIR")
    add_display_arguments(parser)


def _check_folder(path: str, what: str) -> None:
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise SceneError(path, f"the {what} folder {folder} does not exist")


def run(args: argparse.Namespace) -> int:
    # Every check on the user's input happens before the (long) render.
    fmt = image_format(args.output)
    _check_folder(args.output, "output")
    view = view_for(args) if fmt == "png" else None
    if args.passes is not None and os.path.exists(args.passes) and not os.path.isdir(args.passes):
        raise SceneError(args.passes, "--passes must name a folder; this is a file")
    scene = load_scene_file(args.scene, args.width, args.height)

    from .. import RenderCancelled, render_passes  # the tracer loads only when it is needed
    from ..images.imageio import write_image

    start = time.perf_counter()
    with ctrl_c_sets() as stop:
        try:
            result = render_passes(scene, should_stop=stop.is_set)
        except RenderCancelled:
            raise KeyboardInterrupt from None
    if stop.is_set():  # Ctrl-C after the last band: still nothing is written
        raise KeyboardInterrupt
    seconds = time.perf_counter() - start

    if args.passes is not None:
        os.makedirs(args.passes, exist_ok=True)
        for name, data in result.passes.items():
            write_image(os.path.join(args.passes, f"{name}.exr"), data, scene)
    ev = write_image(args.output, result.image, scene, view=view, exposure=args.exposure)

    h, w = result.image.shape[:2]
    segments = result.stats.get("segments")
    traced = f", {segments} ray segments" if segments is not None else ""
    shown = f", {view.view} at {ev:+.1f} EV" if view is not None else ""
    print(f"{args.output}: {w}x{h} px in {seconds:.2f} s{traced}{shown}")
    return 0

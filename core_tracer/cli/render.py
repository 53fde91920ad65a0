"""``render SCENE.json -o OUT.exr|OUT.png``: trace a scene to an image file."""

from __future__ import annotations

import argparse
import os
import time

from .. import budget
from ..checkpoints import checkpoint
from ..fileio import atomic_folder, check_replaceable_folder, is_pass_file
from ..images.imageio import image_format
from ..scene.beside import environment_file
from ..scene.reading import SceneError
from ..scene.safe_text import printable
from .common import (
    add_image_arguments,
    check_output,
    check_output_folder,
    ctrl_c_sets,
    design_meshes,
    load_scene_file,
    photometric_stops,
    traced_scene,
    view_for,
)

PASSES = "passes (.exr files)"
HELP = "render a scene to an .exr (linear, scene in the header) or .png (view transform, exposure) image"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scene", metavar="SCENE.json", help="the scene file")
    parser.add_argument("-o", "--output", required=True, metavar="OUT", help="image file, .exr or .png")
    parser.add_argument("--width", type=int, metavar="W", help="image width in pixels (overrides the scene)")
    parser.add_argument("--height", type=int, metavar="H", help="image height in pixels (overrides the scene)")
    parser.add_argument("--samples", type=int, metavar="N",
                        help="samples per pixel, 1 (the pixel centre, the paper's setting) or more for smooth "
                             "edges (overrides the scene)")
    parser.add_argument("--passes", metavar="DIR",
                        help="also write one .exr per contribution pass (lens surface, bulb, ...) into DIR")
    parser.add_argument("--environment", metavar="IMAGE",
                        help="your own environment image (.exr or .hdr, any folder) as the surroundings, in place "
                             "of the scene's; a scene file names only an image beside it or a bundled world")
    add_image_arguments(parser)


def run(args: argparse.Namespace) -> int:
    # Every check on the user's input happens before the (long) render: the files can be written,
    # the scene is valid, and the render fits the memory budget.
    file_format = image_format(args.output)
    check_output(args.output, "output")
    view = view_for(args) if file_format == "png" else None
    if args.passes is not None:
        _check_passes_folder(args.passes, args.output)
    scene = load_scene_file(args.scene, args.width, args.height, args.samples)
    _check_photometric_options(args, scene)
    traced, scene = _with_environment(args, scene)
    traced = traced_scene(args.scene, traced)
    meshes = design_meshes(args.scene, scene)
    keep_passes = args.passes is not None
    size = scene["image"]
    from ..raytrace import environment  # numpy and OpenImageIO: the image's header is read here

    world = environment.world_bytes(traced)  # the header checked before any pixel is read
    glow = scene["glare"]["on"]
    workers = budget.pool_workers(size["width"], size["height"], size["samples"], keep_passes, file_format, glow,
                                  world, os.cpu_count() or 1) if meshes is None else 0
    budget.check_render(size["width"], size["height"], keep_passes, file_format, glare=glow,
                        samples=size["samples"], environment=world, workers=workers)
    checkpoint("render:checked")

    from .. import RenderCancelled, render_passes  # the tracer loads only when it is needed
    from ..images import glare
    from ..images.imageio import load_writer

    load_writer()

    start = time.perf_counter()
    with ctrl_c_sets() as stop:
        try:
            if meshes is None:
                # A heavy render starts worker processes for its bands (about 0.2 s, then twice
                # the speed of threads on two cores), where the budget holds them; a light one is
                # done before they would be up (and never imports the pool).
                pool = None
                if workers:
                    from ..raytrace import band_pool  # only for heavy renders (start-up speed)

                    pool = band_pool.shared()
                result = render_passes(traced, should_stop=stop.is_set, keep_passes=keep_passes,
                                       progress=lambda fraction: checkpoint("render:band"), pool=pool)
            else:
                result = meshes.render_passes(traced, should_stop=stop.is_set,
                                              progress=lambda fraction: checkpoint("render:band"))
        except RenderCancelled:
            raise stop.interrupt() from None
        image = glare.apply(result.image, scene)  # the image file holds the glare; the passes do not
    _check_finite(image, result.passes, traced)
    seconds = time.perf_counter() - start
    checkpoint("render:rendered")

    write, write_pass = _writers(args, scene, image, result.stats, view)
    if args.passes is None:
        shown = write()
    else:  # the passes of this render only, put in place once they and the image are all written
        with atomic_folder(args.passes, is_pass_file, PASSES) as folder:
            for name, data in result.passes.items():
                write_pass(os.path.join(folder, f"{name}.exr"), data)
                checkpoint("render:pass")
            shown = write()

    h, w = image.shape[:2]
    segments = result.stats.get("segments")
    traced = f", {segments} ray segments" if segments is not None else ""
    if segments is not None and result.stats.get("max_depth"):
        # how deep the paths went, and the branches the depth limit ended (never dropped silently)
        traced += (f" ({segments / (w * h * size['samples']):.1f} a ray, deepest {result.stats['max_depth']}, "
                   f"{result.stats.get('cut_at_depth', 0)} ended at the depth limit)")
    samples = f" at {size['samples']} samples" if size["samples"] > 1 else ""
    print(f"{printable(args.output)}: {w}x{h} px{samples} in {seconds:.2f} s{traced}{shown}")
    return 0


def _check_photometric_options(args: argparse.Namespace, scene: dict) -> None:
    """Before the render: ``--ev100``, ``--false-color`` and ``--luminance-range`` fit the scene and the output."""
    if scene.get("light_model", "paper") != "photometric":
        for option, given in (("--ev100", args.ev100 is not None), ("--false-color", args.false_color),
                              ("--luminance-range", args.luminance_range is not None)):
            if given:
                raise SceneError(option, 'is for photometric scenes; allowed with "light_model": "photometric"')
        return
    if args.luminance_range is not None and not args.false_color:
        raise SceneError("--luminance-range", "is the scale of --false-color; allowed with --false-color")
    if args.false_color and image_format(args.output) != "png":
        raise SceneError("--false-color", "draws a .png (an .exr holds the luminance itself, channel Y); allowed "
                                          "with -o OUT.png")


def _writers(args: argparse.Namespace, scene: dict, image, stats: dict, view):
    """(write the image and say in words what it shows, write a pass) for the scene's light model:
    the paper mode's linear RGB as ever; the photometric mode's XYZ in cd/m² at one EV100
    (``images.photometric``)."""
    from ..images.imageio import write_image

    if stats.get("light_model") != "photometric":

        def write() -> str:
            ev = write_image(args.output, image, scene, view=view, exposure=args.exposure)
            return f", {view.view} at {ev:+.1f} EV" if view is not None else ""

        return write, lambda path, data: write_image(path, data, scene)

    from ..images import photometric
    from ..photometry.bands import Bands
    from ..raytrace import spectral_bands

    bands = Bands(stats["band_edges_nm"])  # the render's own (``raytrace.spectral_bands``)
    bands_words = spectral_bands.words(bands)
    ev100 = photometric.ev100_for(image, scene, args.ev100)
    stops = photometric_stops(args)
    false_colour = (args.luminance_range or (None, None)) if args.false_color else None

    def write() -> str:
        photometric.write_render(args.output, image, scene, ev100=ev100, view=view, stops=stops, bands=bands,
                                 false_colour=false_colour)
        if image_format(args.output) == "exr":
            return f", XYZ (Y in cd/m2) on {bands_words}"
        if false_colour is not None:
            return f", false colour of luminance in cd/m2 on {bands_words}"
        extra = f" {stops:+.1f} EV" if stops else ""
        return f", {view.view} at EV100 {ev100:.1f}{extra} on {bands_words}"

    return write, lambda path, data: photometric.write_pass(path, data, scene, bands)


def _with_environment(args: argparse.Namespace, scene: dict) -> tuple[dict, dict]:
    """(the scene to trace, the scene the files record): the environment image is the one
    ``--environment`` gives (the files name it by its file name), else the scene's own, confined to
    the scene file's folder (``scene.beside``) and traced by its full path, whatever the working
    directory."""
    env = scene["environment"]
    if args.environment is not None:
        path = os.path.abspath(os.path.expanduser(args.environment))
        if not os.path.isfile(path):
            raise SceneError("--environment", f"{printable(args.environment, 200)!r} does not exist; allowed an "
                                              "existing .exr or .hdr file")
        recorded = {**scene, "environment": {**env, "world": "file", "file": os.path.basename(path)}}
        return {**scene, "environment": {**env, "world": "file", "file": path}}, recorded
    path = environment_file(args.scene, env)
    if path is None:
        return scene, scene
    return {**scene, "environment": {**env, "file": path}}, scene


def _check_finite(image, passes: dict, scene: dict) -> None:
    """No inf or NaN reaches a file (the environment's values are bounded, ``world_image``: this
    is the last guard)."""
    import numpy as np

    if np.isfinite(image).all() and all(np.isfinite(p).all() for p in passes.values()):
        return
    env = scene["environment"]
    source = f"; the environment image {printable(env['file'], 200)!r} is too bright" if env["world"] == "file" else ""
    raise SceneError("image", f"the render holds values that are not finite numbers{source}; allowed finite "
                              "images only (nothing was written)")


def _check_passes_folder(passes: str, output: str) -> None:
    """Before the render: the passes can be written beside the folder, which is new or holds the
    passes of an earlier render only (replaced whole), and does not hold the output image."""
    check_output_folder(passes, "--passes")
    check_output_folder(os.path.dirname(os.path.abspath(passes)) or os.sep, "--passes")
    try:
        check_replaceable_folder(passes, is_pass_file, PASSES)
    except OSError as e:
        raise SceneError(passes, f"--passes {e.strerror}") from None
    if os.path.realpath(os.path.dirname(os.path.abspath(output))) == os.path.realpath(passes):
        raise SceneError(passes, "--passes holds the output image; allowed a folder apart from -o (it is "
                                 "replaced whole by the passes)")

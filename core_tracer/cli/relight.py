"""``relight STATES.npz -o OUT.png|OUT.exr``: the image of a design under other lighting states,
from the passes ``states`` rendered, without rendering (docs/measures.md, "Lighting states")."""

from __future__ import annotations

import argparse
import math
import os
import time

from ..images.imageio import image_format
from ..scene.reading import SceneError
from ..scene.safe_text import printable
from .common import add_image_arguments, check_output, view_for

HELP = "switch a design's functions on or off and change bulb fluxes on the passes 'states' wrote, without rendering"
MAX_BYTES = 2_000_000_000


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("states", metavar="STATES.npz", help="a file the 'states' command wrote")
    parser.add_argument("-o", "--output", metavar="OUT", help="image file, .exr or .png")
    parser.add_argument("--list", action="store_true", help="list the states and what the design has lit")
    parser.add_argument("--on", action="append", default=[], metavar="KEY[,KEY]",
                        help="switch these states on, named by the lamp's function (e.g. stop, turn, "
                             "tail.stop_filament; 'surroundings' for sun and sky; --list names them; the "
                             "keys of earlier versions, lamps[0].stop, still work)")
    parser.add_argument("--off", action="append", default=[], metavar="KEY[,KEY]", help="switch these states off")
    parser.add_argument("--level", action="append", default=[], metavar="KEY=VALUE",
                        help="a state's flux in lm (photometric bulbs) or scale (paper bulbs, surroundings); "
                             "giving one switches the state on")
    add_image_arguments(parser)


def _keys(values: list[str]) -> list[str]:
    return [key.strip() for value in values for key in value.split(",") if key.strip()]


def _levels(values: list[str]) -> dict[str, float]:
    out = {}
    for value in values:
        key, _, number = value.partition("=")
        try:
            level = float(number)
        except ValueError:
            raise SceneError("--level", f"{printable(value)!r} is not KEY=VALUE; allowed e.g. "
                                        "stop=500") from None
        if not math.isfinite(level):
            raise SceneError("--level", f"{printable(value)!r} is not a finite number; allowed [0, 100000]")
        out[key.strip()] = level
    return out


def run(args: argparse.Namespace) -> int:
    from ..measures import states as S

    if not os.path.isfile(args.states):
        raise SceneError(args.states, "does not exist or is not a file; allowed a file the 'states' command wrote")
    if os.path.getsize(args.states) > MAX_BYTES:
        raise SceneError(args.states, f"is larger than {MAX_BYTES // 1_000_000} MB; allowed a file 'states' wrote")
    if args.output is None and not args.list:
        raise SceneError("--output", "is missing; allowed -o OUT.png or OUT.exr, or --list")
    if args.output is not None:
        check_output(args.output, "output")
    from .. import budget

    def beside(scene: dict) -> int:  # relight's own footprint beside the arrays (budget.render_bytes)
        if args.output is None:
            return 0
        size = scene["image"]
        return budget.render_bytes(size["width"], size["height"], False, image_format(args.output),
                                   scene["glare"]["on"]) - budget.BASE_BYTES

    with open(args.states, "rb") as f:
        light = S.from_bytes(f.read(), printable(args.states), beside=beside)
    if args.list:
        for state in light.states:
            lit = "on " if state.lit_in_design else "off"
            level = f"{state.rendered:g} lm" if state.unit else "x1"
            also = f" (also {state.alias})" if state.alias else ""
            print(f"{lit} {state.key:<24} {level:>8}  {state.label}{also}")
        if args.output is None:
            return 0
    on = {light.state(key).key: True for key in _keys(args.on)}  # an earlier version's key: the state's own
    for key in _keys(args.off):
        if light.state(key).key in on:
            raise SceneError("--off", f"{printable(key)} is also given to --on; allowed each state once")
        on[light.state(key).key] = False
    start = time.perf_counter()
    weights = S.weights_for(light, on, _levels(args.level))
    image = S.with_glare(light, S.relight(light, weights))
    seconds = time.perf_counter() - start

    from .render import _check_photometric_options, _writers

    _check_photometric_options(args, light.scene)
    view = view_for(args) if image_format(args.output) == "png" else None
    write, _ = _writers(args, light.scene, image, light.stats, view)
    shown = write()
    lit = ", ".join(f"{key}" + (f" x{w:.3g}" if w != 1.0 else "") for key, w in weights.items() if w) or "nothing"
    print(f"{printable(args.output)}: {image.shape[1]}x{image.shape[0]} px in {1000 * seconds:.1f} ms{shown}; "
          f"lit: {lit}")
    return 0

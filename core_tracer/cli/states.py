"""``states SCENE.json -o STATES.npz``: render a design's lighting states once, to re-weight later
with ``relight`` (docs/measures.md, "Lighting states")."""

from __future__ import annotations

import argparse
import os
import sys

from ..fileio import atomic_write_bytes
from ..scene.reading import SceneError
from ..scene.safe_text import printable
from .common import check_output, ctrl_c_sets, design_meshes, load_scene_file, traced_scene

HELP = ("render the surroundings and one pass per bulb and filament of a design, so that 'relight' switches "
        "functions and changes fluxes without rendering")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scene", metavar="SCENE.json", help="the scene file (parametric designs)")
    parser.add_argument("-o", "--output", required=True, metavar="STATES.npz", help="the light-states file")
    parser.add_argument("--width", type=int, metavar="W", help="image width in pixels (overrides the scene)")
    parser.add_argument("--height", type=int, metavar="H", help="image height in pixels (overrides the scene)")
    parser.add_argument("--samples", type=int, metavar="N", help="samples per pixel (overrides the scene)")


def run(args: argparse.Namespace) -> int:
    if not args.output.lower().endswith(".npz"):
        raise SceneError("--output", f"{printable(args.output)!r} is not a light-states file; allowed a name ending "
                                     ".npz")
    check_output(args.output, "output")
    scene = load_scene_file(args.scene, args.width, args.height, args.samples)
    meshes = design_meshes(args.scene, scene)
    from .. import budget
    from ..measures import states as S
    from ..raytrace import environment
    from ..raytrace.engine import RenderCancelled
    from ..scene.beside import environment_file

    # The whole footprint before the first render (issue 33), as ``render`` counts its own.
    size = scene["image"]
    path = environment_file(args.scene, scene["environment"])
    traced = traced_scene(args.scene, scene)  # the measured curves by their full paths beside the file
    traced = traced if path is None else {**traced, "environment": {**traced["environment"], "file": path}}
    # A parametric design's states are one walk keeping each source's light (``states.one_walk``),
    # its bands on the band pool's workers as a render's where they fit; a free-form one's a render each.
    count = len(S.states_of(scene)) - 1
    sources = 1 + len(scene["lamps"]) if meshes is None else 0
    world = environment.world_bytes(traced)
    workers = 0
    if meshes is None and budget.uses_pool(size["width"], size["height"], size["samples"]):
        workers = os.cpu_count() or 1
        if budget.states_bytes(size["width"], size["height"], count, "exr", workers, world, sources) > \
                budget.MEMORY_BUDGET:
            workers = 0
    budget.check_states(size["width"], size["height"], size["samples"], count, workers=workers, environment=world,
                        sources=sources)
    pool = None
    if workers:
        from ..raytrace import band_pool  # only for heavy walks (start-up speed)

        pool = band_pool.shared()

    def progress(done: int, total: int, label: str) -> None:
        if sources and done == 0:
            print(f"one walk for {label}", flush=True)
        elif not sources:
            print(f"state {done + 1} of {total}: {label}", flush=True)

    with ctrl_c_sets() as stop:
        try:
            light = S.render_states(traced, progress=progress, should_stop=stop.is_set, meshes=meshes,
                                    recorded=scene, pool=pool)
        except RenderCancelled:
            raise stop.interrupt() from None
    atomic_write_bytes(args.output, S.to_bytes(light))
    for state in light.states:
        lit = "on " if state.lit_in_design else "off"
        level = f"{state.rendered:g} lm" if state.unit else "x1"
        print(f"  {lit} {state.key:<16} {level:>8}  {state.label}")
    print(f"{printable(args.output)}: {len(light.states) - 1} states and the surroundings", file=sys.stdout)
    return 0

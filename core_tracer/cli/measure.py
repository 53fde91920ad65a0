"""``measure SCENE.json -o report/``: the measures a lamp engineer signs (docs/measures.md)."""

from __future__ import annotations

import argparse
import os

from ..fileio import atomic_folder, check_replaceable_folder
from ..scene.reading import SceneError
from ..scene.safe_text import printable
from .common import check_output_folder, design_meshes, load_scene_file, traced_scene

HELP = "measure a photometric design: intensity grids (UN R148, FMVSS 108), colour, homogeneity, IES/LDT, report"
OUTPUTS = ("measures.json", "measures.png")
FUNCTION_NAMES = ("tail", "stop", "turn", "reversing")
EXIT_FAILS = 1  # a regulation fails (``--exit-zero`` keeps 0); bad input is 2 (cli.main)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scene", metavar="SCENE.json", help="a photometric scene file")
    parser.add_argument("-o", "--output", required=True, metavar="DIR",
                        help="folder for measures.json, measures.png and one .ies and .ldt per function")
    parser.add_argument("--function", action="append", default=[], metavar="LAMP=NAME",
                        help="what lamp LAMP (from 0) is for, one of tail, stop, turn, reversing (default: its "
                             "function field, or for a custom lamp its lens filter and bulb filament)")
    parser.add_argument("--pixel-mm", type=float, default=2.0, metavar="MM",
                        help="pixel size of the measuring views in mm (default 2)")
    parser.add_argument("--replicates", type=int, default=2, metavar="N",
                        help="shifted renders per direction, for the standard error (default 2)")
    parser.add_argument("--distance-m", type=float, default=10.0, metavar="M",
                        help="viewing distance for the homogeneity figures (default 10 m: the eye resolves 2.9 mm)")
    parser.add_argument("--no-beam-files", action="store_true", help="skip the IES and EULUMDAT files")
    parser.add_argument("--beam-grid", default="10,2.5,5", metavar="C,GAMMA[,FAR]",
                        help="the beam files' angles in degrees: C every C, γ every GAMMA to 50° and every FAR "
                             "beyond (default 10,2.5,5: 1009 directions, the files integrate to the flux out within "
                             "0.1 %%; 30,10,10 is quick and coarse)")
    parser.add_argument("--exit-zero", action="store_true",
                        help="exit 0 when a regulation fails (default: exit 1, so a script or CI job notices)")


def _functions(values: list[str], lamps: int) -> dict[int, str]:
    out = {}
    for value in values:
        lamp, _, name = value.partition("=")
        if not lamp.isdigit() or int(lamp) >= lamps or name not in FUNCTION_NAMES:
            raise SceneError("--function", f"{printable(value)!r} is not LAMP=NAME; allowed LAMP from 0 to "
                                           f"{lamps - 1} and NAME one of {', '.join(FUNCTION_NAMES)}")
        out[int(lamp)] = name
    return out


def run(args: argparse.Namespace) -> int:
    for option, value, lo, hi in (("--pixel-mm", args.pixel_mm, 0.05, 20.0), ("--replicates", args.replicates, 1, 64),
                                  ("--distance-m", args.distance_m, 0.1, 1000.0)):
        if not (lo <= value <= hi):
            raise SceneError(option, f"{value!r} is outside the allowed {lo:g} to {hi:g}")
    from ..measures.export import BeamGrid  # the grid is checked before any work, as every option

    try:
        grid = BeamGrid.parse(args.beam_grid)
    except ValueError as e:
        raise SceneError("--beam-grid", str(e)) from None
    check_output_folder(args.output, "--output")  # its parent exists and is writable: before a minute's work
    check_replaceable_folder(args.output, _ours, "measures")
    scene = traced_scene(args.scene, load_scene_file(args.scene))
    meshes = design_meshes(args.scene, scene)  # a free-form design is measured on its meshes, as one lamp
    functions = _functions(args.function, 1 if meshes is not None else len(scene["lamps"]))
    from ..measures import export, report  # numpy, the tracer and matplotlib: loaded once the input is checked

    report.check_memory(scene, args.pixel_mm)  # the whole footprint before the first view (issue 33)

    result = report.measure(scene, functions=functions, pixel_mm=args.pixel_mm, replicates=args.replicates,
                            distance_m=args.distance_m, progress=lambda text: print(text, flush=True),
                            meshes=meshes, beams=None if args.no_beam_files else grid)  # one sweep for both
    picture = report.lamp_picture(scene, meshes=meshes)
    with atomic_folder(args.output, _ours, "measures") as folder:
        for name, dist in result.beams.items():
            export.write_ies(dist, os.path.join(folder, f"{name}.ies"))
            export.write_ldt(dist, os.path.join(folder, f"{name}.ldt"))
        report.write_json(result, os.path.join(folder, "measures.json"))
        report.write_page(result, os.path.join(folder, "measures.png"), picture)
    verdicts = result.verdicts()
    failing = [k for k, ok in verdicts.items() if not ok]
    print(f"{printable(args.output)}: {'fails ' + ', '.join(failing) if failing else 'passes every check'} "
          f"({sum(verdicts.values())} of {len(verdicts)} regulations pass)")
    return EXIT_FAILS if failing and not args.exit_zero else 0


def _ours(name: str) -> bool:
    return name in OUTPUTS or name.endswith((".ies", ".ldt"))

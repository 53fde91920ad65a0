"""``study BASE.json --vary P=LO:HI:STEPS [--vary ...] -o SHEET``: a design study on a contact sheet.

Also ``study --study STUDY.json|SHEET.exr|SHEET.png -o SHEET`` re-runs a saved study (a sheet
carries its study in its header), and ``study --list`` prints the parameters a study can vary.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import os
import re
import shutil
import sys
import time

from .. import budget
from ..checkpoints import checkpoint
from ..fileio import atomic_folder, check_replaceable_folder
from ..images import display
from ..images.imageio import image_format
from ..scene.reading import SceneError, read_json
from ..scene.safe_text import printable
from ..study import definition as st
from ..study.measured import measured_doc
from ..study.parameters import study_parameters
from . import common

VARIANTS = "variant presets (variant-NN.json)"
HELP = "render variants of a design (one or two parameters varied) on a labelled contact sheet"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("base", nargs="?", metavar="BASE.json", help="the design to vary (a lamp-scene/1 file)")
    parser.add_argument("--vary", action="append", default=[], metavar="PARAM=SPEC",
                        help="a parameter and its values: lens.ior=1.45:1.6:4 (lo:hi:steps), "
                             "cuts.height=0.5,1,2 (a list), lens.transmitted_color=0.9/0.1/0.1,0.9/0.5/0.05 "
                             "(colours), cuts.type=fisheye,sawtooth,flutes (names of a choice); "
                             "lamps[1].lens.ior names one lamp; once or twice")
    parser.add_argument("--study", metavar="STUDY", help="re-run a study: a .json definition or a sheet .exr/.png")
    parser.add_argument("-o", "--output", metavar="SHEET",
                        help="the contact sheet, .png (view transform) or .exr (linear)")
    parser.add_argument("--size", metavar="WxH", help="size of each variant image (default: framed on the lamp, "
                                                      "the body's aspect at about "
                                                      f"{st.DEFAULT_SIZE[0]}x{st.DEFAULT_SIZE[1]} pixels)")
    parser.add_argument("--title", help="the sheet's title (default: the design's name)")
    parser.add_argument("--workers", type=int, metavar="N",
                        help="worker processes of a local cluster or pool (default: one per core; 0 renders in "
                             "this process)")
    parser.add_argument("--engine", choices=("dask", "processes"),
                        help="dask: each variant a task on a Dask cluster (a local one without --scheduler); "
                             "processes: the project's own worker processes, no cache (default: each variant a task "
                             "on the local worker pool, results cached by content; Dask with --scheduler)")
    parser.add_argument("--scheduler", metavar="ADDRESS",
                        help="a Dask scheduler, tcp://HOST:8786 (default: $DASK_SCHEDULER_ADDRESS, else the local "
                             "worker pool; \"local\" starts a local Dask cluster); docs/cluster.md")
    parser.add_argument("--cache", metavar="DIR", help="the folder of rendered cells kept by content (default: "
                                                       "the per-user cache, lamp-styling/cells)")
    parser.add_argument("--no-cache", action="store_true", help="render every variant, keep none")
    parser.add_argument("--save-study", metavar="STUDY.json", help="write the study definition (base embedded)")
    parser.add_argument("--save-variants", metavar="DIR", help="write every variant as a lamp-scene/1 preset")
    common.add_image_arguments(parser, view=display.LAMP_VIEW, false_colour=False)  # a sheet of lamps: the lamp view
    parser.add_argument("--list", action="store_true", help="list the parameters a study can vary and exit")
    parser.add_argument("--measure", action="append", default=[], metavar="NAME",
                        help="a measure to put under each cell (photometric designs; e.g. homogeneity.lmin_lmax, "
                             "grid.min_margin, intensity.hv_cd@stop: docs/measures.md); tens of seconds a variant")
    parser.add_argument("--sort", metavar="[-]NAME",
                        help="order the cells by a measure; --sort=-NAME for highest first")
    parser.add_argument("--filter", action="append", default=[], metavar="NAME<OP>NUMBER",
                        help="keep the variants where a measure holds, e.g. 'grid.pass==1' (the others are listed "
                             "in the sheet's footer)")


def _size(text: str) -> tuple[int, int]:
    parts = text.lower().split("x")
    try:
        size = [int(p) for p in parts]
    except ValueError:
        size = []
    if len(size) != 2:
        raise SceneError("--size", f"{text!r} is not WIDTHxHEIGHT (e.g. 256x256)")
    return st.parse_size(size, "--size")


def _measured(args: argparse.Namespace) -> dict:
    """The study fields of ``--measure``, ``--sort`` and ``--filter`` (those given)."""
    return measured_doc(args.measure, args.sort, args.filter)


def _with_options(error: SceneError) -> SceneError:
    """A study-field error in the words of the command line (``measures[0]`` -> ``--measure``)."""
    for field, option in (("measures", "--measure"), ("sort", "--sort"), ("filter", "--filter")):
        if error.path == field or error.path.startswith(f"{field}["):
            return SceneError(option, error.message)
    return error


def _build(args: argparse.Namespace) -> st.Study:
    size = _size(args.size) if args.size else None
    measured = _measured(args)
    if args.study:
        if args.base or args.vary:
            raise SceneError("--study", "re-runs a saved study; give it without BASE.json and --vary")
        study = st.Study.load(args.study)
        if size is None and args.title is None and not measured:
            return study
        doc = study.to_doc()
        if size is not None:
            doc["size"] = list(size)
        if args.title is not None:
            doc["title"] = args.title
        doc.update(measured)
        try:
            return st.Study.from_doc(doc)
        except SceneError as e:
            raise _with_options(e) from None
    if not args.base:
        raise SceneError("study", "give BASE.json with --vary, or --study STUDY")
    if not args.vary:
        raise SceneError("--vary", "is required: one or two parameters to vary, e.g. --vary lens.ior=1.45:1.6:4")
    if len(args.vary) > st.MAX_AXES:
        raise SceneError("--vary", f"given {len(args.vary)} times; a study varies 1 or {st.MAX_AXES} parameters")
    base = read_json(args.base)
    axes = [st.parse_vary(v) for v in args.vary]
    try:
        return st.Study.build(base, axes, size, args.title or "", measured)  # None: framed on the lamp
    except SceneError as e:
        if e.path == "base" or e.path.startswith("base."):  # a problem of the design file itself
            raise common.in_file(SceneError(e.path[len("base."):], e.message), args.base) from None
        raise _with_options(e) from None


def _with_environment(study: st.Study, document: str) -> tuple[st.Study, int]:
    """(the study to render, the bytes of its largest world): the base's environment image is the
    one beside ``document`` (``scene.beside``), rendered by its full path whatever the working
    directory; every variant's image is checked by its header, then read and made into its world
    (``raytrace.world_cache``), before any worker starts."""
    from ..raytrace import environment  # numpy and OpenImageIO: the images' headers are read here
    from ..scene.beside import environment_file

    try:
        path = environment_file(document, study.base["environment"])
    except SceneError as e:
        raise common.in_file(SceneError(f"base.{e.path}", e.message), document) from None
    runnable = study
    if path is not None:
        doc = study.to_doc()
        doc["base"]["environment"]["file"] = path
        runnable = st.Study.from_doc(doc)
    worlds = {(v.scene["environment"]["world"], v.scene["environment"]["file"]): v.scene for v in runnable.variants}
    world = max((environment.world_bytes(scene) for scene in worlds.values()), default=0)
    for scene in worlds.values():
        environment.from_scene(scene)  # made (or found) once here: the workers map its cache file
    return runnable, world


def _with_curves(study: st.Study, document: str) -> st.Study:
    """The study whose variants are traced with the measured curves they name (``filter_file``,
    ``spectrum_file``) and a free-form design's mesh file by their full paths beside ``document``
    (the base design or the study file), confined to its folder (``scene.beside``); a Dask worker is sent their contents
    (``cluster.cells``). The study itself (its sheet, its saved files) keeps the plain names."""
    from ..scene.beside import spectrum_files, with_curves_at

    mesh_file = None
    if "freeform" in study.base:  # its meshes beside the document too, checked before any worker starts
        common.design_meshes(document, study.base)
        from ..freeform.loading import mesh_file_path

        mesh_file = mesh_file_path(document, study.base["freeform"]["mesh_file"])
    variants = []
    for v in study.variants:
        try:
            found = spectrum_files(document, v.scene)
        except SceneError as e:
            raise common.in_file(SceneError(f"base.{e.path}", e.message), document) from None
        if mesh_file is not None:
            found[("freeform", "mesh_file")] = mesh_file
        variants.append(dataclasses.replace(v, scene=with_curves_at(v.scene, found)))
    return dataclasses.replace(study, variants=tuple(variants))


def _is_variant_file(name: str) -> bool:
    """A file ``--save-variants`` writes: a variant, or the meshes a free-form study's variants name."""
    return re.fullmatch(r"variant-\d+\.json|[^/]+\.glb", name) is not None


def _save_side_files(args: argparse.Namespace, study: st.Study) -> None:
    """``--save-study`` and ``--save-variants``, after the sheet: an interrupt before leaves none of
    them, one while they are written removes them; the variants replace an earlier run's whole."""
    saved = []
    try:
        if args.save_study:
            study.save(args.save_study)
            saved.append(args.save_study)
        if args.save_variants:
            with atomic_folder(args.save_variants, _is_variant_file, VARIANTS) as folder:
                study.save_variants(folder)
                if "freeform" in study.base:  # each variant names the design's meshes beside it
                    from ..freeform.loading import mesh_file_path

                    name = study.base["freeform"]["mesh_file"]
                    shutil.copyfile(mesh_file_path(args.base or args.study, name), os.path.join(folder, name))
    except BaseException:
        for path in saved:
            with contextlib.suppress(OSError):
                os.unlink(path)
        raise


def _progress_printer():
    if not sys.stderr.isatty():
        return None

    def progress(done: int, total: int) -> None:
        end = "\n" if done == total else ""
        print(f"\rrendering variants: {done}/{total}", end=end, file=sys.stderr, flush=True)

    return progress


def run(args: argparse.Namespace) -> int:
    if args.list:
        for name in study_parameters():
            print(name)
        return 0
    # Every check on the user's input happens before the first worker starts.
    from ..cluster import engine as dask_engine

    dask_engine.check_workers(args.workers)
    if args.cache is not None and not args.no_cache:
        from ..cluster.cache import CellCache

        CellCache(args.cache).ready()  # its own cause, before any cell is looked for
    if args.output is None and not (args.save_study or args.save_variants):
        raise SceneError("--output", "is required: the contact sheet to write (.png or .exr)")
    view = None
    if args.output is not None:
        if image_format(args.output) == "png":
            view = common.view_for(args)
        common.check_output(args.output, "output")
    if args.save_study:
        common.check_output(args.save_study, "--save-study")
    if args.save_variants:
        common.check_output_folder(args.save_variants, "--save-variants")
        common.check_output_folder(os.path.dirname(os.path.abspath(args.save_variants)), "--save-variants")
        try:
            check_replaceable_folder(args.save_variants, _is_variant_file, VARIANTS)
        except OSError as e:
            raise SceneError(args.save_variants, f"--save-variants {e.strerror}") from None
    study = _build(args)
    _check_photometric_options(args, study)
    runnable = study
    if args.output is not None:
        from ..study import sheet as study_sheet  # numpy: only for a sheet

        runnable, world = _with_environment(study, args.base or args.study)
        runnable = _with_curves(runnable, args.base or args.study)
        sheet_layout = study_sheet.layout(study)
        budget.check_study(study.size, len(study), (sheet_layout.width, sheet_layout.height), environment=world)

    if args.output is None:
        _save_side_files(args, study)
        print(f"study of {len(study)} variants saved")
        return 0

    from ..study import run as study_run  # the tracer loads only when it is needed

    study_sheet.preload_writers()
    checkpoint("study:checked")
    start = time.perf_counter()
    progress = _progress_printer()

    def on_progress(done: int, total: int) -> None:
        if progress is not None:
            progress(done, total)
        if done:
            checkpoint("study:variant")

    engine = _engine(args)
    if engine == "dask":
        dask_engine.scheduler_address(args.scheduler)  # checked before the first worker starts
    counted = ""
    with common.ctrl_c_sets() as stop:
        if engine in ("dask", "pool"):
            images, how, counted = _run_cells(args, runnable, world, on_progress, stop, dask=engine == "dask")
        else:
            try:
                images = study_run.run_study(runnable, args.workers, progress=on_progress, should_stop=stop.is_set,
                                             on_start=lambda run: checkpoint("study:started"))
            except study_run.Cancelled:
                raise stop.interrupt() from None
        checkpoint("study:rendered")
    seconds = time.perf_counter() - start
    measured = _measure(args, study, runnable) if study.measured else None
    checkpoint("study:composed")
    shown = _write_sheet(args, study, images, view, measured)
    _save_side_files(args, study)
    if engine == "processes":
        workers = args.workers if args.workers is not None else min(study_run.default_workers(), len(study))
        how = "in this process" if workers == 0 else f"on {workers} worker{'s' if workers != 1 else ''}"
    w, h = study.size
    shape = " x ".join(str(len(a.values)) for a in study.axes)
    print(f"{printable(args.output)}: {shape} variants of {w}x{h} px in {seconds:.2f} s {how}{counted}{shown}")
    return 0


def _measure(args: argparse.Namespace, study: st.Study, runnable: st.Study) -> list[dict]:
    """Each variant's values of the study's measures (printed as they come; kept in the cell cache
    unless ``--no-cache``), and the variants a filter leaves out, named."""
    from ..cluster.cache import CellCache
    from ..study import measured as study_measured

    start = time.perf_counter()
    names = study.measured.names

    def progress(done: int, total: int) -> None:
        if done < total:
            print(f"measures: variant {done + 1} of {total}", flush=True)

    cache = None if args.no_cache else CellCache(args.cache)
    values = study_measured.measure_variants([v.scene for v in runnable.variants], names, progress, cache)
    _kept, dropped = study_measured.arrange(study.measured, values)
    print(f"measured {len(values)} variants in {time.perf_counter() - start:.1f} s"
          + (f"; left out by the filter: {', '.join(f'#{i + 1}' for i in dropped)}" if dropped else ""))
    return values


def _check_photometric_options(args: argparse.Namespace, study: st.Study) -> None:
    """Before any worker starts: ``--ev100`` needs a photometric design; an .exr sheet holds one kind of cell."""
    modes = {v.scene.get("light_model", "paper") for v in study.variants}
    if args.ev100 is not None and "photometric" not in modes:
        raise SceneError("--ev100", 'is for photometric designs; allowed with "light_model": "photometric"')
    if len(modes) > 1 and args.output is not None and image_format(args.output) == "exr":
        raise SceneError(args.output, "a study that varies light_model mixes RGB and XYZ cells; allowed a .png "
                                      "sheet for it")


def _write_sheet(args: argparse.Namespace, study: st.Study, images: list, view, measured: list | None = None) -> str:
    """Write the sheet under ONE exposure for all its cells (never one per cell, issue 22 item 7):
    the paper mode's ``--exposure`` ("auto" measured over every cell); the photometric mode's
    EV100 (``--ev100``, else the design's camera; "auto" measured over every cell) with
    ``--exposure`` stops on top. Returns what the sheet shows, in words."""
    from ..images import photometric
    from ..study import sheet as study_sheet

    scenes = [v.scene for v in study.variants]
    if view is None and any(photometric.is_photometric(scene) for scene in scenes):
        # an .exr of a photometric study: the cells' XYZ in cd/m², named and with units
        sheet = study_sheet.compose(study, images, text="bitmap", measured=measured, as_values=True)
        photometric.write_photometric_exr(args.output, sheet, channels=("X", "Y", "Z"), attributes={
            study_sheet.STUDY_ATTRIBUTE: study.to_json(), "ImageDescription": study.heading()})
        return ", XYZ (Y in cd/m2)"
    stops = common.photometric_stops(args)  # on top of the photometric cells' EV100 only
    used = study_sheet.write_sheet(args.output, study, images, view=view, exposure=args.exposure, measured=measured,
                                   ev100=args.ev100, stops=stops)
    if view is None:
        return ""
    if used.ev100 is None:
        return f", {view.view} at {used.paper_stops:+.1f} EV"
    extra = f" {stops:+.1f} EV" if stops else ""
    paper = f", paper-mode cells at {used.paper_stops:+.1f} EV" if used.paper_stops is not None else ""
    return f", {view.view} at EV100 {used.ev100:.1f}{extra} for every cell{paper}"


def _engine(args: argparse.Namespace) -> str:
    """dask, pool or processes: ``--engine``; else Dask for a scheduler (``--scheduler``,
    ``$DASK_SCHEDULER_ADDRESS``, "local") and the local worker pool otherwise (cells and the cache as
    on Dask, without its start-up: docs/cluster.md); ``--workers 0`` renders in this process through
    the processes path."""
    from ..cluster import engine as dask_engine
    from ..cluster import local_pool

    if args.workers == 0:
        if args.scheduler or args.engine == "dask":
            raise SceneError("--workers", "0 renders in this process; allowed 1 or more with --engine dask "
                                          "or --scheduler")
        return "processes"
    wanted = args.engine or ("dask" if local_pool.dask_wanted(args.scheduler) else "pool")
    if wanted == "processes" and args.scheduler:
        raise SceneError("--scheduler", "needs the Dask engine; allowed with --engine dask (or without --engine)")
    if wanted == "dask" and not dask_engine.available():
        raise SceneError("--engine", "dask is not installed here (pip install distributed); allowed processes")
    return wanted


def _run_cells(args: argparse.Namespace, study: st.Study, world: int, on_progress, stop, dask: bool):
    """(the images, how they were rendered, what the cache gave) on a Dask cluster (``dask``) or the
    local worker pool."""
    from ..cluster import engine as dask_engine
    from ..cluster.cache import CellCache
    from ..study import on_cluster as dask_study

    cache = None if args.no_cache else CellCache(args.cache)
    where = []

    def started(client) -> None:
        local = client.local
        # The summary is printed after the cluster has stopped: its dashboard only in the line said now.
        where.append(local.describe(live=False) if local is not None else f"Dask scheduler {client.scheduler.address}")
        if sys.stderr.isatty():
            print(local.describe() if local is not None else where[0], file=sys.stderr)
        checkpoint("study:started")

    try:
        images, count = dask_study.run_study(study, args.scheduler, args.workers, cache=cache, environment=world,
                                             progress=on_progress, should_stop=stop.is_set, on_start=started,
                                             dask=dask)
    except dask_engine.Cancelled:
        raise stop.interrupt() from None
    except dask_engine.Unreachable as e:  # only the connection: any other OSError names its own file
        raise SceneError("--scheduler" if args.scheduler else dask_engine.SCHEDULER_VARIABLE,
                         f"{e}; allowed the address of a running dask scheduler, or local") from None
    how = f"on the {where[0]}" if where else "all from the cache"
    if count.workers is not None:
        how += f", only on the workers whose memory holds a variant: {', '.join(count.workers)}"
    return images, how, f" ({count.rendered} rendered, {count.from_cache} from the cache)"

"""``optimise OPT.json [-o FOLDER]``: let the computer search a design (docs/cluster.md).

Trials render as Dask tasks on ``--scheduler`` (or ``$DASK_SCHEDULER_ADDRESS``; "local" starts a
local Dask cluster), else on the local worker pool (``cluster.local_pool``: no start-up to wait
for); ``--workers 0`` renders them in this process one by one. The Optuna study is kept in the
file's storage, so running the command again resumes it (``--trials`` raises the count).
"""

from __future__ import annotations

import argparse
import os
import sys
import time

from ..checkpoints import checkpoint
from ..scene.reading import SceneError
from ..scene.safe_text import printable
from .common import check_output_folder, ctrl_c_sets

HELP = "search a design's parameters for the best measures (Optuna; trials on the local worker pool or Dask)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("spec", metavar="OPT.json", help="the optimisation (a lamp-optimise/1 file)")
    parser.add_argument("-o", "--output", metavar="FOLDER",
                        help="where the results go (default: OPT-results beside the file): best.json or "
                             "pareto-NN.json, sheet.png, history.png, trials.json")
    parser.add_argument("--trials", type=int, metavar="N", help="finish N trials in all (default: the file's)")
    parser.add_argument("--workers", type=int, metavar="N",
                        help="local pool or cluster worker processes (default: one per core; 0 renders in this "
                             "process)")
    parser.add_argument("--scheduler", metavar="ADDRESS",
                        help="a Dask scheduler, tcp://HOST:8786 (default: $DASK_SCHEDULER_ADDRESS, else the local "
                             "worker pool; \"local\" starts a local Dask cluster)")
    parser.add_argument("--cache", metavar="DIR", help="the folder of rendered cells (default: the per-user cache)")
    parser.add_argument("--no-cache", action="store_true", help="keep no rendered trial")


def run(args: argparse.Namespace) -> int:
    from ..optimise import spec

    opt = spec.load(args.spec)
    if args.trials is not None:
        if not 1 <= args.trials <= spec.MAX_TRIALS:
            raise SceneError("--trials", f"{args.trials} is out of range; allowed 1 to {spec.MAX_TRIALS}")
        opt = spec.Optimisation(**{**opt.__dict__, "trials": args.trials})
    from ..cluster import engine

    engine.check_workers(args.workers)
    if args.cache is not None and not args.no_cache:
        from ..cluster.cache import CellCache

        CellCache(args.cache).ready()  # its own cause, before any cell is looked for
    if args.workers == 0 and args.scheduler:
        raise SceneError("--workers", "0 renders in this process; allowed 1 or more with --scheduler")
    if args.workers != 0 and opt.needs_task:
        engine.scheduler_address(args.scheduler)  # checked before anything starts
    folder = args.output or os.path.splitext(args.spec)[0] + "-results"
    check_output_folder(folder, "--output")
    os.makedirs(folder, exist_ok=True)

    from .. import budget
    from ..cluster import local_pool
    from ..cluster.cache import CellCache
    from ..optimise import results, search, storage

    cache = None if args.no_cache else CellCache(args.cache)
    tty = sys.stderr.isatty()

    def progress(p: search.Progress) -> None:
        checkpoint("optimise:trial")
        if p.refused:
            print(f"trial {p.number}: {results.setting(p.params)} refused: {p.refused}  [{p.finished}/{p.total}]",
                  file=sys.stderr if tty else sys.stdout, flush=True)
            return
        shown = ", ".join(f"{v:.4g}" for v in p.values or [])
        flag = "" if p.feasible else " (infeasible)"
        src = "" if p.rendered else " (cached)"
        print(f"trial {p.number}: {results.setting(p.params)} -> {shown}{flag}{src}  [{p.finished}/{p.total}]",
              file=sys.stderr if tty else sys.stdout, flush=True)

    start = time.perf_counter()
    where = "in this process"
    with ctrl_c_sets() as stop:
        try:
            if args.workers == 0 or not opt.needs_task:
                outcome = search.run(opt, None, cache, progress=progress, should_stop=stop.is_set)
            else:
                workers = args.workers or engine.default_workers()
                parallel = opt.parallel or workers
                limit = min(budget.MEMORY_BUDGET, search.trial_bytes(opt) + engine.DASK_BYTES + engine.KEPT_FREED_BYTES)
                with local_pool.connect(args.scheduler, workers=workers, memory_limit=limit,
                                        should_stop=stop.is_set) as client:
                    if client.local is not None:  # a local Dask cluster's dashboard now, while it is there to open
                        print(client.local.describe(), file=sys.stderr if tty else sys.stdout, flush=True)
                    where = "on the " + (client.local.describe(live=False) if client.local is not None else
                                         f"Dask scheduler {client.scheduler.address}")
                    outcome = search.run(opt, client, cache, parallel=parallel, progress=progress,
                                         should_stop=stop.is_set)
                    if outcome.workers is not None:
                        where += (f", only on the workers whose memory holds a trial: {', '.join(outcome.workers)}")
        except (search.Cancelled, engine.Cancelled):
            raise stop.interrupt() from None
        except engine.Unreachable as e:  # only the connection: any other OSError names its own file
            raise SceneError("--scheduler" if args.scheduler else engine.SCHEDULER_VARIABLE,
                             f"{e}; allowed the address of a running dask scheduler, or local") from None
    seconds = time.perf_counter() - start
    if cache is not None:
        cache.prune()
    study = outcome.study
    results.write_trials(opt, study, os.path.join(folder, "trials.json"))
    results.write_history(opt, study, os.path.join(folder, "history.png"))
    best = storage.best(opt, study)
    measured = len(storage.finished_trials(study))
    refused = storage.count_finished(study) - measured
    print(f"{measured + refused} trials in {printable(opt.storage)} ({measured} measured, {refused} refused by the "
          f"scene; {len(outcome.told)} this run: {outcome.rendered} rendered, {outcome.from_cache} from the cache) "
          f"in {seconds:.1f} s {where}")
    if not best:
        closest = storage.closest_infeasible(study)
        detail = ""
        if closest is not None:
            detail = (f"; the closest is trial {closest.number} ({results.setting(closest.user_attrs['design'])}: "
                      + ", ".join(f"{k} {v:.4g}" for k, v in closest.user_attrs.get("measures", {}).items()) + ")")
        print(f"error: no trial met every constraint{detail}; allowed: wider ranges or looser constraints",
              file=sys.stderr)
        return 1
    presets = results.write_presets(opt, best, folder)
    top = storage.ranked(opt, study, results.SHEET_TRIALS)
    if opt.needs_task:
        results.write_sheet(opt, top, results.trial_images(opt, top, cache), os.path.join(folder, "sheet.png"))
    first = storage.finished_trials(study)[:1]
    if first and first[0].number == 0 and storage.feasible(first[0]):
        shown = ", ".join(f"{o.measure.name} {v:.4g}" for o, v in zip(opt.objectives, first[0].values, strict=True))
        print(f"start: trial 0 (the design as given): {results.setting(first[0].user_attrs['design'])} -> {shown}")
    for trial in best:
        shown = ", ".join(f"{o.measure.name} {v:.4g}" for o, v in zip(opt.objectives, trial.values, strict=True))
        print(f"best: trial {trial.number}: {results.setting(trial.user_attrs['design'])} -> {shown}")
    print(f"results in {printable(folder)}: {', '.join(os.path.basename(p) for p in presets)}, "
          f"{'sheet.png, ' if opt.needs_task else ''}history.png, trials.json")
    return 0


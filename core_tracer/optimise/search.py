"""The search: Optuna asks for trials, each is rendered (a Dask task, or in this process) and
measured, and told back, until the optimisation has its number of finished trials.

The Optuna study lives in the optimisation's storage (SQLite beside the file by default), so a
search that is interrupted resumes where it stopped, and several processes (several machines with
a database server) can work on one study at once: each counts the trials finished by all of them.
Trials under way when the search is interrupted are told as failed (they do not count); a trial
whose design the scene refuses (a combination of values no lamp can have) is failed with the
reason kept in its ``refused`` attribute, and counts.

Each finished trial keeps its measures (``measures``), constraint excesses (``constraints``: <= 0
is feasible) and whether it is ``feasible`` as user attributes.
"""

from __future__ import annotations

import contextlib
import math
import os
import time
import uuid
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any
from urllib.parse import quote

import numpy as np

from ..cluster.cache import CellCache
from ..cluster.cells import Inputs, make_cell
from ..scene.reading import SceneError
from . import trials as T
from .measures import Trial
from .spec import Knob, Optimisation

POLL = 0.05
OPEN_ATTEMPTS = 5


class Cancelled(Exception):
    """The search was interrupted; the trials finished so far are in the storage."""


@dataclass
class Progress:
    number: int  # the Optuna trial number
    finished: int  # trials finished in the study (every process's)
    total: int
    values: list[float] | None
    feasible: bool
    params: dict[str, Any]
    rendered: bool  # False: the image came from the cache
    refused: str = ""  # why the scene refused the design (then no values)


@dataclass
class Outcome:
    study: Any  # optuna.Study
    rendered: int = 0
    from_cache: int = 0
    refused: int = 0  # designs the scene refused (failed trials, counted)
    told: list[int] = field(default_factory=list)  # trial numbers this process finished
    workers: list[str] | None = None  # the workers trials were sent to (those whose memory fits), None: any


def directions(opt: Optimisation) -> list[str]:
    return ["maximize" if o.goal == "maximise" else "minimize" for o in opt.objectives]


def make_sampler(opt: Optimisation):
    import optuna

    # Constraints reach the samplers through each trial's set_constraint (Optuna 5).
    if opt.sampler == "tpe":
        return optuna.samplers.TPESampler(seed=opt.seed, multivariate=True,
                                          n_startup_trials=min(10, max(2, opt.trials // 4)))
    if opt.sampler == "nsga2":
        return optuna.samplers.NSGAIISampler(seed=opt.seed, population_size=max(4, min(50, opt.trials // 4)))
    if opt.sampler == "cmaes":
        return optuna.samplers.CmaEsSampler(seed=opt.seed)
    return optuna.samplers.RandomSampler(seed=opt.seed)


def open_study(opt: Optimisation):
    """The Optuna study of ``opt`` in its storage, made or loaded; its directions must match."""
    import optuna

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    # Constraints and the multivariate TPE are marked experimental, and Optuna says so on every trial:
    # what the user gets is stated in docs/cluster.md instead.
    warnings.filterwarnings("ignore", category=optuna.exceptions.ExperimentalWarning)
    warnings.filterwarnings("ignore", category=FutureWarning, module=r"optuna\.")
    from sqlalchemy.exc import SQLAlchemyError

    check_database(opt)
    for attempt in range(OPEN_ATTEMPTS):
        try:
            storage = opt.storage
            if storage.startswith("sqlite:"):  # processes sharing the file wait for each other's writes
                storage = optuna.storages.RDBStorage(storage, engine_kwargs={"connect_args": {"timeout": 60}})
            study = optuna.create_study(storage=storage, study_name=opt.name, directions=directions(opt),
                                        sampler=make_sampler(opt), load_if_exists=True)
            break
        except (ValueError, ImportError) as e:  # a URL SQLAlchemy cannot use
            raise SceneError("storage", f"{opt.storage!r} cannot be opened ({e}); allowed a database URL Optuna "
                                        "accepts, e.g. sqlite:///opt.db") from None
        except (SQLAlchemyError, optuna.exceptions.DuplicatedStudyError):
            # Two processes creating the tables or the study at once: one wins, the other loads it.
            if attempt == OPEN_ATTEMPTS - 1:
                raise
            time.sleep(0.2 * (attempt + 1))
    wanted = directions(opt)
    have = [d.name.lower() for d in study.directions]
    if have != wanted:
        raise SceneError("name", f"the study {opt.name!r} in {opt.storage} has objectives to {', '.join(have)}, "
                                 f"this file {', '.join(wanted)}; allowed another name")
    check_same_search(opt, study)
    study.set_user_attr("parameters", [k.name for k in opt.knobs])
    study.set_user_attr("objectives", [o.label for o in opt.objectives])
    study.set_user_attr(KNOBS_ATTRIBUTE, knobs_record(opt))
    return study


OPTUNA_TABLES = {"alembic_version", "studies", "version_info"}  # in every database Optuna made
KNOBS_ATTRIBUTE = "lamp_knobs"  # what each parameter of the search is (``knobs_record``)


def _tables(opt: Optimisation) -> tuple[set[str], dict[str, dict]] | None:
    """(the tables, {study name: its user attributes}) of ``opt``'s database, read without writing
    anything; None when there is no database yet (a new SQLite file)."""
    import json
    import sqlite3

    if opt.storage.startswith("sqlite:///"):
        path = opt.storage[len("sqlite:///"):]
        if not os.path.lexists(path):
            return None
        if not os.path.isfile(path):
            raise SceneError("storage", f"{opt.storage!r} is not a file; allowed a SQLite file this program made")
        try:
            with contextlib.closing(sqlite3.connect(f"file:{quote(path)}?mode=ro", uri=True, timeout=60)) as db:
                tables = {r[0] for r in db.execute("SELECT name FROM sqlite_master WHERE type = 'table'")}
                studies = {}
                if {"studies", "study_user_attributes"} <= tables:
                    for name, key, value in db.execute(
                            "SELECT s.study_name, a.key, a.value_json FROM studies s LEFT JOIN study_user_attributes "
                            "a ON a.study_id = s.study_id"):
                        attrs = studies.setdefault(name, {})
                        if key is not None:
                            attrs[key] = json.loads(value)
        except (sqlite3.Error, ValueError) as e:
            raise SceneError("storage", f"{opt.storage!r} is not a SQLite database ({e}); allowed a new file, or one "
                                        "this program made") from None
        return tables, studies
    from sqlalchemy import create_engine, inspect, text
    from sqlalchemy.exc import SQLAlchemyError

    try:
        engine = create_engine(opt.storage)
        try:
            tables = set(inspect(engine).get_table_names())
            studies = {}
            if {"studies", "study_user_attributes"} <= tables:
                with engine.connect() as db:
                    for name, key, value in db.execute(text(
                            "SELECT s.study_name, a.key, a.value_json FROM studies s LEFT JOIN study_user_attributes "
                            "a ON a.study_id = s.study_id")):
                        attrs = studies.setdefault(name, {})
                        if key is not None:
                            attrs[key] = json.loads(value)
        finally:
            engine.dispose()
    except (SQLAlchemyError, ImportError, ValueError) as e:
        raise SceneError("storage", f"{opt.storage!r} cannot be opened ({str(e)[:200]}); allowed a database URL "
                                    "Optuna accepts, e.g. sqlite:///opt.db") from None
    return tables, studies


def check_database(opt: Optimisation) -> None:
    """Before Optuna touches ``opt``'s database (it creates its tables in any database it is given,
    issue 33): the database is new or empty, or holds Optuna's tables; and a study of ``opt``'s name
    in it is one this program made (its ``parameters`` attribute). Else a one-line ``SceneError``."""
    found = _tables(opt)
    if found is None:
        return
    tables, studies = found
    if tables and not OPTUNA_TABLES <= tables:
        shown = ", ".join(sorted(tables)[:5]) + (", ..." if len(tables) > 5 else "")
        raise SceneError("storage", f"{opt.storage!r} holds tables ({shown}) that are not an Optuna study's; allowed a "
                                    "new database, or one this program made (nothing was changed)")
    if opt.name in studies and "parameters" not in studies[opt.name]:
        raise SceneError("name", f"the study {opt.name!r} in {opt.storage} was not made by an optimisation file; "
                                 "allowed another name (nothing was changed)")


def knobs_record(opt: Optimisation) -> list[dict]:
    """What each parameter of the search is, as the study keeps it (``check_same_search``)."""
    out = []
    for k in opt.knobs:
        if k.values:
            out.append({"parameter": k.name, "values": [v if isinstance(v, (bool, int, float, str)) else repr(v)
                                                        for v in k.values]})
        else:
            out.append({"parameter": k.name, "range": [k.lo, k.hi], "step": k.step, "log": k.log,
                        "integer": k.integer})
    return out


def _described(record: dict) -> str:
    if "values" in record:
        return f"values {record['values']}"[:120]
    kind = "an integer range" if record.get("integer") else "a range"
    extra = f" step {record['step']:g}" if record.get("step") else ""
    extra += " log" if record.get("log") else ""
    return f"{kind} [{record['range'][0]:g}, {record['range'][1]:g}]{extra}"


def check_same_search(opt: Optimisation, study) -> None:
    """Resuming a study with trials: its parameters must be what they were (issue 33: a parameter
    that became a list of values, or a new step, gave a traceback from Optuna). A one-line
    ``SceneError`` names the first change."""
    if not study.trials:
        return
    attrs = study.user_attrs
    before, now = attrs.get(KNOBS_ATTRIBUTE), knobs_record(opt)
    names_before = attrs.get("parameters")
    where = f"the study {opt.name!r} in {opt.storage}"
    allowed = "allowed the parameters its trials were made with, or another name (a new study)"
    if names_before is not None and list(names_before) != [k.name for k in opt.knobs]:
        raise SceneError("parameters", f"{where} varies {', '.join(map(str, names_before))}, this file "
                                       f"{', '.join(k.name for k in opt.knobs)}; {allowed}")
    if before is None:  # made before the parameters were recorded: the names are all it kept
        return
    for i, (old, new) in enumerate(zip(before, now, strict=False)):
        if old != new:
            raise SceneError(f"parameters[{i}]", f"{new['parameter']} was {_described(old)} in {where}, now "
                                                 f"{_described(new)}; {allowed}")


def suggest(trial, knob: Knob) -> Any:
    if knob.values:
        index = trial.suggest_categorical(knob.name, list(range(len(knob.values))))
        return knob.values[index]
    if knob.integer:
        return trial.suggest_int(knob.name, int(knob.lo), int(knob.hi), step=int(knob.step or 1), log=knob.log)
    return trial.suggest_float(knob.name, knob.lo, knob.hi, step=knob.step, log=knob.log)


def start_params(opt: Optimisation) -> dict[str, Any] | None:
    """The base design's own values as Optuna parameters, or None if one lies outside its range (or
    is not among its values, or off the step grid)."""
    out = {}
    for k in opt.knobs:
        node = k.parameter.nodes(opt.base)[0]
        value = node[k.parameter.keys[-1]]
        if k.parameter.component is not None:
            value = value[k.parameter.component]
        if k.values:
            if value not in k.values:
                return None
            out[k.name] = k.values.index(value)
            continue
        steps = (value - k.lo) / k.step if k.step else 0.0
        if not k.lo <= value <= k.hi or abs(steps - round(steps)) > 1e-9:
            return None
        out[k.name] = int(value) if k.integer else float(value)
    return out


def design_values(opt: Optimisation, params: dict[str, Any]) -> dict[str, Any]:
    """A trial's Optuna parameters as design values (a choice is stored as its index)."""
    out = {}
    for k in opt.knobs:
        v = params[k.name]
        out[k.name] = k.values[v] if k.values else (float(v) if not k.integer else int(v))
    return out


def finished_states():
    import optuna

    return (optuna.trial.TrialState.COMPLETE, optuna.trial.TrialState.FAIL)


def count_finished(study) -> int:
    return len(study.get_trials(deepcopy=False, states=finished_states()))


def measure(opt: Optimisation, scene: dict, image: np.ndarray | None, mask: np.ndarray | None,
            figures=None) -> tuple[list[float], dict[str, float], list[float]]:
    """(objective values, every measure by name, constraint excesses) of one rendered trial."""
    trial = Trial(scene, image, mask, figures)
    values = [o.measure.compute(trial, o.prepared) for o in opt.objectives]
    named = {o.measure.name: v for o, v in zip(opt.objectives, values, strict=True)}
    excess = []
    for c in opt.constraints:
        v = c.measure.compute(trial, c.prepared)
        named[c.measure.name] = v
        excess.append(c.excess(v))
    return values, named, excess


def run(opt: Optimisation, client=None, cache: CellCache | None = None, *, parallel: int = 1,
        progress: Callable[[Progress], None] | None = None,
        should_stop: Callable[[], bool] | None = None) -> Outcome:
    """Finish ``opt.trials`` trials in the study (counting earlier runs and other processes'),
    ``parallel`` at a time: on ``client`` (Dask) or, without one, in this process one by one."""
    study = open_study(opt)
    if not study.get_trials(deepcopy=False):  # a new study starts from the design as it is
        start = start_params(opt)
        if start is not None:
            study.enqueue_trial(start)
    outcome = Outcome(study)
    inputs = Inputs()
    width, height = opt.size
    stop_name = f"lamp-stop-{uuid.uuid4().hex}"
    in_flight: dict[Any, tuple[Any, dict, dict, str]] = {}  # future -> (optuna trial, scene, values, key)
    sent: dict[str, Any] = {}
    camera, request = opt.needs_render, opt.request
    workers = None
    if client is not None and opt.needs_task:  # before anything is sent: every worker's memory
        from ..cluster import engine

        workers = engine.fitting_workers(client, trial_bytes(opt), "a trial")
        outcome.workers = workers

    def tell(trial, scene, values, key, image, mask, figures, rendered) -> None:
        objective, named, excess = measure(opt, scene, image, mask, figures)
        feasible = all(e <= 0 for e in excess)
        trial.set_user_attr("measures", named)
        trial.set_user_attr("constraints", excess or [0.0])
        for i, (c, e) in enumerate(zip(opt.constraints, excess, strict=True)):
            trial.set_constraint(f"{i}:{c.measure.name}", e)
        trial.set_user_attr("feasible", feasible)
        trial.set_user_attr("design", values)
        trial.set_user_attr("cell", key)
        study.tell(trial, objective)
        outcome.told.append(trial.number)
        if rendered:
            outcome.rendered += 1
        else:
            outcome.from_cache += 1
        if progress is not None:
            progress(Progress(trial.number, count_finished(study), opt.trials, objective, feasible, values,
                              rendered))

    def refuse(trial, values, e: SceneError) -> None:
        """A design the scene or its measures refuse: a failed trial, with the reason, that counts."""
        import optuna

        trial.set_user_attr("refused", f"{e.path}: {e.message}")
        trial.set_user_attr("design", values)
        study.tell(trial, state=optuna.trial.TrialState.FAIL)
        outcome.told.append(trial.number)
        outcome.refused += 1
        if progress is not None:
            progress(Progress(trial.number, count_finished(study), opt.trials, None, False, values, False,
                              refused=f"{e.path}: {e.message}"))

    def start_one() -> None:

        trial = study.ask()
        params = {k.name: suggest(trial, k) for k in opt.knobs}
        values = design_values(opt, {k.name: trial.params[k.name] for k in opt.knobs})
        del params
        try:
            scene = opt.scene_of(values)
        except SceneError as e:
            refuse(trial, values, e)
            return
        if not opt.needs_task:
            tell(trial, scene, values, "", None, None, None, False)
            return
        cell = make_cell(scene, width, height, inputs)
        key = cell.key
        found = T.cached(cache, key) if camera else (None, None)
        figures = T.cached_figures(cache, key, scene, request) if request else None
        if found is not None and (figures is not None or not request):
            tell(trial, scene, values, key, *found, figures, False)
            return
        if client is None:
            try:
                image, mask, figures = T.run_trial(cell, inputs.data.get(cell.environment), None, camera, request)
            except SceneError as e:  # a design its measures cannot read (light tracing: a cylindrical lens)
                refuse(trial, values, e)
                return
            keep(key, scene, image, mask, figures)
            tell(trial, scene, values, key, image, mask, figures, True)
            return
        env = None
        if cell.environment is not None and camera:
            if cell.environment not in sent:
                sent[cell.environment] = client.scatter(inputs.data[cell.environment], hash=False)
            env = sent[cell.environment]
        future = client.submit(T.run_trial, cell, env, stop_name, camera, request,
                               key=f"lamp-trial-{key}-{uuid.uuid4().hex[:8]}", pure=False, workers=workers,
                               allow_other_workers=False)
        in_flight[future] = (trial, scene, values, key)

    def keep(key, scene, image, mask, figures) -> None:
        if image is not None:
            T.keep(cache, key, image, mask)
        if figures is not None:
            T.keep_figures(cache, key, scene, request, figures)

    try:
        while True:
            if should_stop is not None and should_stop():
                raise Cancelled()
            if count_finished(study) + len(in_flight) < opt.trials and len(in_flight) < max(1, parallel):
                start_one()
                continue
            if not in_flight:
                if count_finished(study) >= opt.trials:
                    break
                time.sleep(POLL)  # another process's trials are under way: they may yet fail
                continue
            done = [f for f in in_flight if f.done()]
            if not done:
                time.sleep(POLL)
                continue
            for future in done:
                trial, scene, values, key = in_flight.pop(future)
                if future.status == "error" and isinstance(future.exception(), SceneError):
                    refuse(trial, values, future.exception())
                    future.release()
                    continue
                if future.status != "finished":
                    raise RuntimeError(f"trial {trial.number} failed on a worker: {future.exception()}")
                image, mask, figures = future.result()
                future.release()
                keep(key, scene, image, mask, figures)
                tell(trial, scene, values, key, image, mask, figures, True)
        return outcome
    except BaseException:
        import optuna

        if client is not None and in_flight:
            with contextlib.suppress(Exception):
                from distributed import Event

                Event(stop_name, client=client).set()
            client.cancel(list(in_flight), force=True)
        for trial, *_ in in_flight.values():  # they do not count: a resumed search asks again
            with contextlib.suppress(Exception):
                study.tell(trial, state=optuna.trial.TrialState.FAIL)
        raise
    finally:
        for f in sent.values():
            f.release()


def trial_bytes(opt: Optimisation) -> int:
    """A trial task's estimated peak (``budget.render_bytes``): the camera's view with its passes
    kept, or the photometric work (the front view's image; the light tracing's batches of rays,
    ``LIGHT_TRACING_BYTES``), whichever is larger."""
    from .. import budget

    need = budget.BASE_BYTES
    if opt.needs_render:
        w, h = opt.size
        glare = bool((opt.base.get("glare") or {}).get("on", False))
        need = max(need, budget.render_bytes(w, h, True, "exr", glare))
    request = opt.request
    if request.front_pixel_mm is not None:
        from ..measures.directions import direction
        from ..measures.intensity import view_along

        view = view_along(opt.base, direction(0.0, 0.0), request.front_pixel_mm)
        need = max(need, budget.render_bytes(view.width, view.height, False, "exr"))
    if request.traces:
        from ..measures.light_tracing import BATCH

        need = max(need, budget.BASE_BYTES + LIGHT_TRACING_BYTES_PER_PHOTON * min(request.photons, BATCH))
    return need


# The light tracing's peak beyond the interpreter grows with its batch of photons (at most
# measures.light_tracing.BATCH at once): their rays, spectral bands and branches. Measured with
# tracemalloc on the photometric stop lamp, 20,000 photons, the 45 directions of R148 S1: 308 MB,
# 15.4 kB a photon; rounded up.
LIGHT_TRACING_BYTES_PER_PHOTON = 16 * 2**10


# ---------------------------------------------------------------------------------------------
# Reading the study


def finished_trials(study) -> list:
    import optuna

    return [t for t in study.get_trials(deepcopy=False, states=(optuna.trial.TrialState.COMPLETE,))]


def feasible(trial) -> bool:
    return bool(trial.user_attrs.get("feasible", True))


def best(opt: Optimisation, study) -> list:
    """The best feasible trial (one objective) or the feasible Pareto front (several), best first."""
    done = [t for t in finished_trials(study) if feasible(t)]
    if not done:
        return []
    signs = [1.0 if o.goal == "maximise" else -1.0 for o in opt.objectives]
    scored = [(t, [s * v for s, v in zip(signs, t.values, strict=True)]) for t in done]
    if len(signs) == 1:
        return sorted((t for t, _ in scored), key=lambda t: -signs[0] * t.values[0])[:1]
    front = [t for t, a in scored
             if not any(all(y >= x for x, y in zip(a, b, strict=True)) and b != a for _, b in scored)]
    return sorted(front, key=lambda t: -signs[0] * t.values[0])


def ranked(opt: Optimisation, study, count: int) -> list:
    """Up to ``count`` feasible trials, best first by the first objective (the front first when several)."""
    top = best(opt, study)
    sign = 1.0 if opt.objectives[0].goal == "maximise" else -1.0
    rest = sorted((t for t in finished_trials(study) if feasible(t) and t not in top),
                  key=lambda t: -sign * t.values[0])
    return (top + rest)[:count]


def closest_infeasible(study):
    """The trial nearest to meeting every constraint (its largest excess the smallest)."""
    trials = [t for t in finished_trials(study) if not feasible(t)]
    return min(trials, key=lambda t: max(t.user_attrs.get("constraints", [math.inf])), default=None)

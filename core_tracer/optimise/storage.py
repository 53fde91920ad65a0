"""The optimisation's Optuna study: opened in its storage (SQLite beside the file by default, or a
database server's URL), checked to be the same search when it resumes, and read back (finished
trials, the feasible best or Pareto front, the nearest to feasible).

Optuna is imported on use: the Blender extension runs without it and says so in one line.
"""

from __future__ import annotations

import contextlib
import math
import os
import time
import warnings
from urllib.parse import quote

from ..scene.reading import SceneError
from .spec import Optimisation

OPEN_ATTEMPTS = 5
OPTUNA_TABLES = {"alembic_version", "studies", "version_info"}  # in every database Optuna made
KNOBS_ATTRIBUTE = "lamp_knobs"  # what each parameter of the search is (``knobs_record``)


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
    if tables and not OPTUNA_TABLES <= tables and not tables <= optuna_schema():
        shown = ", ".join(sorted(tables)[:5]) + (", ..." if len(tables) > 5 else "")
        raise SceneError("storage", f"{opt.storage!r} holds tables ({shown}) that are not an Optuna study's; allowed a "
                                    "new database, or one this program made (nothing was changed)")
    if opt.name in studies and "parameters" not in studies[opt.name]:
        raise SceneError("name", f"the study {opt.name!r} in {opt.storage} was not made by an optimisation file; "
                                 "allowed another name (nothing was changed)")


def optuna_schema() -> set[str]:
    """Every table Optuna's storage makes (its models' and Alembic's): a database holding only some
    of them is one Optuna is making now (another process's first trial), not a foreign one."""
    from optuna.storages._rdb import models

    return set(models.BaseModel.metadata.tables) | {"alembic_version"}


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


def finished_states():
    import optuna

    return (optuna.trial.TrialState.COMPLETE, optuna.trial.TrialState.FAIL)


def count_finished(study) -> int:
    return len(study.get_trials(deepcopy=False, states=finished_states()))


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

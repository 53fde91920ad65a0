"""The optimisation file, ``lamp-optimise/1``::

    {"schema": "lamp-optimise/1",
     "base": "../presets/paper-baseline.json",     (a lamp-scene/1 file beside this one, or the document)
     "parameters": [{"parameter": "cuts.height", "range": [0.2, 2.0]},
                    {"parameter": "lens.ior", "range": [1.45, 1.6], "step": 0.01},
                    {"parameter": "cuts.type", "values": ["fisheye", "flutes"]}],
     "objectives": [{"measure": "ssim", "goal": "maximise", "reference": "liked.exr"}],
     "constraints": [{"measure": "lens_luminance", "min": 0.5}],
     "size": [96, 96], "trials": 40, "sampler": "tpe", "seed": 1,
     "storage": "sqlite:///opt.db", "name": "cut height for the liked look"}

- ``parameters``: any study parameter (``python -m core_tracer study --list``), a number over a
  ``range`` [lo, hi] (optionally on a ``step`` grid; ``log`` for a log scale) or one of ``values``
  (names of a choice, switches, or numbers). Vectors are varied one component at a time
  (``bulb.offset[1]``).
- ``objectives``: one or more ``{"measure", "goal": "maximise"|"minimise", ...options}``
  (``measures.MEASURES``); more than one is a multi-objective search (a Pareto front).
- ``constraints``: ``{"measure", "min", "max"}``; a trial outside is infeasible. A search whose
  trials are all infeasible says so when it ends.
- ``sampler``: ``tpe`` (default), ``cmaes`` (Optuna's CMA-ES, the ``cmaes`` package: numbers
  only, one objective, no constraints), ``nsga2`` (the default with several objectives), ``random``.
- ``base``: a lamp-scene/1 file in this file's folder (no absolute path, ``~`` or ``..``), or the
  design itself.
- ``storage``: ``sqlite:///NAME.db``, a file in this file's folder (default ``<this file>.optuna.db``
  beside it), so an interrupted optimisation resumes and several processes can share it; or a
  database server's URL (``postgresql://``, ``mysql://``). A database that holds anything but
  Optuna's tables, or a study of that name this program did not make, is refused untouched; so is
  resuming a study whose parameters changed (``storage.open_study``). ``name`` names the Optuna
  study in it (default: the file's name).

Every error is a ``SceneError`` naming the JSON path, with the allowed range.
"""

from __future__ import annotations

import copy
import math
import os
from dataclasses import dataclass, field
from typing import Any

from ..scene import spec as S
from ..scene.messages import show_value
from ..scene.reading import SceneError, parse_json_text, read_json
from ..scene.safe_text import show_key
from ..scene.validate import parse_scene
from ..study import definition as st
from ..study.parameters import Parameter, apply_values, check_value, resolve_parameter
from . import measures as M

SCHEMA = "lamp-optimise/1"
SAMPLERS = ("tpe", "cmaes", "nsga2", "random")
GOALS = ("maximise", "minimise")
MAX_TRIALS = 10_000
MAX_STEPS = 1_000_000  # steps in a range: a step of 1e-300 overflowed Optuna's grid (issue 33)
DEFAULT_SIZE = (96, 96)
KEYS = ("schema", "name", "base", "parameters", "objectives", "constraints", "size", "trials", "sampler", "seed",
        "storage", "parallel")


@dataclass(frozen=True)
class Knob:
    """One parameter of the search."""

    parameter: Parameter
    lo: float | None = None
    hi: float | None = None
    step: float | None = None
    log: bool = False
    values: tuple[Any, ...] = ()  # a choice among these (when no range)
    integer: bool = False

    @property
    def name(self) -> str:
        return self.parameter.text


@dataclass(frozen=True)
class Objective:
    measure: M.Measure
    goal: str
    prepared: Any = None
    label: str = ""


@dataclass(frozen=True)
class Constraint:
    measure: M.Measure
    lo: float | None
    hi: float | None
    prepared: Any = None

    def excess(self, value: float) -> float:
        """Optuna's convention: <= 0 is feasible; the larger, the further outside."""
        out = -math.inf
        if self.lo is not None:
            out = max(out, self.lo - value)
        if self.hi is not None:
            out = max(out, value - self.hi)
        return out


@dataclass(frozen=True)
class Optimisation:
    name: str
    base: dict  # normalised scene
    knobs: tuple[Knob, ...]
    objectives: tuple[Objective, ...]
    constraints: tuple[Constraint, ...]
    size: tuple[int, int]
    trials: int
    sampler: str
    seed: int | None
    storage: str
    parallel: int | None
    folder: str  # where relative paths are read from
    doc: dict = field(default_factory=dict)
    # the document the base's measured curves (``filter_file``, ``spectrum_file``) lie beside: the
    # base's file, or this file when the base is embedded
    base_document: str = ""

    @property
    def needs_render(self) -> bool:
        """Whether a trial renders the camera's view (for the measures of the image)."""
        return any(o.measure.needs_render for o in self.objectives) or \
            any(c.measure.needs_render for c in self.constraints)

    @property
    def request(self):
        """The photometric work each trial's task does for the measures (``photometric.Request``;
        false when none asks for any)."""
        from .photometric import Request

        out = Request()
        for m, prepared in [(o.measure, o.prepared) for o in self.objectives] + \
                [(c.measure, c.prepared) for c in self.constraints]:
            if m.request is not None:
                out = out.merge(m.request(prepared))
        return out

    @property
    def needs_task(self) -> bool:
        """Whether a trial is work for a worker (a render of any kind), not only the design's figures."""
        return self.needs_render or bool(self.request)

    def traced(self, scene: dict) -> dict:
        """A trial's design as the tracer takes it: its measured curves and a free-form design's mesh
        file by their full paths beside the base's document (``scene.beside``, ``freeform.loading``);
        a Dask worker is sent their bytes (``cluster.cells``)."""
        from ..scene.beside import spectrum_files, with_curves_at

        document = self.base_document or os.path.join(self.folder, "optimisation.json")
        try:
            found = spectrum_files(document, scene)
            if "freeform" in scene:
                from ..freeform.loading import mesh_file_path

                found[("freeform", "mesh_file")] = mesh_file_path(document, scene["freeform"]["mesh_file"])
        except SceneError as e:
            raise SceneError(f"base.{e.path}", e.message) from None
        return with_curves_at(scene, found)

    def scene_of(self, values: dict[str, Any]) -> dict:
        """The design of one trial: the base with ``values`` (by parameter name) applied, checked."""
        scene = copy.deepcopy(self.base)
        apply_values(scene, tuple(k.parameter for k in self.knobs), tuple(values[k.name] for k in self.knobs))
        return parse_scene(scene)


def load(path: str) -> Optimisation:
    doc = read_json(path)
    folder = os.path.dirname(os.path.abspath(path))
    stem = os.path.splitext(os.path.basename(path))[0]
    try:
        return from_doc(doc, folder, stem)
    except SceneError as e:
        raise SceneError(f"{path}: {e.path}" if e.path else path, e.message) from None


def from_json(text: str, folder: str, stem: str = "optimisation") -> Optimisation:
    return from_doc(parse_json_text(text, stem), folder, stem)


def from_doc(doc: Any, folder: str, stem: str = "optimisation") -> Optimisation:
    if not isinstance(doc, dict):
        raise SceneError("", f"a {SCHEMA} document is a JSON object, got {show_value(doc)}")
    if doc.get("schema") != SCHEMA:
        raise SceneError("schema", f"{show_value(doc.get('schema'))} is missing or wrong; allowed \"{SCHEMA}\"")
    for key in doc:
        if key not in KEYS:
            raise SceneError(show_key(key), f"unknown key; allowed keys here: {', '.join(KEYS)}")
    size = st.parse_size(doc.get("size", list(DEFAULT_SIZE)))
    base = _base(doc.get("base"), folder, size)
    base_document = (os.path.join(folder, os.path.expanduser(doc["base"])) if isinstance(doc.get("base"), str)
                     else os.path.join(folder, f"{stem}.json"))
    knobs = _knobs(doc.get("parameters"), base)
    objectives = tuple(_objective(o, f"objectives[{i}]", folder) for i, o in enumerate(_list(doc, "objectives", 1)))
    constraints = tuple(_constraint(c, f"constraints[{i}]", folder)
                        for i, c in enumerate(_list(doc, "constraints", 0) if "constraints" in doc else []))
    photometric = [o.measure.name for o in objectives + constraints if o.measure.photometric]
    for i, knob in enumerate(knobs):
        if photometric and knob.name == "light_model":
            raise SceneError(f"parameters[{i}].parameter", f"light_model cannot vary: {photometric[0]} needs light in "
                                                           "cd in every trial; allowed any other parameter")
    for kind, items in (("objectives", objectives), ("constraints", constraints)):
        for i, item in enumerate(items):
            M.check_size(item.prepared, size, f"{kind}[{i}]")
            if "freeform" in base and (item.measure.photometric or not item.measure.needs_render):
                raise SceneError(f"{kind}[{i}].measure", f"{item.measure.name} is measured on the parametric lamps, "
                                 "which a free-form design does not trace; allowed a measure of its camera view "
                                 "(ssim, lens_luminance, lit_fraction)")
            if item.measure.photometric and base.get("light_model") != "photometric":
                raise SceneError(f"{kind}[{i}].measure", f"{item.measure.name} needs light in cd, which the base's "
                                 f"light_model \"{base.get('light_model', 'paper')}\" has not; allowed a base with "
                                 "light_model \"photometric\" (or a measure of the image: ssim, lens_luminance, "
                                 "lit_fraction, lens_thickness)")
    trials = _whole(doc.get("trials", 30), "trials", 1, MAX_TRIALS)
    default_sampler = "nsga2" if len(objectives) > 1 else "tpe"
    sampler = doc.get("sampler", default_sampler)
    if sampler not in SAMPLERS:
        raise SceneError("sampler", f"{show_value(sampler)} is not a sampler; allowed {', '.join(SAMPLERS)}")
    if sampler == "cmaes":
        import importlib.util

        if importlib.util.find_spec("cmaes") is None:
            raise SceneError("sampler", "cmaes needs the cmaes package, which is not installed here; allowed tpe, "
                                        "nsga2 or random")
        if len(objectives) > 1:
            raise SceneError("sampler", "cmaes searches one objective; allowed nsga2, tpe or random for "
                                        f"{len(objectives)} objectives")
        if constraints:
            raise SceneError("sampler", "cmaes takes no constraints; allowed tpe, nsga2 or random with constraints")
        if any(k.values for k in knobs):
            choice = next(k for k in knobs if k.values)
            raise SceneError("sampler", f"cmaes varies numbers over ranges only ({choice.name} is a list of values); "
                                        "allowed tpe, nsga2 or random")
    seed = doc.get("seed")
    if seed is not None:
        seed = _whole(seed, "seed", 0, 2**32 - 1)
    name = doc.get("name", stem)
    if not isinstance(name, str) or not name or len(name) > 200 or not name.isprintable():
        raise SceneError("name", f"expected a non-empty string of at most 200 printable characters (no control "
                                 f"characters), got {show_value(name)}")
    storage = _storage(doc.get("storage"), folder, stem)
    parallel = doc.get("parallel")
    if parallel is not None:
        parallel = _whole(parallel, "parallel", 1, 1024)
    opt = Optimisation(name, base, knobs, objectives, constraints, size, trials, sampler, seed, storage, parallel,
                       folder, doc, base_document)
    traced = opt.traced(base)  # the base's measured curves are beside it, or refused before any trial
    if "freeform" in base:  # and its meshes, their geometry checked
        from ..freeform.traced import meshes_of

        meshes = meshes_of(traced)
        try:
            meshes.cache.get(traced, meshes.meshes)
        except SceneError as e:
            raise SceneError(f"base.{e.path}", e.message) from None
    return opt


SERVER_SCHEMES = ("postgresql", "mysql")  # a database server a team shares (checked before use, search.py)


def _storage(value: Any, folder: str, stem: str) -> str:
    """The study's database URL: SQLite in a file within this file's folder (default
    ``<stem>.optuna.db`` beside it; a relative name is resolved there, never against the working
    directory), or a database server's URL. ``file:`` URIs, query options, ``~``, ``..``, absolute
    paths and in-memory databases are refused (issue 33: ``storage`` created or altered databases
    anywhere)."""
    allowed = ('allowed "sqlite:///NAME.db" (a file in this file\'s folder, which is where it is looked for) '
               'or "postgresql://user@host/db"')
    if value is None:
        return "sqlite:///" + os.path.join(folder, f"{stem}.optuna.db")
    if not isinstance(value, str) or "://" not in value or len(value) > 1000 or not value.isprintable():
        raise SceneError("storage", f"{show_value(value)} is not a database URL; {allowed}")
    scheme, _, rest = value.partition("://")
    if scheme.split("+")[0] in SERVER_SCHEMES:
        return value
    if scheme != "sqlite":
        raise SceneError("storage", f"{show_value(value)} is not a database this runs on; {allowed}")
    if not rest.startswith("/") or rest == "/":
        raise SceneError("storage", f"{show_value(value)} is an in-memory or unnamed database, which no run can "
                                    f"resume; {allowed}")
    name = rest[1:]
    if "?" in name or "#" in name or name.startswith(("file:", "~")) or os.path.isabs(name) or \
            ".." in name.replace("\\", "/").split("/") or "\0" in name:
        raise SceneError("storage", f"{show_value(value)} names a database outside this file's folder (absolute, "
                                    f"~, .., file: or options); {allowed}")
    path = os.path.join(folder, name)
    if os.path.commonpath([os.path.realpath(path), os.path.realpath(folder)]) != os.path.realpath(folder):
        raise SceneError("storage", f"{show_value(value)} leads outside this file's folder; {allowed}")
    return "sqlite:///" + path


def base_path(value: str, folder: str) -> str:
    """The base design's file: a relative path within the optimisation file's folder (no absolute
    path, ``~`` or ``..``, no link out of it), as a preset's files are confined to its folder."""
    shown = show_value(value)
    if not value or not value.isprintable() or os.path.isabs(value) or value.startswith("~") or \
            ".." in value.replace("\\", "/").split("/"):
        raise SceneError("base", f"{shown} is outside this file's folder (absolute, ~, .. or not printable); "
                                 "allowed a lamp-scene/1 file in this file's folder (copy it there), or the design "
                                 "itself as the value")
    path = os.path.join(folder, value)
    if os.path.commonpath([os.path.realpath(path), os.path.realpath(folder)]) != os.path.realpath(folder):
        raise SceneError("base", f"{shown} leads outside this file's folder (a link); allowed a lamp-scene/1 file in "
                                 "this file's folder, or the design itself as the value")
    return path


def _base(value: Any, folder: str, size: tuple[int, int]) -> dict:
    if isinstance(value, str):
        path = base_path(value, folder)
        if not os.path.isfile(path):
            raise SceneError("base", f"{show_value(value)} does not exist; allowed a lamp-scene/1 file in this file's "
                                     "folder, or the design itself")
        value = read_json(path)
        from ..scene.beside import environment_file  # the base's environment image is the one beside it

        if isinstance(value, dict) and isinstance(value.get("environment"), dict):
            env = dict(value["environment"])
            if env.get("world") == "file" and env.get("file"):
                env["file"] = environment_file(path, {**env}) or env["file"]
                value = {**value, "environment": env}
    if not isinstance(value, dict):
        raise SceneError("base", f"expected a lamp-scene/1 document or the path of one, got {show_value(value)}")
    image = value.get("image") if isinstance(value.get("image"), dict) else {}
    try:
        base = parse_scene({**value, "image": {**image, "width": size[0], "height": size[1]}})
    except SceneError as e:
        raise SceneError(f"base.{e.path}" if e.path else "base", e.message) from None
    return base


def _list(doc: dict, key: str, least: int) -> list:
    value = doc.get(key)
    if not isinstance(value, list) or len(value) < least:
        raise SceneError(key, f"expected a list of at least {least}, got {show_value(value)}")
    return value


def _whole(value: Any, where: str, lo: int, hi: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
        raise SceneError(where, f"{show_value(value)} is out of range; allowed a whole number {lo} to {hi}")
    return value


def _number(value: Any, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise SceneError(where, f"expected a number, got {show_value(value)}")
    return float(value)


def _knobs(value: Any, base: dict) -> tuple[Knob, ...]:
    if not isinstance(value, list) or not value:
        raise SceneError("parameters", f"expected a list of at least one parameter, got {show_value(value)}")
    knobs: list[Knob] = []
    for i, doc in enumerate(value):
        where = f"parameters[{i}]"
        if not isinstance(doc, dict):
            raise SceneError(where, f"expected an object with parameter and range or values, got {show_value(doc)}")
        for key in doc:
            if key not in ("parameter", "range", "step", "log", "values"):
                raise SceneError(f"{where}.{show_key(key)}", "unknown key; allowed keys here: parameter, range, "
                                                            "step, log, values")
        try:
            param = resolve_parameter(doc.get("parameter"), base)
        except SceneError as e:
            said = f"{e.path}: {e.message}" if e.path != "parameter" else e.message
            if "allowed" not in said:
                said += "; allowed a name `python -m core_tracer study --list` prints"
            raise SceneError(f"{where}.parameter", said) from None
        if any(k.name == param.text for k in knobs):
            raise SceneError(f"{where}.parameter", f"{param.text} is given twice; allowed each parameter once")
        if param.is_vector:
            raise SceneError(f"{where}.parameter", f"{param.text} is a vector; allowed one component of it, "
                                                   f"e.g. {param.text}[0]")
        if "values" in doc:
            if "range" in doc:
                raise SceneError(where, "gives both range and values; allowed one of them")
            values = doc["values"]
            if not isinstance(values, list) or not values:
                raise SceneError(f"{where}.values", f"expected a non-empty list, got {show_value(values)}")
            try:
                checked = tuple(check_value(param, v) for v in values)
            except SceneError as e:
                raise SceneError(f"{where}.values", e.message) from None
            knobs.append(Knob(param, values=checked))
            continue
        if isinstance(param.spec, S.Choice | S.Flag):
            allowed = param.spec.range_text() if isinstance(param.spec, S.Choice) else "true, false"
            raise SceneError(f"{where}.values", f"is required: {param.text} is a choice; allowed a list of values "
                                                f"({allowed})")
        rng = doc.get("range")
        if not isinstance(rng, list) or len(rng) != 2:
            raise SceneError(f"{where}.range", f"expected [lo, hi], got {show_value(rng)}; allowed within "
                                               f"{param.spec.range_text()}")
        lo, hi = (_number(v, f"{where}.range") for v in rng)
        try:
            lo, hi = check_value(param, lo), check_value(param, hi)
        except SceneError as e:
            raise SceneError(f"{where}.range", e.message) from None
        if not lo < hi:
            raise SceneError(f"{where}.range", f"[{lo:g}, {hi:g}] is empty; allowed lo < hi within "
                                               f"{param.spec.range_text()}")
        step = doc.get("step")
        if step is not None:
            step = _number(step, f"{where}.step")
            if not (hi - lo) / MAX_STEPS <= step <= hi - lo:
                least = (hi - lo) / MAX_STEPS
                raise SceneError(f"{where}.step", f"{step:g} is out of range; allowed {least:g} (a {MAX_STEPS:,}th of "
                                                  f"the range) up to {hi - lo:g} (the range's width)")
        log = doc.get("log", False)
        if not isinstance(log, bool):
            raise SceneError(f"{where}.log", f"expected true or false, got {show_value(log)}")
        if log and (lo <= 0 or step is not None):
            raise SceneError(f"{where}.log", "a log scale needs a range above 0 and no step; allowed false here")
        knobs.append(Knob(param, lo, hi, step, log, integer=param.spec.integer if hasattr(param.spec, "integer")
                          else False))
    return tuple(knobs)


def _options(doc: dict, measure: M.Measure, where: str, extra: tuple[str, ...]) -> dict:
    allowed = ("measure", *extra, *measure.options)
    for key in doc:
        if key not in allowed:
            raise SceneError(f"{where}.{show_key(key)}", f"unknown key; allowed keys here: {', '.join(allowed)}")
    return {k: v for k, v in doc.items() if k in measure.options}


def _objective(doc: Any, where: str, folder: str) -> Objective:
    if not isinstance(doc, dict):
        raise SceneError(where, f"expected an object with measure and goal, got {show_value(doc)}")
    measure = M.lookup(doc.get("measure"), f"{where}.measure")
    options = _options(doc, measure, where, ("goal",))
    goal = doc.get("goal", measure.goal)
    if goal not in GOALS:
        raise SceneError(f"{where}.goal", f"{show_value(goal)} is not a goal; allowed {', '.join(GOALS)}")
    prepared = measure.prepare(options, where, folder)
    return Objective(measure, goal, prepared, f"{measure.name} ({goal[:3]})")


def _constraint(doc: Any, where: str, folder: str) -> Constraint:
    if not isinstance(doc, dict):
        raise SceneError(where, f"expected an object with measure, min and/or max, got {show_value(doc)}")
    measure = M.lookup(doc.get("measure"), f"{where}.measure")
    options = _options(doc, measure, where, ("min", "max"))
    lo = _number(doc["min"], f"{where}.min") if "min" in doc else None
    hi = _number(doc["max"], f"{where}.max") if "max" in doc else None
    if lo is None and hi is None:
        raise SceneError(where, "gives neither min nor max; allowed one or both")
    if lo is not None and hi is not None and lo > hi:
        raise SceneError(f"{where}.max", f"{hi:g} is below min {lo:g}; allowed max >= min")
    return Constraint(measure, lo, hi, measure.prepare(options, where, folder))

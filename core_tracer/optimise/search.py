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
import time
import uuid
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..cluster.cache import CellCache
from ..cluster.cells import Inputs, make_cell
from ..scene.reading import SceneError
from . import storage
from . import trials as T
from .measures import Trial
from .spec import Knob, Optimisation

POLL = 0.05


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
    study = storage.open_study(opt)
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
            progress(Progress(trial.number, storage.count_finished(study), opt.trials, objective, feasible, values,
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
            progress(Progress(trial.number, storage.count_finished(study), opt.trials, None, False, values, False,
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
        cell = make_cell(opt.traced(scene), width, height, inputs)
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
            if storage.count_finished(study) + len(in_flight) < opt.trials and len(in_flight) < max(1, parallel):
                start_one()
                continue
            if not in_flight:
                if storage.count_finished(study) >= opt.trials:
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



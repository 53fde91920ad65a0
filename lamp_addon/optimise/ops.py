# SPDX-License-Identifier: GPL-3.0-or-later
"""Running an optimisation from Blender and applying what it found.

From the interface the search runs on a worker thread (``OptimiseRun``: ``core_tracer.optimise``,
which never touches ``bpy``) while a modal operator polls it on a timer; the status bar shows the
trials finished, Esc stops it (the trials finished are kept in the optimisation's storage; running
again resumes). Called from a script or in background mode, the operator searches synchronously.
Trials render in Blender's process one after the other ("local"), or as Dask tasks on the
scheduler the settings name. The results go where the command line puts them (``<file>-results``).
"""

from __future__ import annotations

import importlib
import json
import os
import threading

import bpy

from ...core_tracer.scene.reading import SceneError, read_json
from .. import jobs, reports
from ..design import properties as design_properties
from . import settings


def importable(module: str) -> bool:
    """Whether ``module`` imports in this Python (a real Blender's has numpy and little else)."""
    try:
        importlib.import_module(module)
    except ImportError:
        return False
    return True


def load_optimisation(context):
    """The settings' optimisation; a file without ``base`` starts from this scene's design."""
    from ...core_tracer.optimise import spec

    path = bpy.path.abspath(context.scene.lamp_optimise.file)
    if not path:
        raise SceneError("File", "is empty; allowed a lamp-optimise/1 JSON file (docs/cluster.md)")
    doc = read_json(path)
    if isinstance(doc, dict) and "base" not in doc:
        from ..freeform import geometry as freeform_geometry

        freeform_geometry.refuse_parts("optimised", "optimise")  # the scene's design is its parametric lamp
        doc = {**doc, "base": design_properties.design_to_scene(context.scene)}
    stem = os.path.splitext(os.path.basename(path))[0]
    try:
        opt = spec.from_doc(doc, os.path.dirname(os.path.abspath(path)), stem)
    except SceneError as e:
        raise SceneError(f"{path}: {e.path}" if e.path else path, e.message) from None
    trials = context.scene.lamp_optimise.trials
    if trials:
        opt = spec.Optimisation(**{**opt.__dict__, "trials": trials})
    return opt, os.path.splitext(path)[0] + "-results"


class OptimiseRun:
    """The search on a worker thread: ``start``, ``poll`` (True once it ended), ``cancel``, ``close``."""

    def __init__(self, opt, folder: str, scheduler: str):
        self.opt, self.folder, self.scheduler = opt, folder, scheduler.strip()
        self.stop = threading.Event()
        self.finished_trials = 0
        self.outcome: settings.Outcome | None = None
        self.error: BaseException | None = None
        self._thread = threading.Thread(target=self._work, name="lamp-optimise", daemon=True)

    @property
    def fraction(self) -> float:
        return min(1.0, self.finished_trials / max(1, self.opt.trials))

    def start(self) -> None:
        self._thread.start()

    def poll(self, timeout: float = 0.0) -> bool:
        self._thread.join(timeout)
        return not self._thread.is_alive()

    def wait(self) -> None:
        self._thread.join()

    def cancel(self) -> None:
        self.stop.set()

    def close(self) -> None:
        self.stop.set()
        self._thread.join(timeout=30)

    def _progress(self, p) -> None:
        self.finished_trials = p.finished

    def _work(self) -> None:
        from ...core_tracer.cluster import engine
        from ...core_tracer.cluster.cache import CellCache
        from ...core_tracer.optimise import results, search, storage

        try:
            cache = CellCache()
            if self.scheduler.lower() in ("", "local"):
                outcome = search.run(self.opt, None, cache, progress=self._progress, should_stop=self.stop.is_set)
            else:
                if not engine.available():
                    raise SceneError("Scheduler", "needs Dask (distributed) in Blender's Python, which is not "
                                                  "installed; allowed \"local\"")
                with engine.connect(self.scheduler, should_stop=self.stop.is_set) as client:
                    workers = len(client.scheduler_info()["workers"]) or 1
                    outcome = search.run(self.opt, client, cache, parallel=self.opt.parallel or workers,
                                         progress=self._progress, should_stop=self.stop.is_set)
            study = outcome.study
            os.makedirs(self.folder, exist_ok=True)
            results.write_trials(self.opt, study, os.path.join(self.folder, "trials.json"))
            if importable("matplotlib"):  # the history plot is matplotlib's; Blender's Python has none
                results.write_history(self.opt, study, os.path.join(self.folder, "history.png"))
            best = storage.best(self.opt, study)
            if best:
                results.write_presets(self.opt, best, self.folder)
                if self.opt.needs_task:
                    top = storage.ranked(self.opt, study, results.SHEET_TRIALS)
                    results.write_sheet(self.opt, top, results.trial_images(self.opt, top, cache),
                                        os.path.join(self.folder, "sheet.png"))
            done = len(storage.finished_trials(study))
            self.outcome = settings.Outcome(
                self.opt.name, [o.label for o in self.opt.objectives],
                [(t.number, dict(t.user_attrs["design"]), list(t.values)) for t in best], self.folder,
                f"{self.opt.name}: {done} trials, best of {', '.join(o.label for o in self.opt.objectives)}")
        except BaseException as e:  # handed to the main thread, which reports it
            self.error = e


def _finish(operator, run: OptimiseRun) -> set[str]:
    from ...core_tracer.optimise.search import Cancelled

    if isinstance(run.error, Cancelled):
        operator.report({"WARNING"}, "Lamp Optimise stopped; run it again to resume")
        return {"CANCELLED"}
    if isinstance(run.error, SceneError):
        error = run.error
        if error.path == "--scheduler":  # the workers' memory, said in the panel's words
            error = SceneError("Scheduler", error.message)
        return reports.cancelled(operator, str(error))
    if run.error is not None:
        return reports.cancelled(operator, f"Lamp Optimise failed: {type(run.error).__name__}: {run.error}")
    settings.remember(run.outcome)
    if not run.outcome.best:
        return reports.cancelled(operator, "Lamp Optimise: no trial met every constraint (see trials.json)")
    number, design, values = run.outcome.best[0]
    shown = ", ".join(f"{v:.4g}" for v in values)
    return reports.finished(operator, f"Lamp Optimise: best trial {number} ({shown}); results in {run.folder}")


class LAMP_OT_optimise_run(jobs.ModalJob, bpy.types.Operator):
    """Search the design's parameters for the best measures (an optimisation file; Optuna)"""

    bl_idname = "lamp.optimise_run"
    bl_label = "Optimise"

    busy_message = "An optimisation is running (Esc stops it)"
    settings = "lamp_optimise"

    def _run(self, context) -> OptimiseRun:
        if not importable("optuna"):
            raise SceneError("Optimise", "needs Optuna, not in Blender's Python; run python -m core_tracer optimise")
        opt, folder = load_optimisation(context)
        return OptimiseRun(opt, folder, context.scene.lamp_optimise.scheduler)

    def execute(self, context):
        try:
            run = self._run(context)
        except (SceneError, OSError) as e:
            return reports.cancelled(self, str(e))
        run.start()
        run.wait()
        return _finish(self, run)

    def invoke(self, context, event):
        if bpy.app.background or context.window is None:
            return self.execute(context)
        try:
            self._job = self._run(context)
        except (SceneError, OSError) as e:
            return reports.cancelled(self, str(e))
        self._job.start()
        return self.begin_modal(context, self._job)

    def escape(self, context):
        self._job.cancel()
        return {"RUNNING_MODAL"}  # the thread ends at its next look; step() then reports

    def step(self, context):
        if not self._job.poll(0.0):
            return None
        self.end_modal(context)
        return _finish(self, self._job)

    def abandon(self, context):
        self._job.close()

    def status(self) -> str:
        job = self._job
        stopping = " stopping..." if job.stop.is_set() else " (Esc to stop)"
        return f"Lamp Optimise: {job.finished_trials}/{job.opt.trials} trials{stopping}"


class LAMP_OT_optimise_apply(bpy.types.Operator):
    """Set the design's parameters to the values of the chosen best design of the last optimisation"""

    bl_idname = "lamp.optimise_apply"
    bl_label = "Apply to Design"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        outcome = settings.last()
        if outcome is None or not outcome.best:
            cls.poll_message_set("Run an optimisation first")
            return False
        return True

    def execute(self, context):
        from ...core_tracer.study.parameters import apply_values, resolve_parameter

        outcome = settings.last()
        index = context.scene.lamp_optimise.choice - 1
        if not 0 <= index < len(outcome.best):
            return reports.cancelled(self, f"Design {index + 1} does not exist; the optimisation found "
                                           f"{len(outcome.best)}")
        number, design_values, _ = outcome.best[index]
        try:
            design = design_properties.design_to_scene(context.scene)
            params = tuple(resolve_parameter(name, design) for name in design_values)
            apply_values(design, params, tuple(design_values.values()))
            design_properties.scene_to_design(context.scene, design)
        except SceneError as e:
            return reports.cancelled(self, str(e))
        shown = ", ".join(f"{k}={json.dumps(v)}" for k, v in design_values.items())
        return reports.finished(self, f"Design set to trial {number}: {shown}")


classes = (LAMP_OT_optimise_run, LAMP_OT_optimise_apply)


register, unregister = bpy.utils.register_classes_factory(classes)

"""Compare with Cycles, the operator: blocking from scripts and in background mode
(``comparison.compare_design``), modal from the interface (each render a Blender render job; a timer
advances the ``comparison.CompareRun``), and a button of the actions area.
"""

from __future__ import annotations

import bpy

from ...core_tracer.scene.reading import SceneError
from .. import actions, image_view, jobs, reports
from ..convert.sheet import lens_figures_text
from ..design import properties as design_properties
from ..design import validity as design_validity
from .comparison import (
    COMPARE_IMAGE,
    CYCLES,
    DEFAULT_SAMPLES,
    JOB_KEY,
    REPORTED_ERRORS,
    STAGES,
    CompareCancelled,
    CompareRun,
    compare_design,
    running,
    show_comparison,
    unwatch,
    watch,
    write_comparison,
)
from .scope import left_out_text


class LAMP_OT_compare_cycles(jobs.ModalJob, bpy.types.Operator):
    """Render the design with Cycles and with the Lamp Tracer from the scene camera and show them
    side by side (render slots 1 and 2 of Render Result, flip with J, and the "Lamp Compare" image)"""

    bl_idname = "lamp.compare_cycles"
    bl_label = "Compare with Cycles"
    bl_options = {"REGISTER", "UNDO"}  # builds the lamp objects

    job_key = JOB_KEY
    busy_message = "A comparison is running (Esc cancels its render)"

    samples: bpy.props.IntProperty(name="Cycles Samples", default=DEFAULT_SAMPLES, min=1, max=65536,
                                   description="Samples per pixel of the Cycles render")
    filepath: bpy.props.StringProperty(name="Save As", subtype="FILE_PATH", default="",
                                       description="Also write the side-by-side image here (.png as shown, "
                                                   "through the scene's view transform, or .exr linear); "
                                                   "empty: do not write")

    @classmethod
    def poll(cls, context):
        if not design_properties.poll_design(cls, context):
            return False
        if not hasattr(context.scene, "cycles"):
            cls.poll_message_set("Cycles is not enabled")
            return False
        return cls.poll_not_running()

    def _output_path(self) -> str:
        """The file to write, checked before minutes of rendering (raises ``SceneError``), or "" (also
        when this Blender cannot write image files: ``_not_saved`` then says so)."""
        from ...core_tracer.images import imageio

        self._not_saved = ""
        path = bpy.path.abspath(self.filepath) if self.filepath else ""
        if path:
            imageio.image_format(path)
            if not image_view.openimageio_available():
                self._not_saved = (f"{path} not written: {image_view.NO_OPENIMAGEIO}; save the "
                                   f"\"{COMPARE_IMAGE}\" image from the Image Editor")
                return ""
        return path

    def execute(self, context):
        try:
            path = self._output_path()
            comparison = compare_design(context.scene, samples=self.samples)
        except REPORTED_ERRORS as e:
            return self._failed(e)
        return self._finished(context, comparison, path)

    def invoke(self, context, event):
        if bpy.app.background or context.window is None:
            return self.execute(context)
        run = CompareRun(context.scene, samples=self.samples)
        try:
            self._path = self._output_path()
            watch(run)
            run.prepare()
            run.start(CYCLES, invoke=True)
        except REPORTED_ERRORS as e:
            run.close()
            return self._failed(e)
        except BaseException:
            run.close()
            raise
        self._run = run
        return self.begin_modal(context, run)

    def escape(self, context):
        if bpy.app.is_job_running("RENDER"):
            return {"PASS_THROUGH"}  # Esc during a render goes on to Blender's render job, which stops
        self.end_modal(context)  # between the two renders: Esc is ours
        reports.say(self, "WARNING", "Compare with Cycles cancelled")
        return {"CANCELLED"}

    def step(self, context):
        try:
            if not self._run.advance():
                return None
            comparison = self._run.compose()
        except REPORTED_ERRORS as e:
            self.end_modal(context)
            return self._failed(e)
        except BaseException:
            self.end_modal(context)
            raise
        self.end_modal(context)
        show_comparison(context.scene, comparison)
        return self._finished(context, {**comparison, "not_restored": self._run.not_restored}, self._path)

    def abandon(self, context):
        pass  # nothing runs between the timer ticks but Blender's render job; end_modal puts the settings back

    def status(self) -> str:
        stage = self._run.stage
        return f"Compare with Cycles: {stage.label} render, {STAGES.index(stage) + 1} of {len(STAGES)} (Esc cancels)"

    def fraction(self) -> float:
        return STAGES.index(self._run.stage) / len(STAGES)

    def end_modal(self, context) -> None:
        super().end_modal(context)
        self._run.close()  # the settings back, the handlers removed (again: nothing)

    def _failed(self, error: Exception):
        """Report why the comparison stopped (one of ``REPORTED_ERRORS``)."""
        if isinstance(error, CompareCancelled):
            reports.say(self, "WARNING", f"Compare with Cycles cancelled: {error}")
        elif isinstance(error, SceneError):  # the design's error, in the panel's words
            reports.say(self, "ERROR", design_validity.message(bpy.context.scene, error))
        else:
            reports.say(self, "ERROR", str(error).strip())
        return {"CANCELLED"}

    def _finished(self, context, comparison: dict, path: str):
        image_view.show_image(context, bpy.data.images[COMPARE_IMAGE])
        if path:
            try:
                # What the "Lamp Compare" image shows: both halves at the design's exposure, the scene's view.
                write_comparison(path, comparison, view=image_view.scene_view(context.scene),
                                 exposure=comparison["exposure"])
            except (SceneError, OSError) as e:
                reports.say(self, "ERROR", str(e))
                return {"CANCELLED"}
        if self._not_saved:
            reports.say(self, "WARNING", self._not_saved)
        if comparison["not_restored"]:
            reports.say(self, "WARNING", "Settings not put back: " + "; ".join(comparison["not_restored"]))
        seconds = comparison["seconds"]
        notes = [comparison["camera_news"]] if comparison["camera_news"] else []
        if comparison["left_out"]:
            notes.append(left_out_text(comparison["left_out"]))
        lens = comparison["lens_differences"]
        means = [f"{name} " + "/".join(f"{v:.3g}" for v in lens[key])
                 for name, key in (("tracer", "tracer_mean"), ("Cycles", "cycles_mean"))]
        notes.append(f"Lens pixels ({lens['pixels']}, found by geometry), linear RGB means: " + ", ".join(means))
        notes.append(comparison["by_design"])
        return reports.finished(self, f"Tracer {seconds['tracer']:.2f} s, Cycles {seconds['cycles']:.1f} s "
                                      f"({comparison['samples']} spp); {lens_figures_text(lens)}", notes)


classes = (LAMP_OT_compare_cycles,)

register, _unregister = actions.register_actions_factory(
    classes, (("lamp.compare_cycles", "Compare with Cycles", "IMAGE_REFERENCE"),))


def unregister() -> None:
    run = running()
    if run is not None:  # a comparison still under way: its settings back, its handlers removed
        run.close()
    unwatch()
    _unregister()

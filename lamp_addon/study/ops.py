# SPDX-License-Identifier: GPL-3.0-or-later
"""Running a design study from Blender and using its contact sheet.

From the interface the variants render in worker processes (``core_tracer.study_run``) while a
modal operator polls them on a timer: the interface keeps responding, the progress shows in the
status bar, Esc cancels (the workers are stopped, nothing is kept). Called from a script or in
background mode, where there are no windows, the operator renders synchronously (``execute``).
The sheet becomes the "Lamp Study" image, shown in an Image Editor, carrying the study's JSON
as a custom property; from it a sheet file (EXR/PNG, study in the header) can be saved, and any
variant applied to the design or kept as a preset.

Only ``{'REGISTER'}`` for the study itself, like ``render.render``: it makes a picture and changes
nothing the design is made of. Applying a variant changes the design, so that one has UNDO.
"""

from __future__ import annotations

import json
import os
import time

import bpy
from bpy.props import StringProperty
from bpy_extras.io_utils import ExportHelper

from ...core_tracer.library import presets as P
from ...core_tracer.scene.reading import SceneError
from ...core_tracer.study import definition as st
from .. import image_view, jobs, reports
from ..design import properties as design_properties
from ..freeform import properties as freeform_properties
from ..freeform import scene as freeform_scene
from ..freeform import written as freeform_written
from ..presets import library as preset_library
from . import settings
from .settings import last_study, sheet_image

# ---------------------------------------------------------------------------------------------
# The sheet image


def show_sheet(context, study: st.Study, images: list, measured: list | None = None) -> bpy.types.Image:
    """Compose the contact sheet into the "Lamp Study" image and show it in an Image Editor; with
    ``measured`` (each variant's values of the study's measures) the values go under the cells."""
    from ...core_tracer.study import sheet as study_sheet

    # One exposure for every variant, so the cells compare; each cell through display.shown, as its
    # light model says (a photometric variant's XYZ at one EV100), scene-linear for Blender's view.
    sheet, used = study_sheet.composed(settings.worded(study), images, exposure="auto",  # labels in the panel's words
                                       measured=measured)
    image = image_view.show_linear(settings.SHEET_IMAGE, sheet, image_view.stops_of(used), context.scene)
    if used.ev100 is not None:
        image[image_view.EV100_PROPERTY] = used.ev100
    elif image_view.EV100_PROPERTY in image:
        del image[image_view.EV100_PROPERTY]
    text = study.to_json()
    image[settings.STUDY_PROPERTY] = text
    settings.remember_study(study, text)
    image_view.show_image(context, image)
    return image


def render_study(context, workers: int | None = None) -> tuple[bpy.types.Image, st.Study, float]:
    """Build the study of the settings, render it (blocking) and show its sheet; the image, the study
    and the render time. Raises ``SceneError`` for a bad setting or design."""
    from ...core_tracer.study import run as study_run

    study = settings.study_from_settings(context.scene)
    traced = freeform_written.runnable(study)  # a free-form design's variants: its mesh file by its full path
    if workers is None:
        workers = context.scene.lamp_study.workers or None
    start = time.perf_counter()
    if settings.uses_cluster(context.scene.lamp_study):
        run = _cluster_run(context, traced)
        try:
            run.start()
            while not run.poll(timeout=0.05):
                pass
            images = run.images
        finally:
            run.close()
    else:
        images = study_run.run_study(traced, workers)
    measured = None
    if study.measured:
        from ...core_tracer.study import measured as study_measured

        measured = study_measured.measure_variants([v.scene for v in traced.variants], study.measured.names)
    seconds = time.perf_counter() - start
    return show_sheet(context, study, images, measured), study, seconds


class VariantMeasures:
    """The study's measures of each variant, one ``measure`` worker process after another (the
    Measures panel's ``MeasureRun``), so the interface keeps responding and Esc stops them."""

    def __init__(self, study: st.Study):
        import tempfile

        self.study = study
        self.values: list[dict] = []
        self._folder = tempfile.mkdtemp(prefix="lamp_study_measures_")
        self._run = None

    @property
    def fraction(self) -> float:
        current = self._run.fraction if self._run is not None else 0.0
        return min(1.0, (len(self.values) + current) / len(self.study))

    def poll(self) -> bool:
        """True once every variant is measured; raises ``RuntimeError`` when a measure fails."""
        from ...core_tracer.measures import by_name
        from ..measures.ops import MeasureRun

        if self._run is not None and self._run.poll():
            problem = self._run.error()
            self._run.close()
            if problem is not None:
                self._run = None
                raise RuntimeError(f"measuring variant {len(self.values) + 1}: {problem}")
            path = os.path.join(self._run.folder, "measures.json")
            with open(path, encoding="utf-8") as f:
                self.values.append(by_name.values(json.load(f), self.study.measured.names))
            self._run = None
        if len(self.values) == len(self.study):
            return True
        if self._run is None:
            index = len(self.values)
            self._run = MeasureRun(self.study.variants[index].scene, os.path.join(self._folder, f"variant-{index:02d}"),
                                   beam_files=False)
            self._run.start()
        return False

    def close(self) -> None:
        import shutil

        if self._run is not None:
            self._run.close()
            self._run = None
        shutil.rmtree(self._folder, ignore_errors=True)


def _cluster_run(context, study: st.Study):
    """The study as Dask tasks on the scheduler the settings name; results kept in the cell cache
    (``core_tracer.cluster``). Raises ``SceneError`` when Dask is not installed in Blender's Python."""
    from ...core_tracer.cluster import engine

    if not engine.available():
        raise SceneError("Scheduler", "needs Dask (distributed) in Blender's Python, which is not installed; "
                                      "allowed \"local\" (this computer's worker processes)")
    from ...core_tracer.cluster.cache import CellCache
    from ...core_tracer.study.on_cluster import DaskStudyRun

    return DaskStudyRun(study, context.scene.lamp_study.scheduler.strip(), cache=CellCache())


def _summary(study: st.Study, seconds: float) -> str:
    shape = " x ".join(str(len(a.values)) for a in study.axes)
    w, h = study.size
    return f"Lamp Study: {shape} variants of {w}x{h} in {seconds:.1f} s"


# ---------------------------------------------------------------------------------------------
# Operators


class LAMP_OT_study_run(jobs.ModalJob, bpy.types.Operator):
    """Render variants of the design (one or two parameters varied) on a contact sheet"""

    bl_idname = "lamp.study_run"
    bl_label = "Run Study"

    busy_message = "A study is running (Esc cancels it)"
    cancelled_message = "Lamp Study cancelled"
    settings = "lamp_study"

    def execute(self, context):
        from ...core_tracer.study.run import StudyError

        try:
            image, study, seconds = render_study(context)
        except SceneError as e:
            return reports.cancelled(self, str(e))
        except (StudyError, OSError, RuntimeError) as e:  # RuntimeError: a task failed on the cluster
            return reports.cancelled(self, f"Lamp Study failed: {e}")
        return reports.finished(self, _summary(study, seconds))

    def invoke(self, context, event):
        if bpy.app.background or context.window is None:
            return self.execute(context)
        from ...core_tracer.study.run import StudyRun

        try:
            self._study = settings.study_from_settings(context.scene)
            self._traced = freeform_written.runnable(self._study)  # a free-form design's mesh file by its full path
        except SceneError as e:
            return reports.cancelled(self, str(e))
        try:
            if settings.uses_cluster(context.scene.lamp_study):
                self._run = _cluster_run(context, self._traced)
            else:
                self._run = StudyRun(self._traced, context.scene.lamp_study.workers or None)
        except SceneError as e:
            return reports.cancelled(self, str(e))
        try:
            self._run.start()
        except OSError as e:
            return reports.cancelled(self, f"Lamp Study cannot start its workers: {e}")
        self._start = time.perf_counter()
        self._measures = None
        return self.begin_modal(context, self._run)

    def step(self, context):
        from ...core_tracer.study.run import StudyError

        try:
            finished = self._run.poll()
        except (StudyError, RuntimeError) as e:  # RuntimeError: a task failed on the cluster
            self.end_modal(context)
            return reports.cancelled(self, f"Lamp Study failed: {e}")
        if not finished:
            return None
        if self._study.measured:  # then each variant is measured, one worker process after another
            if self._measures is None:
                self._measures = VariantMeasures(self._traced)
            try:
                if not self._measures.poll():
                    return None
            except (RuntimeError, OSError) as e:
                self.end_modal(context)
                return reports.cancelled(self, f"Lamp Study failed: {e}")
        seconds = time.perf_counter() - self._start
        images = list(self._run.images)
        measured = self._measures.values if self._measures is not None else None
        self.end_modal(context)
        show_sheet(context, self._study, images, measured)
        return reports.finished(self, _summary(self._study, seconds))

    def abandon(self, context):
        self._run.cancel()
        if self._measures is not None:
            self._measures.close()

    def end_modal(self, context) -> None:
        super().end_modal(context)
        self._run.close()
        if self._measures is not None:
            self._measures.close()

    def status(self) -> str:
        if self._measures is not None:
            done = len(self._measures.values)
            return (f"Lamp Study: measuring variant {min(done + 1, len(self._study))}/{len(self._study)}, "
                    f"{100 * self._measures.fraction:.0f}% (Esc to cancel)")
        run = self._run
        return f"Lamp Study: {run.done}/{run.total} variants, {100 * run.fraction:.0f}% (Esc to cancel)"

    def fraction(self) -> float:
        if self._measures is not None:
            return self._measures.fraction
        return self._run.fraction


def _chosen_variant(operator, context) -> tuple[st.Study, int] | None:
    study = last_study()
    index = context.scene.lamp_study.variant - 1
    if study is None:
        operator.report({"ERROR"}, "There is no study; run one first")
        return None
    if not 0 <= index < len(study):
        operator.report({"ERROR"}, f"Variant {index + 1} does not exist; the study has {len(study)} variants")
        return None
    return study, index


class _OnLastStudy:
    """Operators on the last study's sheet or its chosen variant: available once there is a study."""

    @classmethod
    def poll(cls, context):
        if last_study() is None:
            cls.poll_message_set("Run a study first")
            return False
        return True


class LAMP_OT_study_apply_variant(_OnLastStudy, bpy.types.Operator):
    """Set the design's varied parameters to the values of the chosen variant"""

    bl_idname = "lamp.study_apply_variant"
    bl_label = "Apply to Design"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        chosen = _chosen_variant(self, context)
        if chosen is None:
            return {"CANCELLED"}
        study, index = chosen
        try:
            design = design_properties.design_to_scene(context.scene)
            parts = freeform_written.shown_parts(context.scene)  # a free-form part's values go to its object
            if parts:
                design["freeform"] = freeform_scene.freeform_section(parts)
            # The design may have changed since the study: its lamps and parts are checked again.
            parameters = tuple(st.resolve_parameter(axis.parameter.text, design) for axis in study.axes)
            st.apply_values(design, parameters, study.variants[index].values)
            for obj, part in zip(parts, design.pop("freeform", {"parts": ()})["parts"], strict=True):
                freeform_properties.set_role(obj, part["role"], part[part["role"]])
            design_properties.scene_to_design(context.scene, design)
        except SceneError as e:
            return reports.cancelled(self, str(e))
        return reports.finished(self, f"Design set to {study.variants[index].label(study)}")


class LAMP_OT_study_keep_variant(_OnLastStudy, bpy.types.Operator):
    """Save the chosen variant as a preset in your preset library"""

    bl_idname = "lamp.study_keep_variant"
    bl_label = "Keep as Preset"
    bl_options = {"REGISTER"}

    def execute(self, context):
        chosen = _chosen_variant(self, context)
        if chosen is None:
            return {"CANCELLED"}
        study, index = chosen
        libraries, notes = preset_library.libraries(context)
        writable = [lib for lib in libraries if lib.writable]
        writable.sort(key=lambda lib: lib.name != preset_library.USER_LIBRARY_NAME)
        if not writable:
            return reports.cancelled(self, notes[0] if notes else "No writable preset library; add a preset folder "
                                           "in the add-on preferences")
        try:
            entry = P.save_preset(writable[0], study.variant_name(index), study.variant_scene(index))
        except (SceneError, OSError) as e:
            return reports.cancelled(self, str(e))
        preset_library.mark_stale()
        return reports.finished(self, f"Saved \"{entry.name}\" in {writable[0].name}")


class LAMP_OT_study_save_sheet(_OnLastStudy, bpy.types.Operator, ExportHelper):
    """Save the contact sheet as PNG (as shown: the scene's view transform) or EXR (linear), with the
    study in its header"""

    bl_idname = "lamp.study_save_sheet"
    bl_label = "Save Sheet"
    bl_options = {"REGISTER"}

    filename_ext = ".png"
    filter_glob: StringProperty(default="*.png;*.exr", options={"HIDDEN"})

    def check(self, context):
        # Keep a .exr the user typed; anything else becomes .png.
        if self.filepath.lower().endswith(".exr"):
            return False
        return super().check(context)

    def execute(self, context):
        from ...core_tracer.study import sheet as study_sheet

        study = last_study()
        image = sheet_image()
        if study is None or image is None:
            return reports.cancelled(self, "There is no study sheet; run a study first")
        if not image_view.openimageio_available():
            return reports.cancelled(self, f"Sheet not saved: {image_view.NO_OPENIMAGEIO}; save the image from the "
                                           "Image Editor")
        try:
            # a free-form design's meshes beside the sheet (first, as an export writes the .glb before
            # the JSON naming it), where ``study --study`` finds them
            meshes = freeform_written.copy_beside(study, self.filepath)
            study_sheet.write_composed(self.filepath, study, image_view.image_to_array(image),
                                       view=image_view.scene_view(context.scene),
                                       exposure=image_view.image_exposure(image),
                                       view_exposure=context.scene.view_settings.exposure,
                                       ev100=image.get(image_view.EV100_PROPERTY))
        except (SceneError, OSError) as e:
            return reports.cancelled(self, str(e))
        beside = f" and {os.path.basename(meshes)} beside it" if meshes is not None else ""
        return reports.finished(self, f"Saved {self.filepath}{beside}")


classes = (LAMP_OT_study_run, LAMP_OT_study_apply_variant, LAMP_OT_study_keep_variant, LAMP_OT_study_save_sheet)


register, unregister = bpy.utils.register_classes_factory(classes)

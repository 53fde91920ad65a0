# SPDX-License-Identifier: GPL-3.0-or-later
"""Running a design study from Blender and using its contact sheet (issue 5).

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

import time

import bpy
from bpy.props import StringProperty
from bpy_extras.io_utils import ExportHelper

from ..core_tracer.library import presets as P
from ..core_tracer.scene.validate import SceneError
from ..core_tracer.study import definition as st
from . import design_properties, image_view, study_settings
from .study_settings import last_study, sheet_image

POLL_SECONDS = 0.1


# ---------------------------------------------------------------------------------------------
# The sheet image


def show_sheet(context, study: st.Study, images: list) -> bpy.types.Image:
    """Compose the contact sheet into the "Lamp Study" image and show it in an Image Editor."""
    from ..core_tracer.study import sheet as study_sheet

    sheet = study_sheet.compose(study, images)
    image = image_view.image_from_array(study_settings.SHEET_IMAGE, sheet)
    text = study.to_json()
    image[study_settings.STUDY_PROPERTY] = text
    study_settings.remember_study(study, text)
    image_view.show_image(context, image)
    return image


def render_study(context, workers: int | None = None) -> tuple[bpy.types.Image, st.Study, float]:
    """Build the study of the settings, render it (blocking) and show its sheet; the image, the study
    and the render time. Raises ``SceneError`` for a bad setting or design."""
    from ..core_tracer.study import run as study_run

    study = study_settings.study_from_settings(context.scene)
    if workers is None:
        workers = context.scene.lamp_study.workers or None
    start = time.perf_counter()
    images = study_run.run_study(study, workers)
    seconds = time.perf_counter() - start
    return show_sheet(context, study, images), study, seconds


def _summary(study: st.Study, seconds: float) -> str:
    shape = " x ".join(str(len(a.values)) for a in study.axes)
    w, h = study.size
    return f"Lamp Study: {shape} variants of {w}x{h} in {seconds:.1f} s"


# ---------------------------------------------------------------------------------------------
# Operators


class LAMP_OT_study_run(bpy.types.Operator):
    """Render variants of the design (one or two parameters varied) on a contact sheet"""

    bl_idname = "lamp.study_run"
    bl_label = "Run Study"
    bl_options = {"REGISTER"}

    _running = False  # one interactive study at a time

    @classmethod
    def poll(cls, context):
        if context.scene is None or not hasattr(context.scene, "lamp_study"):
            cls.poll_message_set("No scene")
            return False
        if LAMP_OT_study_run._running:
            cls.poll_message_set("A study is running (Esc cancels it)")
            return False
        return True

    def execute(self, context):
        from ..core_tracer.study.run import StudyError

        try:
            image, study, seconds = render_study(context)
        except SceneError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        except (StudyError, OSError) as e:
            self.report({"ERROR"}, f"Lamp Study failed: {e}")
            return {"CANCELLED"}
        self.report({"INFO"}, _summary(study, seconds))
        return {"FINISHED"}

    def invoke(self, context, event):
        if bpy.app.background or context.window is None:
            return self.execute(context)
        from ..core_tracer.study.run import StudyRun

        try:
            self._study = study_settings.study_from_settings(context.scene)
        except SceneError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        self._run = StudyRun(self._study, context.scene.lamp_study.workers or None)
        try:
            self._run.start()
        except OSError as e:
            self.report({"ERROR"}, f"Lamp Study cannot start its workers: {e}")
            return {"CANCELLED"}
        self._start = time.perf_counter()
        wm = context.window_manager
        self._timer = wm.event_timer_add(POLL_SECONDS, window=context.window)
        wm.modal_handler_add(self)
        wm.progress_begin(0, 100)
        LAMP_OT_study_run._running = True
        self._status(context)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        from ..core_tracer.study.run import StudyError

        if event.type == "ESC" and event.value == "PRESS":
            self._run.cancel()
            self._finish(context)
            self.report({"WARNING"}, "Lamp Study cancelled")
            return {"CANCELLED"}
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        try:
            finished = self._run.poll()
        except StudyError as e:
            self._finish(context)
            self.report({"ERROR"}, f"Lamp Study failed: {e}")
            return {"CANCELLED"}
        if not finished:
            context.window_manager.progress_update(int(100 * self._run.fraction))
            self._status(context)
            return {"PASS_THROUGH"}
        seconds = time.perf_counter() - self._start
        images = list(self._run.images)
        self._finish(context)
        show_sheet(context, self._study, images)
        self.report({"INFO"}, _summary(self._study, seconds))
        return {"FINISHED"}

    def cancel(self, context):
        # Blender ends the operator (file load, quit): stop the workers and clean up.
        self._run.cancel()
        self._finish(context)

    def _status(self, context) -> None:
        run = self._run
        context.workspace.status_text_set(f"Lamp Study: {run.done}/{run.total} variants, "
                                          f"{100 * run.fraction:.0f}% (Esc to cancel)")

    def _finish(self, context) -> None:
        self._run.close()
        wm = context.window_manager
        wm.event_timer_remove(self._timer)
        wm.progress_end()
        context.workspace.status_text_set(None)
        LAMP_OT_study_run._running = False


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
            for axis, value in zip(study.axes, study.variants[index].values, strict=True):
                parameter = st.resolve_parameter(axis.parameter.text, design)  # the design may have changed
                st.apply_value(design, parameter, value)
            design_properties.scene_to_design(context.scene, design)
        except SceneError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        self.report({"INFO"}, f"Design set to {study.variants[index].label(study)}")
        return {"FINISHED"}


class LAMP_OT_study_keep_variant(_OnLastStudy, bpy.types.Operator):
    """Save the chosen variant as a preset in your preset library"""

    bl_idname = "lamp.study_keep_variant"
    bl_label = "Keep as Preset"
    bl_options = {"REGISTER"}

    def execute(self, context):
        from . import preset_library

        chosen = _chosen_variant(self, context)
        if chosen is None:
            return {"CANCELLED"}
        study, index = chosen
        libraries, notes = preset_library.libraries(context)
        writable = [lib for lib in libraries if lib.writable]
        writable.sort(key=lambda lib: lib.name != preset_library.USER_LIBRARY_NAME)
        if not writable:
            self.report({"ERROR"}, notes[0] if notes else "No writable preset library; add a preset folder "
                                                          "in the add-on preferences")
            return {"CANCELLED"}
        try:
            entry = P.save_preset(writable[0], study.variant_name(index), study.variant_scene(index))
        except (SceneError, OSError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        preset_library.mark_stale()
        self.report({"INFO"}, f"Saved \"{entry.name}\" in {writable[0].name}")
        return {"FINISHED"}


class LAMP_OT_study_save_sheet(_OnLastStudy, bpy.types.Operator, ExportHelper):
    """Save the contact sheet as EXR (linear) or PNG (sRGB), with the study in its header"""

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
        from ..core_tracer.study import sheet as study_sheet

        study = last_study()
        image = sheet_image()
        if study is None or image is None:
            self.report({"ERROR"}, "There is no study sheet; run a study first")
            return {"CANCELLED"}
        if not _openimageio_available():
            self.report({"ERROR"}, "This Blender has no OpenImageIO module; save the image from the Image Editor")
            return {"CANCELLED"}
        try:
            study_sheet.write_sheet(self.filepath, study, image_view.image_to_array(image))
        except (SceneError, OSError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        self.report({"INFO"}, f"Saved {self.filepath}")
        return {"FINISHED"}


def _openimageio_available() -> bool:
    try:
        import OpenImageIO  # noqa: F401
    except ImportError:
        expose = getattr(bpy.utils, "expose_bundled_modules", None)  # Blender 4.4+: its own OpenImageIO
        if expose is None:
            return False
        expose()
        try:
            import OpenImageIO  # noqa: F401
        except ImportError:
            return False
    return True


classes = (LAMP_OT_study_run, LAMP_OT_study_apply_variant, LAMP_OT_study_keep_variant, LAMP_OT_study_save_sheet)


register, unregister = bpy.utils.register_classes_factory(classes)

"""Render with Lamp Tracer: the tracer into an image shown in an Image Editor.

From the interface the tracer runs on a worker thread (numpy releases the GIL) while a modal
operator polls it on a timer: the image fills in band by band, the progress shows in the
status bar, Esc cancels, the interface keeps responding. Called from a script, or in
background mode where there are no windows, the operator renders synchronously (``execute``).

The image follows the one exposure policy: the exposure belongs to the view. It holds what F12
renders (the paper model's linear values, or a photometric design's at its EV100) and is shown at
the scene's exposure, as F12 is; rendering never changes the exposure or exposes the image on its
own, so a stop lamp rendered after a tail lamp shows brighter by the ratio of their bulbs. *Exposure
from Design* is the explicit way to expose for the design in view.

Only ``{'REGISTER'}``, like Blender's own ``render.render``: the operator makes a picture of
the design and changes nothing the design is made of, so there is nothing for undo to take
back (and an undo step pushed when a background render ends would land between whatever
the user did meanwhile).
"""

from __future__ import annotations

import threading
import time

import bpy
import numpy as np

from ...core_tracer.images import glare
from ...core_tracer.raytrace import band_pool
from ...core_tracer.scene.reading import SceneError
from .. import actions, image_view, jobs, reports
from ..design import camera, view_link
from ..design import validity as design_validity
from . import photometric_display

IMAGE_NAME = "Lamp Tracer"


class TracerJob:
    """One tracer render on a worker thread. The worker touches only numpy arrays and plain
    attributes; the main thread reads them (``bpy`` is not thread-safe)."""

    def __init__(self, scene: dict):
        self.scene = scene
        self.shown_as = photometric_display.for_scene(scene)  # photometric: XYZ rows to scene-linear
        width, height = scene["image"]["width"], scene["image"]["height"]
        self.rows = np.zeros((height, width, 3), np.float32)
        self.progress = 0.0
        self.rows_done = 0
        self.updates = 0  # how often ``rows`` changed: the main thread shows it again when this grows
        self.stop_requested = False
        self.cancelled = False
        self.error: str | None = None
        self.seconds = 0.0
        self.done = threading.Event()
        self._thread = threading.Thread(target=self._run, name="Lamp Tracer", daemon=True)

    def start(self) -> TracerJob:
        self._thread.start()
        return self

    def stop(self) -> None:
        self.stop_requested = True

    def wait(self, timeout: float | None = None) -> bool:
        return self.done.wait(timeout)

    def _on_rows(self, row_start: int, row_stop: int, rows: np.ndarray) -> None:
        self.rows[row_start:row_stop] = rows if self.shown_as is None else self.shown_as.linear(rows)
        self.rows_done += row_stop - row_start
        self.updates += 1

    def _set_progress(self, fraction: float) -> None:
        self.progress = fraction

    def _run(self) -> None:
        from ... import core_tracer

        start = time.perf_counter()
        try:
            core_tracer.render_passes(self.scene, progress=self._set_progress,
                                      should_stop=lambda: self.stop_requested, on_rows=self._on_rows,
                                      pool=band_pool.shared())
            shown = glare.apply(self.rows, self.scene)  # as render_to_image: the same pixels
            if shown is not self.rows:
                self.rows[:] = shown
                self.updates += 1
        except core_tracer.RenderCancelled:
            self.cancelled = True
        except Exception as e:  # a tracer bug: shown to the user by the main thread, not lost in a thread
            self.error = f"{type(e).__name__}: {e}"
        finally:
            self.seconds = time.perf_counter() - start
            self.done.set()


def render_to_image(bl_scene) -> tuple[bpy.types.Image, float]:
    """Render the scene with the tracer synchronously into the "Lamp Tracer" image, shown at the
    scene's exposure as F12 is. Returns the image and the render time in seconds. Raises ``SceneError``."""
    from ... import core_tracer

    view_link.sync_view(bl_scene)
    scene = camera.scene_for_render(bl_scene)
    start = time.perf_counter()
    shown_as = photometric_display.for_scene(scene)
    if shown_as is not None:  # photometric: the design's EV100 is in the pixels (render.photometric_display)
        rgb = glare.apply(shown_as.linear(core_tracer.render(scene)), scene)
    else:
        rgb = glare.apply(core_tracer.render(scene), scene)
    seconds = time.perf_counter() - start
    return image_view.show_as_render(IMAGE_NAME, rgb), seconds


class LAMP_OT_render_tracer(jobs.ModalJob, bpy.types.Operator):
    """Render the lamp design with the paper's tracer into the "Lamp Tracer" image"""

    bl_idname = "lamp.render_tracer"
    bl_label = "Render with Lamp Tracer"

    busy_message = "A Lamp Tracer render is running (Esc cancels it)"

    @classmethod
    def refusal(cls, context):
        if context.scene.camera is None:
            return "The scene has no camera; Frame Lamp (Camera & Image) or Build Lamp makes one"
        return None

    def execute(self, context):
        try:
            image, seconds = render_to_image(context.scene)
        except SceneError as e:
            return reports.cancelled(self, design_validity.message(context.scene, e))
        image_view.show_image(context, image)
        return reports.finished(self, f"Lamp Tracer: {image.size[0]}x{image.size[1]} in {seconds:.2f} s")

    def invoke(self, context, event):
        if bpy.app.background or context.window is None:
            return self.execute(context)
        view_link.sync_view(context.scene)
        try:
            scene = camera.scene_for_render(context.scene)
            self._job = TracerJob(scene)
        except SceneError as e:
            return reports.cancelled(self, design_validity.message(context.scene, e))
        self._image = image_view.show_as_render(IMAGE_NAME, self._job.rows)
        image_view.show_image(context, self._image)
        self._shown_updates = 0
        outcome = self.begin_modal(context, self._job)
        self._job.start()
        return outcome

    def escape(self, context):
        self._job.stop()  # the worker stops between bands; the timer then ends the operator
        return {"RUNNING_MODAL"}

    def step(self, context):
        job = self._job
        self._show_rows(context)
        if not job.done.is_set():
            return None
        self.end_modal(context)
        self._show_rows(context)
        if job.error is not None:
            return reports.cancelled(self, f"Lamp Tracer failed: {job.error}")
        if job.cancelled:
            reports.say(self, "WARNING", "Lamp Tracer render cancelled")
            return {"CANCELLED"}
        width, height = self._image.size
        return reports.finished(self, f"Lamp Tracer: {width}x{height} in {job.seconds:.2f} s")

    def abandon(self, context):
        self._job.stop()
        self._job.wait(5.0)

    def status(self) -> str:
        if self._job.stop_requested:
            return "Lamp Tracer: cancelling..."
        return f"Lamp Tracer: {100 * self._job.progress:.0f}% (Esc to cancel)"

    def fraction(self) -> float:
        return self._job.progress

    def _show_rows(self, context) -> None:
        if self._job.updates != self._shown_updates:
            self._shown_updates = self._job.updates
            self._image.pixels.foreach_set(image_view.rgba_rows(self._job.rows))
            self._image.update()
            image_view.redraw_image_editors(context, self._image)


classes = (LAMP_OT_render_tracer,)


register, unregister = actions.register_actions_factory(
    classes, (("lamp.render_tracer", "Render with Lamp Tracer", "RENDER_STILL"),))

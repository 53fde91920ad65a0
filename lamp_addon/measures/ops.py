# SPDX-License-Identifier: GPL-3.0-or-later
"""Measuring the design from Blender, and opening the one-page report.

``Measure Design`` runs the ``measure`` command of ``core_tracer`` (the same code as
``python -m core_tracer measure``) in a worker process (``core_tracer.cli.job``) while a modal
operator polls it on a timer: the interface keeps responding, the progress shows in the status
bar, Esc stops the worker (SIGTERM: the command leaves no partial folder). Called from a script or in
background mode the operator waits for it (``execute``). The results go to ``<name>_measures`` next
to the saved .blend, or to a temporary folder while the file is unsaved; the panel reads the table
from its ``measures.json``; ``Open Report`` shows its ``measures.png`` in an Image Editor.

A design with free-form parts is measured as F12 renders it, its meshes written with Blender's glTF
exporter beside the worker's scene file (``freeform.written``), as ``measure`` reads an exported pair.

Only ``{'REGISTER'}``: measuring changes nothing the design is made of.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import tempfile
import threading
import time

import bpy

from ...core_tracer import processes
from ...core_tracer.scene.beside import with_curves_at
from ...core_tracer.scene.reading import SceneError
from .. import image_view, jobs, reports
from ..design import camera as render_camera
from ..design import properties as design_properties
from ..freeform import written as freeform_written
from . import settings

REPORT_IMAGE = "Lamp Measures"
_DIRECTION = re.compile(r"intensity: direction (\d+) of (\d+)")
_BEAM_DIRECTION = re.compile(r"beam files: direction (\d+) of (\d+)")
# Share of the run each stage starts at (the intensity grid is most of it: benchmarks/bench_measures.py).
_STAGES = (("homogeneity", 0.75), ("beam files", 0.8))


def measured_scene(bl_scene) -> dict:
    """The design as the measures see it: through Blender's scene camera when there is one (the
    report's picture of the lamp), else the design's own camera; with free-form parts, the design F12
    renders, its meshes written for the worker (``freeform.written``) and named by their full path.
    Raises ``SceneError``."""
    if bl_scene.camera is not None:
        scene = render_camera.scene_for_render(bl_scene)
    else:
        scene = design_properties.design_to_scene(bl_scene)
    parts = freeform_written.shown_parts(bl_scene)
    return freeform_written.traced(freeform_written.with_parts(bl_scene, scene, parts)) if parts else scene


def not_photometric(bl_scene) -> bool:
    return bl_scene.lamp_design.light_model != "photometric"


class MeasureRun:
    """The ``measure`` command in a worker process; its progress read from its output on a thread."""

    def __init__(self, scene: dict, folder: str, beam_files: bool):
        self.folder = folder
        self.fraction = 0.0
        self.stage = "starting"
        self._lines: list[str] = []
        self._scratch = tempfile.mkdtemp(prefix="lamp_measures_scene_")
        self._scene_path = os.path.join(self._scratch, "scene.json")
        if "freeform" in scene:  # the mesh file beside the scene file, named plainly, as a pair has it
            mesh_file = scene["freeform"]["mesh_file"]
            shutil.copyfile(mesh_file, os.path.join(self._scratch, os.path.basename(mesh_file)))
            scene = with_curves_at(scene, {("freeform", "mesh_file"): os.path.basename(mesh_file)})
        with open(self._scene_path, "w", encoding="utf-8") as f:
            json.dump(scene, f)
        # --exit-zero: a failing regulation is a finding the panel shows, not a failed run
        arguments = [self._scene_path, "-o", folder, "--exit-zero"] + ([] if beam_files else ["--no-beam-files"])
        self._command = processes.worker_command("cli.job", "measure", *arguments)
        self._process: subprocess.Popen | None = None
        self._reader: threading.Thread | None = None
        self.cancelled = False

    def start(self) -> None:
        self._errors = open(os.path.join(self._scratch, "stderr.txt"), "w+", encoding="utf-8")  # never a full pipe
        self._process = subprocess.Popen(self._command, stdout=subprocess.PIPE, stderr=self._errors,
                                         stdin=subprocess.DEVNULL, text=True, encoding="utf-8",
                                         errors="replace", env=processes.worker_environment())
        self._reader = threading.Thread(target=self._read, name="lamp-measures", daemon=True)
        self._reader.start()

    def _read(self) -> None:
        for line in self._process.stdout:
            line = line.strip()
            self._lines.append(line)
            found = _DIRECTION.match(line)
            if found:
                done, total = int(found.group(1)), int(found.group(2))
                self.fraction = 0.75 * (done - 1) / max(1, total)
                self.stage = f"intensity, direction {done} of {total}"
            for stage, start in _STAGES:
                if line.startswith(stage):
                    self.fraction, self.stage = start, stage
            found = _BEAM_DIRECTION.match(line)
            if found:  # the beam files' sweep, printed every 200 directions
                done, total = int(found.group(1)), int(found.group(2))
                self.fraction = 0.8 + 0.2 * (done - 1) / max(1, total)
                self.stage = f"beam files, direction {done} of {total}"

    def poll(self, timeout: float = 0.0) -> bool:
        """True once the worker has ended."""
        if timeout:
            try:
                self._process.wait(timeout=timeout)
            except subprocess.TimeoutExpired:
                return False
        return self._process.poll() is not None

    def error(self) -> str | None:
        """None when the worker succeeded, else its one-line error."""
        code = self._process.returncode
        if code == 0:
            return None
        self._errors.seek(0)
        lines = [line for line in self._errors.read().splitlines() if line.strip()]
        return lines[-1].removeprefix("error: ") if lines else f"the measuring process ended with status {code}"

    def cancel(self) -> None:
        self.cancelled = True
        if self._process is not None and self._process.poll() is None:
            self._process.terminate()  # SIGTERM: the command removes its partial folder
            try:
                self._process.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self._process.kill()
                self._process.wait()

    def close(self) -> None:
        if self._process is not None:
            if self._process.poll() is None:
                self.cancel()
            if self._reader is not None:
                self._reader.join(timeout=5)
            self._process.stdout.close()
            self._errors.close()
        for name in os.listdir(self._scratch):
            os.remove(os.path.join(self._scratch, name))
        os.rmdir(self._scratch)


def _start(context) -> MeasureRun:
    """The run for the scene's design (not yet started). Raises ``SceneError``."""
    if not processes.python_runs_workers():
        raise SceneError("Measure Design", "needs a Python interpreter to run its worker, which this Blender "
                                           "does not give; allowed: the command python -m core_tracer measure")
    if not_photometric(context.scene):
        raise SceneError("Light Model", "is Paper; the measures need Photometric (light in lm and cd)")
    scene = measured_scene(context.scene)
    temporary = os.path.join(tempfile.gettempdir(), f"lamp_measures_{os.getpid()}")
    folder = settings.output_folder(bpy.data.filepath, temporary)
    return MeasureRun(scene, folder, context.scene.lamp_measures.beam_files)


def _finish(operator, context, run: MeasureRun, seconds: float) -> set[str]:
    problem = run.error()
    if problem is not None:
        return reports.cancelled(operator, f"Measures failed: {problem}")
    context.scene.lamp_measures.folder = run.folder
    measured = settings.last_measures(context.scene)
    if measured is None:
        return reports.cancelled(operator, f"Measures failed: no readable measures.json in {run.folder}")
    from ...core_tracer.measures import table

    for area in context.screen.areas if context.screen else ():
        area.tag_redraw()
    return reports.finished(operator, f"Measures in {seconds:.0f} s: {table.summary(measured)}",
                            [f"Written to {run.folder}"])


class LAMP_OT_measures_run(jobs.ModalJob, bpy.types.Operator):
    """Measure the design: each function's regulation grid (UN R148, FMVSS 108), the colour of its light
    and the evenness of its lit lens, with a one-page report"""

    bl_idname = "lamp.measures_run"
    bl_label = "Measure Design"

    busy_message = "The design is being measured (Esc cancels it)"
    cancelled_message = "Measures cancelled"
    settings = "lamp_measures"

    @classmethod
    def refusal(cls, context):
        return "The measures need the Photometric light model" if not_photometric(context.scene) else None

    def execute(self, context):
        try:
            run = _start(context)
        except SceneError as e:
            return reports.cancelled(self, str(e))
        start = time.perf_counter()
        try:
            run.start()
            run.poll(timeout=24 * 3600)
            return _finish(self, context, run, time.perf_counter() - start)
        except OSError as e:
            return reports.cancelled(self, f"Measures cannot start their worker: {e}")
        finally:
            run.close()

    def invoke(self, context, event):
        if bpy.app.background or context.window is None:
            return self.execute(context)
        try:
            self._run = _start(context)
            self._run.start()
        except SceneError as e:
            return reports.cancelled(self, str(e))
        except OSError as e:
            return reports.cancelled(self, f"Measures cannot start their worker: {e}")
        self._start = time.perf_counter()
        return self.begin_modal(context, self._run)

    def step(self, context):
        if not self._run.poll():
            return None
        seconds = time.perf_counter() - self._start
        self.end_modal(context)
        return _finish(self, context, self._run, seconds)

    def abandon(self, context):
        self._run.cancel()

    def end_modal(self, context) -> None:
        super().end_modal(context)
        self._run.close()

    def status(self) -> str:
        return f"Lamp Measures: {self._run.stage}, {100 * self._run.fraction:.0f}% (Esc to cancel)"


class LAMP_OT_measures_open_report(bpy.types.Operator):
    """Show the last measures' one-page report in an Image Editor"""

    bl_idname = "lamp.measures_open_report"
    bl_label = "Open Report"
    bl_options = {"REGISTER"}

    @classmethod
    def poll(cls, context):
        if context.scene is None or not hasattr(context.scene, "lamp_measures") \
                or settings.last_measures(context.scene) is None:
            cls.poll_message_set("Measure the design first")
            return False
        return True

    def execute(self, context):
        path = os.path.join(bpy.path.abspath(context.scene.lamp_measures.folder), "measures.png")
        if not os.path.isfile(path):
            return reports.cancelled(self, f"The report {path} is missing; measure the design again")
        image = bpy.data.images.get(REPORT_IMAGE)
        if image is not None and os.path.abspath(bpy.path.abspath(image.filepath)) == os.path.abspath(path):
            image.reload()
        else:
            if image is not None:
                bpy.data.images.remove(image)
            image = bpy.data.images.load(path, check_existing=False)
            image.name = REPORT_IMAGE
        image_view.show_image(context, image)
        return reports.finished(self, f"Report of the measures: {path}")


classes = (LAMP_OT_measures_run, LAMP_OT_measures_open_report)


register, unregister = bpy.utils.register_classes_factory(classes)

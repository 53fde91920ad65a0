"""Compare with Cycles: the same design, camera and resolution rendered by the paper's tracer and
by Cycles, side by side.

Both renders go through ``bpy.ops.render.render`` into the "Render Result" image, Cycles into
render slot 1 and the tracer (the Lamp Tracer render engine) into slot 2 (slot indices 0 and 1),
so J flips between them in the Image Editor; their pixels are read back with ``save_render`` to
OpenEXR (in background mode the Render Result has no pixels). A third image, "Lamp Compare",
holds the two halves with labels, both at one automatic exposure (``images.display``) and shown
through the scene's own view transform (``image_view``), so they always share one transform.
During the comparison the scene shows renders on the Standard view transform, under which the
tracer's linear RGB (the paper's stimulus values) and Cycles' radiance are shown the same way;
like every setting the comparison changes, it is put back afterwards.

One comparison is a ``CompareRun`` taken through the same steps on both paths: ``prepare``
(build the lamp, the scene camera, the render settings), for each stage ``start`` (render into
its slot) and ``collect`` (read the slot back), ``compose`` (the labelled image) and ``close``
(put every setting back, stop listening to the render handlers, remove the temporary files).

- ``execute`` (scripts, background mode, tests) renders with blocking ``render.render()`` calls
  (``compare_design``).
- From the interface the operator is modal, as Blender's own long renders are: each stage is a
  render job (``render.render('INVOKE_DEFAULT')``), so the interface stays live, Blender shows the
  render's progress and Esc cancels it. The ``render_complete`` / ``render_cancel`` handlers
  (added for the duration of the comparison, removed on every exit path and on unregister) mark
  the stage as ended; a window-manager timer then calls ``CompareRun.advance``, which reads the
  finished slot back and starts the next stage, or ends the comparison. Handlers run on Blender's
  render thread, so they only set plain attributes; everything that touches ``bpy`` happens on
  the timer.

The Cycles settings both renders use are in ``settings``; what is left out of the Cycles half in
``scope``; the operator in ``ops``.
"""

from __future__ import annotations

import os
import shutil
import tempfile
import time
from dataclasses import dataclass

import bpy
import numpy as np

from ...core_tracer.images import display
from ...core_tracer.scene.reading import SceneError
from .. import image_view, jobs
from ..convert import photometric_cycles
from ..convert.sheet import (
    difference_labels,
    difference_shown,
    differences,
    lens_differences,
    shown_side_by_side,
    side_by_side,
)
from ..design import builder as design_builder
from ..design import camera as render_camera
from ..design import lamp_camera, view_link
from ..design import root as design_root
from ..freeform import materials as freeform_materials
from ..freeform import parametric as freeform_parametric
from ..freeform import properties as freeform_properties
from ..render import photometric_display
from ..render.engine import ENGINE_ID
from .scope import needs_build, objects_outside_design
from .settings import MIN_BOUNCES, STANDARD_VIEW, SceneSettings, cycles_settings, exr_output_values

RENDER_RESULT = "Render Result"
COMPARE_IMAGE = "Lamp Compare"
DEFAULT_SAMPLES = 64

@dataclass(frozen=True)
class Stage:
    """One of the two renders: its key in the results, its name in messages, engine and slot."""

    name: str
    label: str
    engine: str
    slot: int


CYCLES = Stage("cycles", "Cycles", "CYCLES", 0)
TRACER = Stage("tracer", "Lamp Tracer", ENGINE_ID, 1)
STAGES = (CYCLES, TRACER)


class CompareError(Exception):
    """The comparison cannot go on (a render did not start, the scene changed between the renders)."""


class CompareCancelled(Exception):
    """A render of the comparison was cancelled (Esc)."""


# What the operator reports (RuntimeError: bpy.ops.render.render raises an engine's error as one).
REPORTED_ERRORS = (SceneError, CompareError, CompareCancelled, RuntimeError)


# ---------------------------------------------------------------------------------------------
# The render handlers: how a render job tells the comparison it has ended


JOB_KEY = "lamp.compare_cycles"  # the comparison under way is jobs.running(JOB_KEY): at most one


def _report_end(scene, how: str) -> None:
    # Called by Blender, for a render job on its render thread: plain attributes only.
    pointer = scene.as_pointer() if scene is not None else 0
    run = running()
    if run is not None and run.scene_pointer == pointer:
        run.report_end(how)


@bpy.app.handlers.persistent
def _on_render_complete(scene, *_args) -> None:
    _report_end(scene, "complete")


@bpy.app.handlers.persistent
def _on_render_cancel(scene, *_args) -> None:
    _report_end(scene, "cancel")


HANDLERS = {"render_complete": _on_render_complete, "render_cancel": _on_render_cancel}


def watch(run: CompareRun) -> None:
    """Make ``run`` the comparison the render handlers report to, adding the handlers."""
    try:
        jobs.claim(JOB_KEY, run, "A comparison with Cycles is already running")
    except jobs.JobBusy as e:
        raise CompareError(str(e)) from None
    for name, handler in HANDLERS.items():
        handlers = getattr(bpy.app.handlers, name)
        if handler not in handlers:
            handlers.append(handler)


def unwatch() -> None:
    """Stop reporting to any comparison and remove the handlers."""
    jobs.release(JOB_KEY)
    for name, handler in HANDLERS.items():
        handlers = getattr(bpy.app.handlers, name)
        while handler in handlers:
            handlers.remove(handler)


def running() -> CompareRun | None:
    """The comparison under way, if any."""
    return jobs.running(JOB_KEY)


# ---------------------------------------------------------------------------------------------
# One comparison, step by step


class CompareRun:
    """One comparison of the scene's design: the steps both paths take (see the module's doc).

    Used as a context manager, it is watched by the render handlers for the duration and closed
    at the end, however the block ends."""

    def __init__(self, bl_scene, *, samples: int = DEFAULT_SAMPLES, resolution: tuple[int, int] | None = None,
                 build: bool = True):
        self.bl_scene = bl_scene
        self.scene_pointer = bl_scene.as_pointer()
        self.samples = int(samples)
        self.resolution = resolution
        self.build = build
        self.scene: dict | None = None  # what the tracer renders, set by prepare
        self.stage: Stage | None = None
        self.ended: str | None = None  # "complete" or "cancel", from the render handlers
        self.images: dict[str, np.ndarray] = {}
        self.seconds: dict[str, float] = {}
        self.not_restored: list[str] = []
        self.left_out: list[str] = []  # objects hidden from the Cycles render: not part of the design
        self.camera_news = ""  # what making the Lamp Camera did, if it was made
        self.ev100: float | None = None  # photometric: the one EV100 both halves are shown at
        self._paused = False
        self._settings = SceneSettings()
        self._folder: str | None = None
        self._started_at = self._ended_at = 0.0

    def __enter__(self) -> CompareRun:
        watch(self)
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def report_end(self, how: str) -> None:
        """The running stage's render ended (``how`` "complete" or "cancel"). A cancel always wins."""
        if self.ended is None or how == "cancel":
            self._ended_at = time.perf_counter()
            self.ended = how

    def prepare(self) -> None:
        """Make sure the Lamp Camera exists (made and framed the first time, ``design.lamp_camera``), build
        the lamp when its objects are out of date, fix the scene the tracer renders, set the render
        settings both renders use and leave out of the Cycles render every object that is not part of
        the design (``left_out``). Raises ``SceneError``."""
        bl_scene = self.bl_scene
        _camera, self.camera_news = lamp_camera.ensure_lamp_camera(bl_scene)
        view_link.pause_link(bl_scene)  # the render size set below is the comparison's, not the user's
        self._paused = True
        parts = freeform_properties.role_objects(bl_scene)
        if self.build and needs_build(bl_scene) and not parts:  # with parts, the lamp is the parts
            self._build()
        self.scene = render_camera.scene_for_render(bl_scene, size=self.resolution)
        width, height = self.scene["image"]["width"], self.scene["image"]["height"]
        cycles = bl_scene.cycles
        settings = self._settings
        settings.set(bl_scene.view_settings, **STANDARD_VIEW)
        settings.set(bl_scene.render, resolution_x=width, resolution_y=height, resolution_percentage=100,
                     use_border=False)
        settings.set(cycles, samples=self.samples, **{k: max(v, getattr(cycles, k)) for k, v in MIN_BOUNCES.items()},
                     **cycles_settings(self.scene["image"]["samples"]))
        if self.scene["light_model"] == "photometric":  # Cycles in W shown at the tracer's EV100
            self.ev100 = photometric_display.scene_ev100(self.scene)
            settings.set(cycles, film_exposure=photometric_cycles.film_exposure(self.ev100))
        image_settings = bl_scene.render.image_settings
        settings.set(image_settings, **exr_output_values(image_settings))
        for ob in objects_outside_design(bl_scene):
            settings.set(ob, hide_render=True)
            self.left_out.append(ob.name)
        if parts:
            # The tracer traces the free-form parts with the parametric lamps still in use, built at
            # the current design (freeform.render, freeform.parametric): so does Cycles, with the
            # parts' role materials brought up to date and every other built object left out.
            freeform_materials.sync(bl_scene)
            traced = {ob.name for ob in freeform_parametric.built_parts(bl_scene, None)}
            for ob in bl_scene.objects:
                if ob.get(design_root.PART_KEY) not in (None, design_root.ROOT_PART) and ob.type == "MESH" \
                        and not ob.hide_render and not freeform_properties.has_role(ob) and ob.name not in traced:
                    settings.set(ob, hide_render=True)
        self._folder = tempfile.mkdtemp(prefix="lamp-compare-")

    def _build(self) -> None:
        # Seen through the scene camera: a design camera that is not used cannot block the build.
        design_builder.build_lamp(self.bl_scene, render_camera.scene_for_render(self.bl_scene, size=self.resolution))

    def start(self, stage: Stage, *, invoke: bool = False) -> None:
        """Render ``stage`` into its Render Result slot: a blocking render, or (``invoke``) Blender's
        render job, which returns at once. Raises ``CompareError``."""
        if self.images:
            self._check_unchanged()
        self._settings.set(self.bl_scene.render, engine=stage.engine)
        result = bpy.data.images.get(RENDER_RESULT)
        if result is not None:
            result.render_slots.active_index = stage.slot
        self.stage, self.ended = stage, None
        self._started_at = time.perf_counter()
        with bpy.context.temp_override(scene=self.bl_scene):
            outcome = bpy.ops.render.render("INVOKE_DEFAULT" if invoke else "EXEC_DEFAULT")
        if "CANCELLED" in outcome:
            raise CompareError(f"The {stage.label} render did not start (is another render running?)")
        if not invoke:
            self.report_end("complete")  # a blocking render has ended when it returns (a cancel stays)

    def advance(self) -> bool:
        """The modal path's step, on its timer: while the stage's render job runs, nothing; once it
        has ended, read its slot back and start the next stage as a render job. True when every
        stage is done (``compose`` next). Raises ``CompareCancelled``, ``CompareError``."""
        if self.ended is None or bpy.app.is_job_running("RENDER"):
            return False
        self.collect()
        following = STAGES.index(self.stage) + 1
        if following == len(STAGES):
            return True
        self.start(STAGES[following], invoke=True)
        return False

    def collect(self) -> None:
        """Read the ended stage's slot back. Raises ``CompareCancelled`` if it was cancelled."""
        stage = self.stage
        if self.ended == "cancel":
            raise CompareCancelled(f"{stage.label} render cancelled")
        self.seconds[stage.name] = self._ended_at - self._started_at
        result = bpy.data.images[RENDER_RESULT]
        result.render_slots.active_index = stage.slot
        path = os.path.join(self._folder, f"{stage.name}.exr")
        result.save_render(path, scene=self.bl_scene)
        self.images[stage.name] = image_view.read_exr(path)

    def _check_unchanged(self) -> None:
        """The scene must still be the one the first render was made of: the interface is live
        during a modal comparison, and the design, camera or render size may have been edited."""
        try:
            now = render_camera.scene_for_render(self.bl_scene)
        except SceneError as e:
            raise CompareError(f"The scene changed during the {self.stage.label} render: {e}") from None
        if now != self.scene:
            raise CompareError(f"The design, the camera or the render size changed during the {self.stage.label} "
                               "render; compare again")

    def compose(self) -> dict:
        """The comparison's figures: ``scene`` (what the tracer rendered), ``tracer``/``cycles``/
        ``side_by_side`` (H, W, 3 float32 top row first, linear), ``labels`` (of the two halves),
        ``exposure`` (one automatic exposure for both halves), ``seconds`` ({"tracer", "cycles"}),
        ``samples``, ``size`` and ``differences``. ``show_comparison`` makes the image of it."""
        tracer, cycles = self.images[TRACER.name], self.images[CYCLES.name]
        seconds = dict(self.seconds)
        names = ((f"Lamp Tracer  {seconds['tracer']:.2f} s", "Lamp Tracer", "Tracer"),
                 (f"Cycles  {self.samples} spp  {seconds['cycles']:.1f} s", f"Cycles  {seconds['cycles']:.1f} s",
                  "Cycles"))
        comparison = {
            "scene": self.scene,
            "tracer": tracer,
            "cycles": cycles,
            "labels": names,
            # one exposure for both halves (photometric: both at the design's EV100 already)
            "exposure": 0.0 if self.ev100 is not None else display.auto_exposure([tracer, cycles]),
            "side_by_side": None,  # below, with the difference panel
            "seconds": seconds,
            "samples": self.samples,
            "size": (tracer.shape[1], tracer.shape[0]),
            "differences": differences(tracer, cycles),
            "lens_differences": lens_differences(tracer, cycles, lens_pixels(self.scene, tracer.shape[:2])),
            "by_design": by_design(self.scene),
            "left_out": list(self.left_out),
            "camera_news": self.camera_news,
        }
        comparison["side_by_side"] = side_by_side(tracer, cycles, *names, third=difference_shown(comparison, None),
                                                  third_labels=difference_labels(comparison["lens_differences"]))
        return comparison

    def close(self) -> None:
        """Put back every setting the comparison changed, stop listening to the render handlers
        and remove the temporary files. Every exit path calls it; calling it again does nothing."""
        scene_exists = any(s.as_pointer() == self.scene_pointer for s in bpy.data.scenes)
        if scene_exists:
            self.not_restored += self._settings.restore()
        else:  # Blender ends the operator while loading another file: the scene is gone with its settings
            self._settings = SceneSettings()
        if self._paused:
            self._paused = False
            if scene_exists:
                view_link.resume_link(self.bl_scene)
        if running() is self:
            unwatch()
        if self._folder is not None:
            shutil.rmtree(self._folder, ignore_errors=True)
            self._folder = None


def lens_pixels(scene: dict, shape: tuple[int, int]) -> np.ndarray:
    """(H, W) bool: the pixels that see only lenses, found by the tracer's geometry, lit or not
    (``raytrace.engine.lens_pixels``: the eye ray through the centre meets a lens's outer face first).
    With more than one sample per pixel the samples spread over the pixel filter's support
    (``raytrace.pixel_filter``), so a pixel counts only where every pixel within that reach is a lens
    pixel too: a rim pixel that also sees the body or the lens's rim (a constant colour in the paper, diffuse in
    Cycles) is left out. The whole image when the design has free-form parts (their lenses are meshes the
    tracer finds only while it traces)."""
    from ...core_tracer.raytrace import pixel_filter
    from ...core_tracer.raytrace.engine import lens_pixels as lamp_seen

    if "freeform" in scene:
        return np.ones(shape, bool)
    lens = lamp_seen(scene, shape[1], shape[0]) >= 0
    if scene["image"].get("samples", 1) <= 1:
        return lens
    reach = int(np.ceil(pixel_filter.filter_support(pixel_filter.DEFAULT_FILTER)))
    padded = np.pad(lens, reach, constant_values=False)
    height, width = shape
    for dy in range(-reach, reach + 1):
        for dx in range(-reach, reach + 1):
            lens &= padded[reach + dy:reach + dy + height, reach + dx:reach + dx + width]
    return lens


def by_design(scene: dict) -> str:
    """One sentence: what differs between the tracer and Cycles by design on the lens (docs/model.md §8.17)."""
    if scene.get("light_model") == "photometric":
        return ("By design: a legal red (or amber) lies outside Rec.709, so Cycles' RGB cannot hold the "
                "filtered light's colour and clips it into the gamut at its own luminance; the rest is physics "
                "both model alike.")
    return ("By design: nothing on the lens or the body (Cycles builds eq. 3, the phantom light and eq. 1's "
            "highlights as the paper states them); Cycles' socket and lens rim are diffuse where the paper's are "
            "constant colours, and its bulb also lights the lamp's other parts.")


def compare_design(bl_scene, *, samples: int = DEFAULT_SAMPLES, resolution: tuple[int, int] | None = None,
                   build: bool = True) -> dict:
    """Render the scene's design with the tracer and with Cycles from the scene camera, blocking.

    Builds (or updates) the lamp objects first unless ``build`` is False, creates the scene
    camera from the design when there is none, renders both into render slots, makes the
    labelled "Lamp Compare" image and returns ``CompareRun.compose``'s dict, with
    ``not_restored``: the settings it could not put back (normally none). Raises ``SceneError``,
    ``CompareError``, ``CompareCancelled`` and the ``RuntimeError`` of ``bpy.ops.render.render``
    (an engine's error)."""
    with CompareRun(bl_scene, samples=samples, resolution=resolution, build=build) as run:
        run.prepare()
        for stage in STAGES:
            run.start(stage)
            run.collect()
        comparison = run.compose()
    show_comparison(bl_scene, comparison)
    return {**comparison, "not_restored": run.not_restored}


def show_comparison(bl_scene, comparison: dict) -> None:
    """The "Lamp Compare" image: both halves at the comparison's one exposure, through the scene's
    view transform. Made once the scene's own colour settings are back (after ``close``)."""
    exposure = comparison["exposure"]
    # The difference map's colours as the scene's view transform shows them (convert.sheet.difference_shown).
    shown = shown_side_by_side({**comparison, "linear_view": image_view.scene_view(bl_scene)}, None, exposure)
    image_view.show_linear(COMPARE_IMAGE, shown, exposure, bl_scene)


def write_comparison(path: str, comparison: dict, *, view: display.ViewTransform | None = None,
                     exposure: float | str | None = "auto") -> float:
    """Write the side-by-side image as .exr (linear) or .png (both halves through ``view``, default
    ``display.view_transform()``, at one ``exposure``: "auto" measures both halves together) with the
    scene in its header. Returns the exposure applied (0 for an .exr)."""
    from ...core_tracer.images import imageio

    if imageio.image_format(path) == "exr":
        imageio.write_image(path, comparison["side_by_side"], comparison["scene"])
        return 0.0
    view = view or display.view_transform()
    ev = display.resolve_exposure(exposure, [comparison["tracer"], comparison["cycles"]])
    imageio.write_display(path, shown_side_by_side(comparison, view, ev), comparison["scene"], view=view.view,
                          exposure=ev)
    return ev

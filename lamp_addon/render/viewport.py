"""The Lamp Tracer in the 3D Viewport's *Rendered* shading: the design seen from the viewport.

One ``ViewportSession`` per viewport engine instance. On every depsgraph update (``update``) it
reads the design from the scene's properties; on every redraw (``sync``) it makes the tracer's
camera from the region's own matrices (``convert.viewport``) in the design's model space, and
restarts the progressive preview (``render.preview``: coarse, full resolution, then more samples
per pixel) when the design, the view or the region changed. The preview renders on a worker
thread; a timer on the main thread asks for a redraw when a stage finishes, and ``draw_frame`` draws the newest image.

The image is drawn as a float texture of scene-linear values inside the engine's
``bind_display_space_shader``, as Blender's API asks of viewport engines; Blender then applies the
scene's colour management (view transform, look, exposure, gamma) to the viewport, as for Cycles
or EEVEE.
"""

from __future__ import annotations

import weakref

import bpy
import numpy as np

from ...core_tracer.images import display
from ...core_tracer.scene.reading import SceneError
from ..convert import viewport
from ..design import camera as camera_module
from ..design import curves as design_curves
from ..design import properties as design_properties
from ..design import root as design_root
from ..design import validity as design_validity
from ..freeform import geometry as freeform_geometry
from ..freeform import render as freeform_render
from . import photometric_display
from .preview import ProgressivePreview

POLL_SECONDS = 0.05  # how often the main thread looks for a finished stage

# The design's camera and image sections are replaced by the viewport's; these valid stand-ins
# let the rest of the design be checked without them.
_STAND_IN_CAMERA = {"type": "perspective", "position": [0.0, -1000.0, 0.0], "target": [0.0, 0.0, 0.0],
                    "up": [0.0, 0.0, 1.0], "fov_deg": 16.0, "width": 250.0, "sensor_fit": "auto",
                    "shift": [0.0, 0.0]}
_STAND_IN_IMAGE = {"width": 64, "height": 64}


def _rows(matrix) -> list[list[float]]:
    return [list(row) for row in matrix]


def invalid_design_text(bl_scene: bpy.types.Scene, error: SceneError) -> str:
    """Why the viewport shows nothing, in the panel's words: the design's state, the state of its
    objects, and the field to change with its allowed range (``design.validity``)."""
    if not bl_scene.lamp_design.lamps:
        return "no lamp yet: Add Lamp (Lamp tab, Lamps) or apply a preset"
    built = "objects as last built" if design_root.find_root(bl_scene) is not None else "not built"
    return f"design not valid ({built}); {design_validity.message(bl_scene, error)}"


class ViewportSession:
    """What one viewport engine keeps between redraws: the design, the preview, the texture."""

    def __init__(self, engine: bpy.types.RenderEngine | None, *, in_background: bool = True):
        self._engine = weakref.ref(engine) if engine is not None else (lambda: None)
        self.in_background = in_background  # False: the caller steps the preview itself (tests)
        self.preview = ProgressivePreview()
        self.design: dict | None = None
        self.error: str | None = None  # why the design cannot be rendered
        self.view_error: str | None = None  # why this view cannot be (a root scaled unevenly)
        self.display_error: str | None = None  # why the image cannot be shown (the working space)
        self.scene: dict | None = None  # the scene of the current preview job
        self.world_from_model = viewport.model_matrix()  # model mm -> world: the design root's matrix
        self.freeform = None  # freeform.render.Prepared when the view shows parts with roles
        self._freeform_generation = None  # the geometry generation of the current preview job
        self._texture = None
        self._texture_frame = None
        self._auto_ev100: tuple[int | None, float] = (None, 0.0)  # (preview generation, its EV100)
        self._poll = self._make_poll()

    # -- main thread: Blender's callbacks ------------------------------------------------------

    def update(self, bl_scene: bpy.types.Scene, depsgraph: bpy.types.Depsgraph | None = None) -> None:
        """Read the design (after any depsgraph update: an edited property, a moved root), with the
        free-form parts ``depsgraph`` shows."""
        self.preview.threads = bl_scene.render.threads  # Blender's thread count, as for F12
        # Read here, not at every redraw: finding the root walks the scene's objects.
        self.world_from_model = viewport.model_matrix(_rows(design_root.world_from_design(bl_scene)))
        try:
            # the design's exposure stays (photometric: one EV100 for the view, ``_shown``)
            self.design = design_curves.with_curves(bl_scene, design_properties.design_to_scene(
                bl_scene, camera={**_STAND_IN_CAMERA, **camera_module.design_exposure(bl_scene)},
                image=_STAND_IN_IMAGE))
            self.error = None
        except SceneError as e:
            self.design, self.error = None, invalid_design_text(bl_scene, e)
        self.freeform = None
        if depsgraph is not None and self.design is not None:
            freeform_geometry.note_updates(bl_scene, depsgraph)
            try:
                self.freeform = freeform_render.prepare(bl_scene, depsgraph, self.design)
            except SceneError as e:
                self.design, self.error = None, str(e)
                return
            self.design = self.freeform.scene

    def _renderer(self):
        """What renders the preview: the free-form tracer over the kept geometry, or None (the
        parametric tracer)."""
        prepared = self.freeform
        if prepared is None or prepared.geometry is None:
            return None

        def render(scene, width, height, **options):
            return freeform_render.render_passes(freeform_render.Prepared(scene, prepared.geometry), width,
                                                 height, **options)

        return render

    def sync(self, bl_scene: bpy.types.Scene, width: int, height: int, window_matrix, view_matrix) -> None:
        """The view of a region of ``width`` x ``height`` with these matrices: restart the preview
        if it is not what the current job renders."""
        if self.design is None:
            if self.error is None:
                self.update(bl_scene)
            if self.design is None:
                self.preview.cancel()
                return
        try:
            camera = viewport.camera_from_view(width, height, _rows(window_matrix), _rows(view_matrix),
                                               self.world_from_model)
        except ValueError as e:
            self.view_error = str(e)
            self.preview.cancel()
            return
        self.view_error = None
        scene = {**self.design, "camera": camera, "image": {"width": int(width), "height": int(height)}}
        geometry = self.freeform.geometry if self.freeform is not None else None
        generation = geometry.generation if geometry is not None else None  # new meshes: a new preview
        if scene == self.scene and generation == self._freeform_generation:
            return
        self.scene = scene
        self._freeform_generation = generation
        self.preview.restart(scene, int(width), int(height), self._renderer())
        if self.in_background:
            self.preview.start()
            if not bpy.app.timers.is_registered(self._poll):
                bpy.app.timers.register(self._poll, first_interval=POLL_SECONDS)

    def status(self) -> str:
        """One line for the viewport's text overlay."""
        error = self.error or self.view_error or self.display_error or self.preview.error
        if error is not None:
            return f"Lamp Tracer: {error}"
        frame = self.preview.frame()
        if frame is None or frame.generation != self.preview.generation:
            return "Lamp Tracer: rendering"
        if frame.divisor == 1 and frame.samples > 1:
            return f"Lamp Tracer: full resolution, {frame.samples} samples per pixel"
        if frame.divisor == 1:
            return "Lamp Tracer: full resolution" + (", refining" if self.preview.busy() else "")
        return f"Lamp Tracer: 1/{frame.divisor} resolution, refining"

    def draw_frame(self, engine: bpy.types.RenderEngine, bl_scene: bpy.types.Scene, width: int, height: int) -> None:
        """Draw the newest frame over the region (stretched from a coarse stage's size)."""
        frame = self.preview.frame()
        if frame is None or self.design is None or self.view_error is not None:
            return
        exposure = (self.design.get("light_model"), self.design["camera"].get("exposure"),
                    self.design["camera"].get("ev100"))  # an exposure edit redraws without a new preview
        if self._texture_frame != (frame, exposure):
            shown = self._shown(frame)
            if shown is None:
                return
            self._texture = image_texture(shown)
            self._texture_frame = (frame, exposure)
        draw_texture(engine, bl_scene, self._texture, width, height)

    def _shown(self, frame) -> np.ndarray | None:
        """The frame's scene-linear image: the paper's RGB as it is; the photometric XYZ at the
        design's EV100 (with "auto", measured on the first stage of each preview and kept for its
        later stages, so that refining never re-exposes), in the working space. None, with the
        reason in ``display_error``, when the working space cannot show it."""
        if self.design is None or self.design.get("light_model", "paper") != "photometric":
            return frame.image
        if self.design["camera"]["exposure"] == "ev100":
            ev100 = self.design["camera"]["ev100"]
        else:
            if self._auto_ev100[0] != frame.generation:
                self._auto_ev100 = (frame.generation, display.exposure_for([frame.image], [self.design]).ev100)
            ev100 = self._auto_ev100[1]
        try:
            shown = photometric_display.Display(ev100).linear(frame.image)
        except SceneError as e:
            self.display_error = str(e)
            return None
        self.display_error = None
        return shown

    def free(self) -> None:
        self.preview.cancel()
        if bpy.app.timers.is_registered(self._poll):
            bpy.app.timers.unregister(self._poll)

    def _make_poll(self):
        engine_ref, preview = self._engine, self.preview

        def poll() -> float | None:
            engine = engine_ref()
            if engine is None:  # the viewport stopped rendering: nothing to redraw
                preview.cancel()
                return None
            busy = preview.busy()  # first: a worker found finished has published everything
            if preview.take_news():
                try:
                    engine.tag_redraw()
                except ReferenceError:
                    preview.cancel()
                    return None
            return POLL_SECONDS if busy else None

        return poll


# ---------------------------------------------------------------------------------------------
# Drawing (needs a GPU context: Blender's viewport, or an offscreen in the tests)


def image_texture(image: np.ndarray):
    """A half-float RGBA texture of a (height, width, 3) linear image given top row first (the
    GPU's rows run bottom-up); alpha 1: the tracer shades every pixel, background included."""
    import gpu

    height, width = image.shape[:2]
    rgba = np.ones((height, width, 4), np.float32)
    rgba[:, :, :3] = image[::-1]
    buffer = gpu.types.Buffer("FLOAT", rgba.size, rgba.ravel())
    return gpu.types.GPUTexture((width, height), format="RGBA16F", data=buffer)


def draw_texture(engine: bpy.types.RenderEngine, bl_scene: bpy.types.Scene, texture, width: int, height: int) -> None:
    """Draw ``texture`` over the ``width`` x ``height`` region, in pixel coordinates, through the
    engine's display-space shader (Blender's "Simple Render Engine" example)."""
    import gpu
    from gpu_extras.presets import draw_texture_2d

    gpu.state.blend_set("ALPHA_PREMULT")
    engine.bind_display_space_shader(bl_scene)
    draw_texture_2d(texture, (0, 0), width, height)
    engine.unbind_display_space_shader()
    gpu.state.blend_set("NONE")

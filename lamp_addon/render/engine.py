"""The "Lamp Tracer" render engine: the paper's renderer behind F12.

As a ``RenderEngine`` the tracer gets everything Blender gives any engine: F12, render slots,
Image > Save, ``bpy.ops.render.render(write_still=True)`` headless, the output and colour
management panels. The scene it renders is the design from the Lamp panel seen through the
scene camera at the render resolution (``design.camera.scene_for_render``), with the free-form
parts the depsgraph shows (``freeform.render``).
"""

from __future__ import annotations

import bpy
import numpy as np

from ...core_tracer.budget import check_rays
from ...core_tracer.raytrace import band_pool
from ...core_tracer.raytrace.engine import PASS_NAMES
from ...core_tracer.scene.reading import SceneError
from .. import reports
from ..design import camera
from ..design import validity as design_validity
from ..design.setup import ENGINE_ID
from ..freeform import render as freeform_render
from ..freeform import status as freeform_status
from . import photometric_display
from . import viewport as render_viewport

# Blender's name of each contribution pass, in the tracer's order: "Lamp Lens Surface", ...
PASS_LABELS = {name: "Lamp " + name.replace("_", " ").title() for name in PASS_NAMES}
PASSES_PROPERTY = "lamp_contribution_passes"  # the per-view-layer toggle, on bpy.types.ViewLayer

# Blender's own panels that apply to this engine: output and format, colour management (the
# tracer's linear RGB is shown through the view transform like any render) and the camera.
_PANELS = (
    "RENDER_PT_format", "RENDER_PT_frame_range", "RENDER_PT_time_stretching", "RENDER_PT_output",
    "RENDER_PT_output_views", "RENDER_PT_output_color_management", "RENDER_PT_output_pixel_density",
    "RENDER_PT_encoding", "RENDER_PT_encoding_video", "RENDER_PT_encoding_audio",
    "RENDER_PT_post_processing", "RENDER_PT_stamp", "RENDER_PT_stamp_note", "RENDER_PT_stamp_burn",
    "RENDER_PT_color_management", "RENDER_PT_color_management_curves", "RENDER_PT_color_management_advanced",
    "RENDER_PT_color_management_white_balance", "RENDER_PT_color_management_working_space",
    "DATA_PT_context_camera", "DATA_PT_lens", "DATA_PT_camera", "DATA_PT_camera_display",
    "DATA_PT_camera_display_composition_guides", "DATA_PT_camera_safe_areas",
    "DATA_PT_camera_safe_areas_center_cut", "DATA_PT_camera_background_image", "DATA_PT_camera_animation",
    "DATA_PT_custom_props_camera",
    # View Layer properties: the layer list, Use for Rendering, and Passes (our toggle's parent)
    "VIEWLAYER_PT_context_layer", "VIEWLAYER_PT_layer", "VIEWLAYER_PT_layer_passes",
)

BAND_ROWS = 16  # rows per result update when the tracer reports rows in larger blocks


def body_coverage(scene: dict, row_start: int, row_stop: int) -> np.ndarray:
    """The fraction of a pixel's eye rays that hit the body box (the lamp's silhouette), decided
    as the tracer decides it: 1 or 0 at one sample, the mean over the same sample rays as the
    tracer's with more.

    Shape (row_stop - row_start, width), rows top-based like the tracer's. The lenses lie in
    the body's front face, so the box is the whole lamp seen from outside."""
    from ...core_tracer.raytrace import pixel_filter
    from ...core_tracer.raytrace.camera import eye_rays, make_camera
    from ...core_tracer.raytrace.engine.sampling import TILE_RAYS
    from ...core_tracer.raytrace.parts.body_box import body_box, hit_box

    width, height = scene["image"]["width"], scene["image"]["height"]
    samples = scene["image"].get("samples", 1)
    cam = make_camera(scene["camera"], width, height)
    box = body_box(scene["body"])
    pixels = np.arange(row_start * width, row_stop * width)
    if samples == 1:
        t_near, t_far, _ = hit_box(*eye_rays(cam, pixels), *box)
        hit = (t_near <= t_far) & (t_near > 0)
        return hit.reshape(row_stop - row_start, width).astype(np.float32)
    hits = np.zeros(len(pixels))
    per_group = max(1, TILE_RAYS // len(pixels))  # bounded memory, as the tracer's bands
    for s0 in range(0, samples, per_group):
        count = min(samples, s0 + per_group) - s0
        ray_pixels = np.repeat(pixels, count)
        offsets = pixel_filter.sample_offsets(pixel_filter.DEFAULT_FILTER, ray_pixels,
                                              np.tile(np.arange(s0, s0 + count), len(pixels)), samples)
        t_near, t_far, _ = hit_box(*eye_rays(cam, ray_pixels, offsets), *box)
        hits += ((t_near <= t_far) & (t_near > 0)).reshape(len(pixels), count).sum(axis=1)
    return (hits / samples).reshape(row_stop - row_start, width).astype(np.float32)


class LampTracerEngine(bpy.types.RenderEngine):
    bl_idname = ENGINE_ID
    bl_label = "Lamp Tracer"
    bl_use_preview = False
    bl_use_eevee_viewport = True  # Material Preview shading uses EEVEE on the Cycles materials

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._viewport: render_viewport.ViewportSession | None = None  # Rendered shading only

    def __del__(self):
        viewport = getattr(self, "_viewport", None)
        if viewport is not None:  # the viewport left Rendered shading: stop its preview
            viewport.free()

    # Rendered shading in the 3D Viewport: the design from the viewport's own view, refined in
    # stages on a worker thread (render.viewport).

    def view_update(self, context, depsgraph):
        if self._viewport is None:
            self._viewport = render_viewport.ViewportSession(self)
        self._viewport.update(depsgraph.scene, depsgraph)

    def view_draw(self, context, depsgraph):
        if self._viewport is None:
            self._viewport = render_viewport.ViewportSession(self)
        region, view = context.region, context.region_data
        session = self._viewport
        session.sync(depsgraph.scene, region.width, region.height, view.window_matrix, view.view_matrix)
        self.update_stats("", session.status())
        session.draw_frame(self, depsgraph.scene, region.width, region.height)

    def update_render_passes(self, scene=None, renderlayer=None):
        """The passes a view layer will have: what the compositor's Render Layers node offers."""
        self.register_pass(scene, renderlayer, "Combined", 4, "RGBA", "COLOR")
        if contribution_passes_enabled(renderlayer):
            for label in PASS_LABELS.values():
                self.register_pass(scene, renderlayer, label, 3, "RGB", "COLOR")

    def render(self, depsgraph):
        from ... import core_tracer
        from ...core_tracer.images import glare

        width, height = self.resolution_x, self.resolution_y
        self._region = render_region(depsgraph.scene.render, width, height)
        self._layer = depsgraph.view_layer.name  # the engine renders each view layer in turn
        with_passes = contribution_passes_enabled(depsgraph.view_layer)
        if with_passes:
            for label in PASS_LABELS.values():  # before the first begin_result, which copies them
                self.add_pass(label, 3, "RGB", layer=self._layer)
        try:
            scene = camera.scene_for_render(depsgraph.scene, camera_object=self.camera_override,
                                            size=(width, height))
            check_rays(width, height, scene["image"]["samples"])  # as the CLI: not an hour-long F12
            prepared = freeform_render.prepare(depsgraph.scene, depsgraph, scene)
        except SceneError as e:
            black = np.zeros((height, width, 3), np.float32)
            self._fill(black, 0, np.ones((height, width), np.float32),
                       dict.fromkeys(PASS_LABELS.values(), black) if with_passes else {})
            reports.say(self, "ERROR", f"Lamp Tracer: {design_validity.message(depsgraph.scene, e)}")
            return

        if prepared.note is not None:
            reports.say(self, "WARNING", f"Lamp Tracer: {prepared.note}")
        if prepared.geometry is not None:
            self._render_freeform(depsgraph.scene, prepared, width, height, with_passes)
            return

        transparent = depsgraph.scene.render.film_transparent
        samples = scene["image"]["samples"]
        background = np.asarray(scene["background"], np.float32)
        # Surroundings vary with the direction: with a transparent film the tracer leaves out what the
        # missing rays see (they still light the lamp and show in the lens), so nothing is taken away.
        surroundings = scene["environment"]["world"] != "none"
        try:  # photometric: XYZ in cd/m² to the working space at one EV100 (render.photometric_display)
            shown_as = photometric_display.for_scene(scene)
        except SceneError as e:
            self.report({"ERROR"}, f"Lamp Tracer: {e}")
            return
        if surroundings or shown_as is not None:  # the photometric background is black
            background = np.zeros(3, np.float32)

        def write_rows(row_start: int, row_stop: int, rows: np.ndarray,
                       passes: dict[str, np.ndarray] | None = None, *, linear: bool = False) -> None:
            """Rows ``row_start:row_stop`` of the image (and of each pass) into the result, in bands;
            photometric rows are XYZ unless ``linear`` (already the working space's)."""
            if shown_as is not None and not linear:
                rows = shown_as.linear(rows)
                passes = {name: shown_as.linear(values) for name, values in (passes or {}).items()}
            for start in range(row_start, row_stop, BAND_ROWS):
                stop = min(start + BAND_ROWS, row_stop)
                band = slice(start - row_start, stop - row_start)
                if transparent and samples > 1:
                    # The rays that miss the body add exactly the background each, so their share,
                    # (1 - coverage) x background, leaves the image and the background pass.
                    alpha = body_coverage(scene, start, stop)
                    missed = (1.0 - alpha)[:, :, None] * background
                    self._fill(rows[band] - missed, start, alpha,
                               {PASS_LABELS[name]: values[band] - missed if name == "background" else values[band]
                                for name, values in (passes or {}).items()})
                    continue
                if transparent:  # premultiplied; the passes too, so that they still sum to Combined
                    alpha = body_coverage(scene, start, stop)
                    weight = alpha[:, :, None]
                else:
                    alpha, weight = np.ones((stop - start, width), np.float32), None
                self._fill(_weighted(rows[band], weight), start, alpha,
                           {PASS_LABELS[name]: _weighted(values[band], weight)
                            for name, values in (passes or {}).items()})

        try:
            result = core_tracer.render_passes(scene, width, height, progress=self.update_progress,
                                               should_stop=self.test_break, on_band=write_rows,
                                               threads=depsgraph.scene.render.threads,  # Blender's count
                                               keep_passes=with_passes,
                                               world_seen=not (transparent and surroundings),
                                               pool=band_pool.shared())
        except core_tracer.RenderCancelled:
            return  # Esc: Blender keeps the bands finished so far, with their passes
        # Glare needs the whole image: the bands shown while rendering are replaced by the glared
        # image (Combined only; the contribution passes stay the tracer's, without glare).
        if shown_as is not None:  # glare's threshold is a display level: applied to the shown image
            image = shown_as.linear(result.image)
            shown = glare.apply(image, scene)
            if shown is not image:
                write_rows(0, height, shown, linear=True)
            self.update_stats("", f"Lamp Tracer: photometric, EV100 {shown_as.ev100:.2f}")
            return
        shown = glare.apply(result.image, scene)
        if shown is not result.image:
            write_rows(0, height, shown)

    def _render_freeform(self, bl_scene, prepared, width: int, height: int, with_passes: bool) -> None:
        """The free-form tracer's image (and passes), written once it is complete. A mesh it cannot
        use (an open lens, inward normals, ...) is reported, naming the object, on a black image."""
        from ... import core_tracer
        from ...core_tracer.images import glare

        black = np.zeros((height, width, 3), np.float32)
        opaque = np.ones((height, width), np.float32)
        try:
            result = freeform_render.render_passes(prepared, width, height, progress=self.update_progress,
                                                   should_stop=self.test_break,
                                                   threads=bl_scene.render.threads)  # Blender's count
        except core_tracer.RenderCancelled:
            return
        except SceneError as e:
            freeform_status.note_mesh_problem(bl_scene, str(e))
            self._fill(black, 0, opaque, dict.fromkeys(PASS_LABELS.values(), black) if with_passes else {})
            reports.say(self, "ERROR", f"Lamp Tracer: {e}")
            return
        freeform_status.note_mesh_problem(bl_scene, None)
        passes = {}
        if with_passes:
            passes = {PASS_LABELS[name]: np.asarray(result.passes[name], np.float32) for name in PASS_NAMES
                      if name in (result.passes or {})}
        image = result.image
        # photometric: XYZ in cd/m² shown as the parametric tracer's are (render.photometric_display),
        # glare's threshold applied to the shown image
        shown_as = photometric_display.for_image(prepared.scene, image)
        if shown_as is not None:
            image = shown_as.linear(image)
            passes = {label: shown_as.linear(values) for label, values in passes.items()}
            self.update_stats("", f"Lamp Tracer: photometric, EV100 {shown_as.ev100:.2f}")
        self._fill(np.asarray(glare.apply(image, prepared.scene), np.float32), 0, opaque, passes)

    def _fill(self, rows: np.ndarray, row_start: int, alpha: np.ndarray,
              passes: dict[str, np.ndarray] | None = None) -> None:
        """Write ``rows`` (top-based, top row first) into the result's Combined pass and each of
        ``passes`` (Blender pass name -> rows of the same shape) into that pass. Blender's rows run
        bottom-up, and with a render region the result covers only the region, addressed from its
        corner."""
        x0, y0, x1, y1 = self._region
        n, width = rows.shape[:2]
        bottom = self.resolution_y - row_start - n  # of the band, counted from the frame's bottom
        lo, hi = max(bottom, y0), min(bottom + n, y1)
        if lo >= hi:
            return

        def kept(values: np.ndarray) -> np.ndarray:
            return np.ascontiguousarray(values[::-1][lo - bottom:hi - bottom, x0:x1], np.float32).ravel()

        rgba = np.empty((n, width, 4), np.float32)
        rgba[:, :, :3] = rows
        rgba[:, :, 3] = alpha
        result = self.begin_result(0, lo - y0, x1 - x0, hi - lo, layer=self._layer)
        layer = result.layers[0]
        layer.passes["Combined"].rect.foreach_set(kept(rgba))
        for label, values in (passes or {}).items():
            layer.passes[label].rect.foreach_set(kept(values))
        self.end_result(result)


def _weighted(values: np.ndarray, weight: np.ndarray | None) -> np.ndarray:
    return values if weight is None else values * weight


def contribution_passes_enabled(view_layer: bpy.types.ViewLayer) -> bool:
    """The view layer's *Contribution Passes* toggle (False while the add-on is not registered)."""
    return bool(getattr(view_layer, PASSES_PROPERTY, False))


def _passes_changed(view_layer: bpy.types.ViewLayer, _context) -> None:
    view_layer.update_render_passes()  # the Render Layers node gains or loses its sockets


class LAMP_PT_view_layer_passes(bpy.types.Panel):
    """View Layer properties › Passes › Lamp Tracer, shown for this engine only."""

    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "view_layer"
    bl_label = "Lamp Tracer"
    bl_parent_id = "VIEWLAYER_PT_layer_passes"
    COMPAT_ENGINES = {ENGINE_ID}

    @classmethod
    def poll(cls, context):
        return context.engine in cls.COMPAT_ENGINES

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        layout.column().prop(context.view_layer, PASSES_PROPERTY)


def render_region(render, width: int, height: int) -> tuple[int, int, int, int]:
    """The pixels Blender keeps, (x0, y0, x1, y1) from the bottom-left corner: the whole frame, or
    the render region (border) truncated to whole pixels as Blender does."""
    if not render.use_border:
        return 0, 0, width, height
    return (int(render.border_min_x * width), int(render.border_min_y * height),
            int(render.border_max_x * width), int(render.border_max_y * height))


classes = (LampTracerEngine, LAMP_PT_view_layer_passes)


def _panels():
    for name in _PANELS:
        panel = getattr(bpy.types, name, None)
        if panel is not None and hasattr(panel, "COMPAT_ENGINES"):
            yield panel


_register_classes, _unregister_classes = bpy.utils.register_classes_factory(classes)


def register() -> None:
    setattr(bpy.types.ViewLayer, PASSES_PROPERTY, bpy.props.BoolProperty(
        name="Contribution Passes",
        description="Also write the Lamp Tracer's contribution passes (lens surface, bulb, reflector "
                    "constant and scatter, socket, side wall, body, background), which sum to Combined",
        default=False, update=_passes_changed))
    for panel in _panels():
        panel.COMPAT_ENGINES.add(ENGINE_ID)
    _register_classes()


def unregister() -> None:
    _unregister_classes()
    band_pool.shutdown()  # its worker processes end with the engine; the next render starts new ones
    for panel in _panels():
        panel.COMPAT_ENGINES.discard(ENGINE_ID)
    delattr(bpy.types.ViewLayer, PASSES_PROPERTY)

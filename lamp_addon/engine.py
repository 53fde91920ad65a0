"""The "Lamp Tracer" render engine: the paper's renderer behind F12 (issue 3, item 6).

As a ``RenderEngine`` the tracer gets everything Blender gives any engine: F12, render slots,
Image > Save, ``bpy.ops.render.render(write_still=True)`` headless, the output and colour
management panels. The scene it renders is the design from the Lamp panel seen through the
scene camera at the render resolution (``camera.scene_for_render``).
"""

from __future__ import annotations

import bpy
import numpy as np

from ..core_tracer.scene import SceneError
from . import camera

ENGINE_ID = "LAMP_TRACER"

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
)

BAND_ROWS = 16  # rows per result update when the tracer reports rows in larger blocks


def body_coverage(scene: dict, row_start: int, row_stop: int) -> np.ndarray:
    """1 where the eye ray of a pixel hits the body box (the lamp's silhouette), else 0.

    Shape (row_stop - row_start, width), rows top-based like the tracer's. The lenses lie in
    the body's front face, so the box is the whole lamp seen from outside."""
    from ..core_tracer.camera import eye_rays, make_camera

    width, height = scene["image"]["width"], scene["image"]["height"]
    cam = make_camera(scene["camera"], width, height)
    pixels = np.arange(row_start * width, row_stop * width)
    origins, directions = eye_rays(cam, pixels)
    body = scene["body"]
    (cx, cz), (sx, sz) = body["center"], body["size"]
    lo = np.array([cx - sx / 2, 0.0, cz - sz / 2])
    hi = np.array([cx + sx / 2, body["depth"], cz + sz / 2])
    with np.errstate(divide="ignore", invalid="ignore"):
        t0 = (lo - origins) / directions
        t1 = (hi - origins) / directions
    near = np.nanmax(np.minimum(t0, t1), axis=1)
    far = np.nanmin(np.maximum(t0, t1), axis=1)
    hit = (near <= far) & (far > 0)
    return hit.reshape(row_stop - row_start, width).astype(np.float32)


class LampTracerEngine(bpy.types.RenderEngine):
    bl_idname = ENGINE_ID
    bl_label = "Lamp Tracer"
    bl_use_preview = False
    bl_use_eevee_viewport = True  # Material Preview shading uses EEVEE on the Cycles materials

    def render(self, depsgraph):
        from .. import core_tracer

        width, height = self.resolution_x, self.resolution_y
        self._region = render_region(depsgraph.scene.render, width, height)
        try:
            scene = camera.scene_for_render(depsgraph.scene, camera_object=self.camera_override,
                                            size=(width, height))
        except SceneError as e:
            self._fill(np.zeros((height, width, 3), np.float32), 0, np.ones((height, width), np.float32))
            self.report({"ERROR"}, f"Lamp Tracer: {e}")
            return

        transparent = depsgraph.scene.render.film_transparent

        def on_rows(row_start: int, row_stop: int, rows: np.ndarray) -> None:
            for start in range(row_start, row_stop, BAND_ROWS):
                stop = min(start + BAND_ROWS, row_stop)
                band = rows[start - row_start:stop - row_start]
                if transparent:
                    alpha = body_coverage(scene, start, stop)
                    band = band * alpha[:, :, None]
                else:
                    alpha = np.ones(band.shape[:2], np.float32)
                self._fill(band, start, alpha)

        try:
            core_tracer.render_passes(scene, width, height, progress=self.update_progress,
                                      should_stop=self.test_break, on_rows=on_rows,
                                      threads=depsgraph.scene.render.threads)  # Blender's thread count
        except core_tracer.RenderCancelled:
            return  # Esc: Blender keeps the rows finished so far

    def _fill(self, rows: np.ndarray, row_start: int, alpha: np.ndarray) -> None:
        """Write ``rows`` (top-based, top row first) into the result. Blender's rows run bottom-up,
        and with a render region the result covers only the region, addressed from its corner."""
        x0, y0, x1, y1 = self._region
        n, width = rows.shape[:2]
        bottom = self.resolution_y - row_start - n  # of the band, counted from the frame's bottom
        lo, hi = max(bottom, y0), min(bottom + n, y1)
        if lo >= hi:
            return
        rgba = np.empty((n, width, 4), np.float32)
        rgba[:, :, :3] = rows
        rgba[:, :, 3] = alpha
        rgba = rgba[::-1][lo - bottom:hi - bottom, x0:x1]
        result = self.begin_result(0, lo - y0, x1 - x0, hi - lo)
        result.layers[0].passes["Combined"].rect.foreach_set(np.ascontiguousarray(rgba).ravel())
        self.end_result(result)


def render_region(render, width: int, height: int) -> tuple[int, int, int, int]:
    """The pixels Blender keeps, (x0, y0, x1, y1) from the bottom-left corner: the whole frame, or
    the render region (border) truncated to whole pixels as Blender does."""
    if not render.use_border:
        return 0, 0, width, height
    return (int(render.border_min_x * width), int(render.border_min_y * height),
            int(render.border_max_x * width), int(render.border_max_y * height))


classes = (LampTracerEngine,)


def _panels():
    for name in _PANELS:
        panel = getattr(bpy.types, name, None)
        if panel is not None and hasattr(panel, "COMPAT_ENGINES"):
            yield panel


_register_classes, _unregister_classes = bpy.utils.register_classes_factory(classes)


def register() -> None:
    _register_classes()
    for panel in _panels():
        panel.COMPAT_ENGINES.add(ENGINE_ID)


def unregister() -> None:
    for panel in _panels():
        panel.COMPAT_ENGINES.discard(ENGINE_ID)
    _unregister_classes()

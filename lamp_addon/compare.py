"""Compare with Cycles: the same design, camera and resolution rendered by the paper's tracer and
by Cycles, side by side (issue 3, item 7).

Both renders go through ``bpy.ops.render.render`` into the "Render Result" image, Cycles into
render slot 1 and the tracer into slot 2 (slot indices 0 and 1), so J flips between them in the
Image Editor; their pixels are read back with ``save_render`` to OpenEXR (in background mode the
Render Result has no pixels). A third image, "Lamp Compare", holds the two halves with labels.
The scene is left on the Standard view transform, under which the tracer's linear RGB (the
paper's stimulus values) and Cycles' radiance are shown the same way.

Cycles settings. The tracer follows every specular branch to the end (cut-off 0.1 %); Cycles
follows one sampled path per sample, so the bounce limits must cover the longest specular chain
camera -> lens -> cuts -> reflector -> ... -> bulb: ``transmission_bounces`` >= 8,
``glossy_bounces`` >= 6, ``max_bounces`` >= 12; caustics stay on and glossy filtering and
clamping off, since the bulb is seen through the lens and in the mirror. Denoising and
adaptive sampling are off so that the result is the plain Monte Carlo estimate. The tracer
takes one ray through each pixel centre; Cycles integrates over its pixel filter. A box filter
of the smallest width (0.01 px) makes Cycles sample the same pixel centres, so edges alias the
same way in both halves and the per-pixel difference measures the models, not the filters.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
import time
from collections.abc import Sequence

import bpy
import numpy as np

from ..core_tracer.scene import SceneError
from . import bitmap_font, camera, image_view, panels, properties
from .engine import ENGINE_ID

RENDER_RESULT = "Render Result"
COMPARE_IMAGE = "Lamp Compare"
CYCLES_SLOT = 0
TRACER_SLOT = 1
DEFAULT_SAMPLES = 64

MIN_BOUNCES = {"max_bounces": 12, "transmission_bounces": 8, "glossy_bounces": 6}
CYCLES_SETTINGS = {
    "device": "CPU",
    "use_denoising": False,
    "use_adaptive_sampling": False,
    "caustics_reflective": True,
    "caustics_refractive": True,
    "blur_glossy": 0.0,
    "sample_clamp_direct": 0.0,
    "sample_clamp_indirect": 0.0,
    "pixel_filter_type": "BOX",
    "filter_width": 0.01,
    "seed": 0,
    "use_animated_seed": False,
}


# ---------------------------------------------------------------------------------------------
# Pure parts: the side-by-side image and the differences


def differences(tracer: np.ndarray, cycles: np.ndarray) -> dict:
    """Per-channel statistics of tracer - Cycles over the whole image (linear RGB)."""
    diff = tracer.astype(np.float64) - cycles.astype(np.float64)
    return {
        "tracer_mean": tracer.astype(np.float64).mean(axis=(0, 1)).tolist(),
        "cycles_mean": cycles.astype(np.float64).mean(axis=(0, 1)).tolist(),
        "mean_difference": diff.mean(axis=(0, 1)).tolist(),
        "mean_abs_difference": np.abs(diff).mean(axis=(0, 1)).tolist(),
        "rms_difference": np.sqrt((diff * diff).mean(axis=(0, 1))).tolist(),
    }


def label_height(image_height: int) -> int:
    """Height of the label strip: the 7-pixel font at an integer scale, with a margin."""
    return 7 * _label_scale(image_height) + 6


def _label_scale(image_height: int) -> int:
    return max(1, min(4, image_height // 160 + 1))


def side_by_side(left: np.ndarray, right: np.ndarray, left_labels: Sequence[str],
                 right_labels: Sequence[str]) -> np.ndarray:
    """One (H + strip, 2W + gap, 3) image: ``left`` and ``right`` next to each other below a
    strip holding their labels. Each label is the first of its alternatives (longest first) that
    fits above its half. Labels are drawn with OpenImageIO's ``render_text`` when it can (the
    PyPI OpenImageIO has FreeType and a font), else with the bitmap font."""
    height, width = left.shape[:2]
    gap = max(2, width // 128)
    strip = label_height(height)
    out = np.zeros((height + strip, 2 * width + gap, 3), np.float32)
    out[strip:, :width] = left
    out[strip:, width + gap:] = right
    out[:, width:width + gap] = 0.5
    halves = ((left_labels, 0), (right_labels, width + gap))
    scale = _label_scale(height)
    for alternatives, x in halves:
        # Each label is drawn into its own half of the strip, so a long one is clipped there.
        area = out[:strip, x:x + width]
        text = _oiio_text(alternatives, width, strip)
        if text is not None:
            np.maximum(area, text, out=area)
        else:
            label = _fitting(alternatives, width - 4 * scale, lambda t: bitmap_font.text_mask(t, scale).shape[1])
            bitmap_font.draw_text(area, label, 3 * scale, 3, color=(1.0, 1.0, 1.0), scale=scale)
    return out


def _fitting(alternatives: Sequence[str], room: int, measure) -> str:
    """The first label that fits in ``room`` pixels, else the shortest (clipped when drawn)."""
    return next((t for t in alternatives if measure(t) <= room), alternatives[-1])


def _oiio_text(alternatives: Sequence[str], width: int, height: int) -> np.ndarray | None:
    """A (height, width, 3) label drawn by OpenImageIO, or None when it cannot draw text."""
    try:
        import OpenImageIO as oiio
    except ImportError:
        return None
    buf = oiio.ImageBuf(oiio.ImageSpec(width, height, 3, oiio.FLOAT))
    size = height - 2
    label = _fitting(alternatives, width - 8, lambda t: oiio.ImageBufAlgo.text_size(t, size, "").width)
    if not oiio.ImageBufAlgo.render_text(buf, 4, height - 4, label, size, "", (1.0, 1.0, 1.0)):
        return None  # Blender's bundled OpenImageIO has no FreeType
    return np.asarray(buf.get_pixels(oiio.FLOAT), dtype=np.float32).reshape(height, width, 3)


# ---------------------------------------------------------------------------------------------
# Blender side


@contextlib.contextmanager
def _temporarily(owner, **values):
    """Set attributes of ``owner`` for the duration of the block, then put the old ones back."""
    old = {key: getattr(owner, key) for key in values}
    try:
        for key, value in values.items():
            setattr(owner, key, value)
        yield
    finally:
        for key, value in old.items():
            setattr(owner, key, value)


def use_standard_view(bl_scene) -> None:
    """Show renders as their linear values map to the display: Standard, no look, no exposure."""
    view = bl_scene.view_settings
    view.view_transform = "Standard"
    view.look = "None"
    view.exposure = 0.0
    view.gamma = 1.0
    view.use_curve_mapping = False


def _render_into_slot(bl_scene, slot: int, path: str) -> tuple[np.ndarray, float]:
    """Render the scene with its current engine into a render slot; returns (RGB, seconds)."""
    result = bpy.data.images.get(RENDER_RESULT)
    if result is not None:
        result.render_slots.active_index = slot
    start = time.perf_counter()
    with bpy.context.temp_override(scene=bl_scene):
        bpy.ops.render.render()
    seconds = time.perf_counter() - start
    result = bpy.data.images[RENDER_RESULT]
    result.render_slots.active_index = slot
    result.save_render(path, scene=bl_scene)
    return image_view.read_exr(path), seconds


def _exr_output(bl_scene):
    settings = bl_scene.render.image_settings
    values = {"file_format": "OPEN_EXR", "color_depth": "32", "exr_codec": "ZIP"}
    if hasattr(settings, "media_type"):  # Blender 5.0: the format list depends on the media type
        values = {"media_type": "IMAGE", **values}
    if hasattr(settings, "color_management"):
        values["color_management"] = "FOLLOW_SCENE"
    return _temporarily(settings, **values)


def compare_design(bl_scene, *, samples: int = DEFAULT_SAMPLES, resolution: tuple[int, int] | None = None,
                   build: bool = True) -> dict:
    """Render the scene's design with the tracer and with Cycles from the scene camera.

    Builds (or updates) the lamp objects first unless ``build`` is False, creates the scene
    camera from the design when there is none, renders both into render slots, and makes the
    labelled "Lamp Compare" image. Returns a dict: ``scene`` (what the tracer rendered),
    ``tracer``/``cycles``/``side_by_side`` (H, W, 3 float32 top row first), ``seconds``
    ({"tracer", "cycles"}), ``samples``, ``size`` and ``differences``. Raises ``SceneError``."""
    design = properties.design_to_scene(bl_scene)
    if build:
        from . import builder

        builder.build_lamp(bl_scene, design)
    camera.ensure_scene_camera(bl_scene, design)
    scene = camera.scene_for_render(bl_scene, size=resolution)
    width, height = scene["image"]["width"], scene["image"]["height"]
    use_standard_view(bl_scene)

    cycles = bl_scene.cycles
    bounces = {k: max(v, getattr(cycles, k)) for k, v in MIN_BOUNCES.items()}
    render = bl_scene.render
    with tempfile.TemporaryDirectory(prefix="lamp-compare-") as tmp, \
            _temporarily(render, resolution_x=width, resolution_y=height, resolution_percentage=100,
                         use_border=False, engine="CYCLES"), \
            _temporarily(cycles, samples=int(samples), **bounces, **CYCLES_SETTINGS), \
            _exr_output(bl_scene):
        cycles_rgb, cycles_seconds = _render_into_slot(bl_scene, CYCLES_SLOT, os.path.join(tmp, "cycles.exr"))
        render.engine = ENGINE_ID
        tracer_rgb, tracer_seconds = _render_into_slot(bl_scene, TRACER_SLOT, os.path.join(tmp, "tracer.exr"))

    combined = side_by_side(
        tracer_rgb, cycles_rgb,
        (f"Lamp Tracer  {tracer_seconds:.2f} s", "Lamp Tracer", "Tracer"),
        (f"Cycles  {samples} spp  {cycles_seconds:.1f} s", f"Cycles  {cycles_seconds:.1f} s", "Cycles"))
    image_view.image_from_array(COMPARE_IMAGE, combined)
    return {
        "scene": scene,
        "tracer": tracer_rgb,
        "cycles": cycles_rgb,
        "side_by_side": combined,
        "seconds": {"tracer": tracer_seconds, "cycles": cycles_seconds},
        "samples": int(samples),
        "size": (width, height),
        "differences": differences(tracer_rgb, cycles_rgb),
    }


def write_comparison(path: str, comparison: dict) -> None:
    """Write the side-by-side image as .exr (linear) or .png (sRGB) with the scene in its header."""
    from ..core_tracer import imageio

    imageio.write_image(path, comparison["side_by_side"], comparison["scene"])


class LAMP_OT_compare_cycles(bpy.types.Operator):
    """Render the design with the Lamp Tracer and with Cycles from the scene camera and show them
    side by side (render slots 1 and 2 of Render Result, flip with J, and the "Lamp Compare" image)"""

    bl_idname = "lamp.compare_cycles"
    bl_label = "Compare with Cycles"
    bl_options = {"REGISTER", "UNDO"}  # builds the lamp objects and sets the view transform

    samples: bpy.props.IntProperty(name="Cycles Samples", default=DEFAULT_SAMPLES, min=1, max=65536,
                                   description="Samples per pixel of the Cycles render")
    filepath: bpy.props.StringProperty(name="Save As", subtype="FILE_PATH", default="",
                                       description="Also write the side-by-side image here (.png sRGB or "
                                                   ".exr linear); empty: do not write")

    @classmethod
    def poll(cls, context):
        if context.scene is None or not hasattr(context.scene, "lamp_design"):
            cls.poll_message_set("No lamp design in this scene")
            return False
        if not hasattr(context.scene, "cycles"):
            cls.poll_message_set("Cycles is not enabled")
            return False
        return True

    def execute(self, context):
        from ..core_tracer import imageio

        path = bpy.path.abspath(self.filepath) if self.filepath else ""
        try:
            if path:
                imageio.image_format(path)  # refuse a bad file name before minutes of rendering
            comparison = compare_design(context.scene, samples=self.samples)
        except SceneError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        except RuntimeError as e:  # bpy.ops.render.render reports an engine's error this way
            self.report({"ERROR"}, str(e).strip())
            return {"CANCELLED"}
        image_view.show_image(context, bpy.data.images[COMPARE_IMAGE])
        if path:
            try:
                write_comparison(path, comparison)
            except (SceneError, OSError) as e:
                self.report({"ERROR"}, str(e))
                return {"CANCELLED"}
        seconds = comparison["seconds"]
        self.report({"INFO"}, f"Lamp Tracer {seconds['tracer']:.2f} s, Cycles {seconds['cycles']:.1f} s "
                              f"({comparison['samples']} samples)")
        return {"FINISHED"}


classes = (LAMP_OT_compare_cycles,)


def register() -> None:
    for cls in classes:
        bpy.utils.register_class(cls)
    panels.add_action("lamp.compare_cycles", "Compare with Cycles", "IMAGE_REFERENCE")


def unregister() -> None:
    panels.remove_action("lamp.compare_cycles")
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)

"""Images the add-on makes ("Lamp Tracer", "Lamp Compare", "Lamp Study"): pixels in, Image Editor out.

Blender's image rows run bottom-up, the tracer's (and OpenImageIO's) top-down. The colour space
is set before any pixel is written: changing it afterwards resets the pixels (BLENDER-NOTES).

Colour: the images hold linear values and are shown with Blender's own colour management, the
scene's view transform (AgX, Standard, False Color, ...) applied exactly as to a render
(``use_view_as_render``). The exposure belongs to the view: the "Lamp Tracer" image holds the
render as F12 makes it and is shown at the scene's exposure, as F12 is (``show_as_render``), so two
designs rendered in turn keep their difference in brightness. Sheets of several pictures (Lamp
Compare, Lamp Study) are shown under one exposure for all of them, measured over them all
(``core_tracer.images.display.auto_exposure``) whatever the scene's exposure is when they are made:
their pixels carry the difference (recorded in the image's ``lamp_exposure`` property), so the lit
lens's cut pattern reads and labels keep their grey. The scene's exposure (which *Exposure from
Design* sets for F12 renders and the viewport) still moves them afterwards, as any render.
"""

from __future__ import annotations

import bpy
import numpy as np

from ..core_tracer.images import display

EXPOSURE_PROPERTY = "lamp_exposure"  # stops already applied to an image's pictures
EV100_PROPERTY = "lamp_ev100"  # the camera EV100 its photometric pictures are shown at (display.shown)
NO_OPENIMAGEIO = "this Blender has no OpenImageIO Python module to write image files"


def scene_linear_colorspace() -> str:
    """The colour space of the tracer's linear RGB: the working space where Blender has one
    (5.0+), else Linear Rec.709 (Blender's scene-linear space before 5.0)."""
    items = bpy.types.ColorManagedInputColorspaceSettings.bl_rna.properties["name"].enum_items
    return "scene_linear" if "scene_linear" in items else "Linear Rec.709"


def rgba_rows(rgb: np.ndarray, alpha: np.ndarray | None = None) -> np.ndarray:
    """(H, W, 3) top-first RGB to a flat float32 RGBA buffer in Blender's bottom-up order."""
    height, width = rgb.shape[:2]
    rgba = np.ones((height, width, 4), np.float32)
    rgba[:, :, :3] = rgb
    if alpha is not None:
        rgba[:, :, 3] = alpha
    return np.ascontiguousarray(rgba[::-1]).ravel()


def prepare_image(name: str, width: int, height: int) -> bpy.types.Image:
    """A float image ``name`` of the given size in the scene-linear colour space, reusing the
    data-block (so editors showing it keep showing it) when it is a generated float image."""
    image = bpy.data.images.get(name)
    if image is not None and (image.source != "GENERATED" or not image.is_float):
        image.name = name + ".old"  # someone else's image of that name: leave it alone
        image = None
    if image is None:
        image = bpy.data.images.new(name, width, height, float_buffer=True, alpha=True)
    elif tuple(image.size) != (width, height):
        image.generated_width, image.generated_height = width, height
    space = scene_linear_colorspace()
    if image.colorspace_settings.name != space:
        image.colorspace_settings.name = space
    return image


def image_from_array(name: str, rgb: np.ndarray, alpha: np.ndarray | None = None) -> bpy.types.Image:
    """The image ``name`` holding ``rgb`` (H, W, 3 linear, top row first)."""
    height, width = rgb.shape[:2]
    image = prepare_image(name, width, height)
    image.pixels.foreach_set(rgba_rows(rgb, alpha))
    image.update()
    return image


def show_linear(name: str, rgb: np.ndarray, exposure: float, bl_scene) -> bpy.types.Image:
    """The image ``name`` showing ``rgb`` (H, W, 3, linear; its pictures already at ``exposure``
    stops, its labels as they are) through the scene's view transform, like a render, and as if the
    scene's exposure were 0."""
    scene_exposure = bl_scene.view_settings.exposure
    image = image_from_array(name, rgb * np.float32(2.0 ** -scene_exposure) if scene_exposure else rgb)
    image.use_view_as_render = True
    image[EXPOSURE_PROPERTY] = float(exposure - scene_exposure)
    return image


def stops_of(used: display.Exposure) -> float:
    """The stops ``display.shown`` applied to pictures on top of their light model's own scale: the
    paper mode's exposure, else the stops on top of the photometric EV100."""
    return used.paper_stops if used.paper_stops is not None else used.stops


def show_as_render(name: str, rgb: np.ndarray) -> bpy.types.Image:
    """The image ``name`` holding ``rgb`` (H, W, 3, linear) as F12's Render Result holds it: shown
    through the scene's view transform at the scene's exposure (nothing applied to its pixels)."""
    image = image_from_array(name, rgb)
    image.use_view_as_render = True
    image[EXPOSURE_PROPERTY] = 0.0
    return image


PREVIEW_SIDE = 96  # px of the longer side of the preview that measures a design's exposure


def design_exposure(scene: dict) -> float:
    """The automatic exposure of a design (a normalised scene), measured on a small preview render
    of the same view, for images shown while they are still being rendered."""
    from ..core_tracer import render

    if scene.get("light_model", "paper") == "photometric":
        return 0.0  # its EV100 is in the pixels already (render.photometric_display)
    width, height = scene["image"]["width"], scene["image"]["height"]
    scale = min(1.0, PREVIEW_SIDE / max(width, height))
    preview = render(scene, max(1, round(width * scale)), max(1, round(height * scale)))
    return display.auto_exposure(preview)


def image_exposure(image: bpy.types.Image) -> float:
    """The stops applied to an image's pictures (0 for an image without ``lamp_exposure``)."""
    value = image.get(EXPOSURE_PROPERTY, 0.0)
    return float(value) if isinstance(value, int | float) else 0.0


def scene_view(bl_scene) -> display.ViewTransform:
    """The scene's view transform, applied outside Blender's drawing (files): Blender's own
    configuration through OpenImageIO; Standard where the scene's view is not one of its sRGB views."""
    try:
        return display.view_transform(bl_scene.view_settings.view_transform)
    except ValueError:
        return display.view_transform(display.STANDARD)


def thumbnail_view() -> display.ViewTransform:
    """Thumbnails are shown as the shipped ones were made, whatever a scene's settings: the
    default view (AgX) of Blender's own configuration."""
    return display.view_transform(display.DEFAULT_VIEW)


def openimageio_available() -> bool:
    """Whether an OpenImageIO module can be imported (Blender 4.4+ bundles one, made importable by
    ``bpy.utils.expose_bundled_modules``). Without it the add-on writes no image files and draws
    labels with its bitmap font."""
    try:
        import OpenImageIO  # noqa: F401
    except ImportError:
        expose = getattr(bpy.utils, "expose_bundled_modules", None)
        if expose is None:
            return False
        expose()
        try:
            import OpenImageIO  # noqa: F401
        except ImportError:
            return False
    return True


def image_to_array(image: bpy.types.Image) -> np.ndarray:
    """An image's RGB as (H, W, 3) float32, top row first."""
    width, height = image.size
    flat = np.empty(width * height * 4, np.float32)
    image.pixels.foreach_get(flat)
    return flat.reshape(height, width, 4)[::-1, :, :3].copy()


def read_exr(path: str) -> np.ndarray:
    """Linear RGB (H, W, 3 top row first) of an OpenEXR file, through Blender's own reader (so it
    works in any Blender, with or without an OpenImageIO Python module)."""
    image = bpy.data.images.load(path, check_existing=False)
    try:
        return image_to_array(image)
    finally:
        bpy.data.images.remove(image)


def show_image(context, image: bpy.types.Image) -> bool:
    """Show ``image`` in an Image Editor of the current screen, splitting the largest area off
    into one when there is none. Background mode has no windows: returns False there."""
    if bpy.app.background or context.window is None or context.screen is None:
        return False
    screen = context.screen
    editor = next((a for a in screen.areas if a.type == "IMAGE_EDITOR"), None)
    if editor is None:
        editor = _split_off_editor(context, screen)
    if editor is None:
        return False
    editor.spaces.active.image = image
    editor.tag_redraw()
    return True


def _split_off_editor(context, screen):
    candidates = [a for a in screen.areas if a.type in {"VIEW_3D", "PROPERTIES", "OUTLINER"}] or list(screen.areas)
    if not candidates:
        return None
    largest = max(candidates, key=lambda a: a.width * a.height)
    before = {a.as_pointer() for a in screen.areas}
    with context.temp_override(window=context.window, screen=screen, area=largest):
        bpy.ops.screen.area_split(direction="VERTICAL", factor=0.5)
    new = [a for a in screen.areas if a.as_pointer() not in before]
    if not new:
        return None
    area = new[0]
    area.type = "IMAGE_EDITOR"
    return area


def redraw_image_editors(context, image: bpy.types.Image) -> None:
    """Redraw every Image Editor that shows ``image``."""
    wm = context.window_manager
    for window in wm.windows:
        for area in window.screen.areas:
            if area.type == "IMAGE_EDITOR" and area.spaces.active.image == image:
                area.tag_redraw()

"""One source of truth for the view and the size: the design's Camera & Image fields ARE the add-on's
"Lamp Camera" and the render resolution.

``sync_view`` keeps them equal, the side changed last winning (a design edit moves the Lamp Camera
and sets the resolution; moving the Lamp Camera in the viewport or changing the resolution writes the
design). It runs from a depsgraph handler and a message-bus subscription in the interface
(``camera_sync``) and at the start of every operator that renders or frames. The link starts when the
add-on makes its camera (``lamp_camera.ensure_lamp_camera``), so a file the add-on has not been used
in is never changed. A camera of the user's made the scene camera is rendered as it is and never
moved; the panel then says that the design's camera fields are not used.
"""

from __future__ import annotations

import json

from ...core_tracer.scene import spec as S
from . import properties as design_properties
from .camera import apply_camera, find_lamp_camera, is_lamp_camera, scene_camera_to_dict, set_render_size

LINK_KEY = "lamp_view_link"  # scene custom property: the view last seen in the design and in Blender


def design_view(bl_scene) -> tuple[dict, dict]:
    """The design's camera and image sections as the properties hold them (unchecked)."""
    doc = design_properties.design_document(bl_scene)
    return doc["camera"], doc["image"]



def write_design_camera(bl_scene, camera: dict) -> None:
    group = bl_scene.lamp_design.camera
    for key, value in camera.items():
        if key in ("exposure", "ev100"):
            continue  # the design's own, carried by the camera dict (Blender's camera has no exposure)
        if hasattr(group, key) and getattr(group, key) != value:
            setattr(group, key, value)


def _fits(image: dict) -> bool:
    """Whether the design's image size is in its allowed range: a size out of it (a negative width
    typed in the panel) is not handed to Blender, whose render resolution would clamp it and the
    link would then write the clamped size back, a silent change the design's check never saw."""
    sides = (S.IMAGE.fields["width"], S.IMAGE.fields["height"])
    return all(side.lo <= image[key] <= side.hi for key, side in zip(("width", "height"), sides, strict=True))


def _blender_view(bl_scene) -> dict:
    ob = find_lamp_camera(bl_scene)
    render = bl_scene.render
    camera = None
    if ob is not None and ob.data.type in {"PERSP", "ORTHO"}:
        camera = scene_camera_to_dict(bl_scene, ob)
    return {"camera": camera, "image": {"width": render.resolution_x, "height": render.resolution_y}}


def remember(bl_scene) -> None:
    camera, image = design_view(bl_scene)
    bl_scene[LINK_KEY] = json.dumps({"design": {"camera": camera, "image": image}, "blender": _blender_view(bl_scene)})


def _same(a, b) -> bool:
    """Equal up to Blender's single precision: a camera's matrix is recomputed from its location and
    rotation when the depsgraph evaluates it, which moves a target 1 m away by about 0.1 µm."""
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, float) or isinstance(b, float):
        return isinstance(a, (int, float)) and isinstance(b, (int, float)) and abs(a - b) <= 1e-3 + 1e-6 * abs(a)
    return a == b


def is_linked(bl_scene) -> bool:
    """Whether the design's view and Blender's are linked in this scene (the add-on made its camera)."""
    return isinstance(bl_scene.get(LINK_KEY), str)


_paused: set[int] = set()  # scenes whose link waits (a comparison changes the resolution for its renders)


def pause_link(bl_scene) -> None:
    """Stop ``sync_view`` for ``bl_scene`` until ``resume_link``: settings changed for a while and put
    back afterwards (Compare's render size) must not be taken for the user's edits."""
    _paused.add(bl_scene.as_pointer())


def resume_link(bl_scene) -> None:
    _paused.discard(bl_scene.as_pointer())


def sync_view(bl_scene) -> str:
    """Make the design's Camera & Image fields and the Lamp Camera & render resolution equal again,
    the side changed since the last call winning (Blender's when both changed: what the user sees).
    Returns "design", "blender" or "" (which side was written). Does nothing before the link starts."""
    if not is_linked(bl_scene) or not hasattr(bl_scene, "lamp_design") or bl_scene.as_pointer() in _paused:
        return ""
    last = json.loads(bl_scene[LINK_KEY])
    camera, image = design_view(bl_scene)
    design = {"camera": camera, "image": image}
    blender = _blender_view(bl_scene)
    written = ""
    if not _same(blender, last["blender"]):
        if blender["camera"] is not None and not _same(blender["camera"], last["blender"]["camera"]):
            write_design_camera(bl_scene, blender["camera"])
        if blender["image"] != last["blender"]["image"]:
            bl_scene.lamp_design.image.width = blender["image"]["width"]
            bl_scene.lamp_design.image.height = blender["image"]["height"]
        written = "design"
    elif not _same(design, last["design"]):
        ob = find_lamp_camera(bl_scene)
        if ob is not None and not _same(camera, last["design"]["camera"]):
            try:
                apply_camera(ob, camera, bl_scene)
            except (ZeroDivisionError, ValueError):
                pass  # target = position or up along the view: the panel shows the design's error
        if image != last["design"]["image"] and _fits(image):
            set_render_size(bl_scene, image)  # an image size out of range stays in the design, refused there
        written = "blender"
    if written:
        remember(bl_scene)
    return written


def view_status(bl_scene) -> tuple[str, str]:
    """What the panel says about the view: (text, icon)."""
    ob = bl_scene.camera
    if ob is None:
        return "No scene camera: Frame Lamp makes the Lamp Camera", "INFO"
    if is_lamp_camera(ob):
        return f'Rendering through "{ob.name}": the fields below are its view', "CHECKMARK"
    return f'Rendering through your "{ob.name}": the camera fields below are not used', "ERROR"


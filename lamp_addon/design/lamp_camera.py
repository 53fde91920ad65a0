"""The add-on's own "Lamp Camera": made at the design's view the first time the lamp is shown,
carried with the design's root, and framed on the lamp's body (Frame Lamp, and after lamps are added
or removed). A camera of the user's is never moved.
"""

from __future__ import annotations

import bpy

from ..convert import camera as cm
from . import properties as design_properties
from . import root as design_root
from .camera import (
    CAMERA_NAME,
    LAMP_CAMERA_KEY,
    apply_camera,
    find_lamp_camera,
    is_lamp_camera,
    scene_camera_to_dict,
    set_render_size,
)
from .view_link import design_view, is_linked, remember, sync_view, write_design_camera

CARRIED_KEY = "lamp_carried"  # the Lamp Camera was parented to the design's root once (``carry_with_root``)


def _usable_view(bl_scene) -> dict:
    """The design's camera if it is a valid view, else the default camera that frames its body."""
    from ...core_tracer.scene.derived import default_camera
    from ...core_tracer.scene.reading import SceneError
    from ...core_tracer.scene.validate import parse_scene

    doc = design_properties.design_document(bl_scene)
    try:
        return parse_scene({**doc, "lamps": doc["lamps"] or [{}]})["camera"]
    except SceneError:
        return default_camera({"body": doc["body"], "image": doc["image"]})


def ensure_lamp_camera(bl_scene, *, frame: bool = False) -> tuple[object, str]:
    """The add-on's "Lamp Camera", made when the scene has none at the design's view (which
    ``keep_framed`` keeps framed; a preset's own view), framed there when ``frame``; the
    first time it is made it becomes the scene camera, the user's camera left as it was. Starts the
    link between the design's view and Blender (``sync_view``). Returns the camera and what
    happened, for the operator's report ("" when nothing changed)."""
    ob = find_lamp_camera(bl_scene)
    if ob is not None:
        if is_linked(bl_scene):
            sync_view(bl_scene)
        else:  # a camera an earlier version made: the design's view is the truth
            _push_design(bl_scene, ob)
        return ob, ""
    data = bpy.data.cameras.new(CAMERA_NAME)
    ob = bpy.data.objects.new(CAMERA_NAME, data)
    ob[LAMP_CAMERA_KEY] = True
    bl_scene.collection.objects.link(ob)
    carry_with_root(bl_scene, ob)
    previous = bl_scene.camera
    bl_scene.camera = ob
    _, image = design_view(bl_scene)
    set_render_size(bl_scene, image)
    if frame:
        frame_on_body(bl_scene, ob, _usable_view(bl_scene))
    else:
        _push_design(bl_scene, ob)
    what = f'made the scene camera "{ob.name}"' + (", framed on the lamp" if frame else " at its view")
    if previous is not None:
        what += f' (your "{previous.name}" is kept as it was; make it the scene camera again in the Scene properties)'
    return ob, what


def carry_with_root(bl_scene, ob) -> bool:
    """Parent the Lamp Camera ``ob`` to the design's root, where it is in the world, so that moving the
    root (or parenting it to a car body) carries the lamp's own view along: the lamp stays framed and
    the design's camera, which is in the root's space, stays valid. Only a camera without a parent is
    attached, and only once (one the user parented elsewhere, or took off the root, stays so).
    Returns whether it was attached."""
    if ob.get(CARRIED_KEY) or ob.parent is not None or not is_lamp_camera(ob):
        return False
    root = design_root.find_root(bl_scene)
    if root is None:
        return False
    world = ob.matrix_world.copy()
    ob.parent = root
    ob.matrix_world = world
    ob[CARRIED_KEY] = True
    return True


def _push_design(bl_scene, ob) -> None:
    """The design's view onto camera ``ob`` and the render size; starts (or renews) the link."""
    _, image = design_view(bl_scene)
    set_render_size(bl_scene, image)
    apply_camera(ob, _usable_view(bl_scene), bl_scene)
    remember(bl_scene)


def frame_on_body(bl_scene, ob, view: dict) -> None:
    """Frame the body with camera ``ob`` from ``view``'s direction; the design's camera fields follow."""
    doc = design_properties.design_document(bl_scene)
    render = bl_scene.render
    framed = cm.frame_view(view, cm.body_box(doc), (render.resolution_x, render.resolution_y))
    apply_camera(ob, framed, bl_scene)
    write_design_camera(bl_scene, framed)
    remember(bl_scene)


def keep_framed(bl_scene) -> bool:
    """Re-frame the add-on's own view on the design's body (after lamps are added or removed or the
    body is resized), from its current direction: the Lamp Camera and the design's camera fields,
    or the design's camera fields alone before the Lamp Camera is made. A camera of the user's is
    never moved. Returns whether the view was framed (not when the design's camera is not a view)."""
    ob = find_lamp_camera(bl_scene)
    if ob is not None and ob.data.type not in {"PERSP", "ORTHO"}:
        return False
    if ob is not None:
        sync_view(bl_scene)
        frame_on_body(bl_scene, ob, scene_camera_to_dict(bl_scene, ob))
        return True
    from ...core_tracer.scene.reading import SceneError
    from ...core_tracer.scene.validate import parse_scene

    doc = design_properties.design_document(bl_scene)
    try:
        camera = parse_scene(doc)["camera"]
    except SceneError:
        return False  # the design is not valid yet: the panel says why
    size = (doc["image"]["width"], doc["image"]["height"])
    write_design_camera(bl_scene, cm.frame_view(camera, cm.body_box(doc), size))
    return True


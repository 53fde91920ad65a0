"""The scene camera: the one view both renderers use.

The scene description's camera (``scene["camera"]``, millimetres, docs/model.md §2) and Blender's
camera object are converted into each other here. The projection follows Blender's own camera
code (``BKE_camera_params_compute_viewplane``): the sensor size is ``sensor_height`` for a
vertical fit and ``sensor_width`` otherwise; AUTO fits the larger of the render's pixel
dimensions times the pixel aspect; the lens shift is a fraction of the fitted side; an
orthographic ``ortho_scale`` spans the fitted side. The tracer uses the same conventions
(``scene["camera"]``'s ``fov_deg``, ``width``, ``sensor_fit``, ``shift``), so the conversion is
exact apart from Blender's single-precision storage.

Blender keeps no look-at target, only an orientation; the target distance is kept in the
camera's focus distance (``dof.focus_distance``, or the distance to ``dof.focus_object`` as
Blender measures it), which is what "the point the camera looks at" means to a photographer.

The camera is read and written in the design's model space (the root object's local space,
``design.root.world_from_design``), so a lamp moved or parented to a car is seen the same way.

The add-on's own "Lamp Camera" is told apart from the user's cameras here (``is_lamp_camera``); it is
made and framed in ``lamp_camera``, kept equal to the design's Camera & Image fields by ``view_link``
(live in the interface through ``camera_sync``), and its buttons are ``camera_ops`` and
``camera_panel``. The mathematics (conversions, projection, framing) is bpy-free in
``convert/camera.py``.
"""

from __future__ import annotations

import math
import re

import bpy

from ..convert import camera as cm
from ..convert import units
from . import curves as design_curves
from . import properties as design_properties
from . import root as design_root

MM_PER_BU = units.MM_PER_BU
CAMERA_NAME = "Lamp Camera"
LAMP_CAMERA_KEY = "lamp_camera"  # custom property marking the camera the add-on made (found by it, not by name)

_FIT_TO_BLENDER = {"auto": "AUTO", "horizontal": "HORIZONTAL", "vertical": "VERTICAL"}
_FIT_FROM_BLENDER = {v: k for k, v in _FIT_TO_BLENDER.items()}


# ---------------------------------------------------------------------------------------------
# Reading and writing a Blender camera in model space


def _round(values, digits: int):
    if isinstance(values, (list, tuple)):
        return [round(float(v), digits) + 0.0 for v in values]  # + 0.0 turns -0.0 into 0.0
    return round(float(values), digits) + 0.0


def scene_camera_to_dict(bl_scene, camera_object=None) -> dict:
    """``scene["camera"]`` (mm, degrees, model space) read from Blender's scene camera.

    ``camera_object`` overrides ``bl_scene.camera`` (the render engine's camera override).
    Raises ``SceneError`` for what the tracer cannot render (no camera, panoramic camera,
    non-square pixels)."""
    from ...core_tracer.scene.reading import SceneError

    ob = camera_object if camera_object is not None else bl_scene.camera
    if ob is None:
        raise SceneError("camera", "the scene has no camera; press Frame Lamp (Camera & Image) or Build Lamp "
                                   "to make the Lamp Camera")
    if ob.type != "CAMERA":
        raise SceneError("camera", f'the scene camera "{ob.name}" is a {ob.type.lower()}, not a camera')
    cam = ob.data
    render = bl_scene.render
    if cam.type not in {"PERSP", "ORTHO"}:
        raise SceneError("camera.type", f'"{cam.type.lower()}" is not supported; allowed "perspective", '
                                        '"orthographic"')
    if render.pixel_aspect_x != render.pixel_aspect_y:
        raise SceneError("camera", f"pixel aspect {render.pixel_aspect_x:g}:{render.pixel_aspect_y:g} is not "
                                   "supported; the Lamp Tracer renders square pixels (set both to 1)")

    matrix = design_root.world_from_design(bl_scene).inverted() @ ob.matrix_world
    position = [matrix[i][3] * MM_PER_BU for i in range(3)]
    y_axis = [matrix[i][1] for i in range(3)]
    z_axis = [matrix[i][2] for i in range(3)]
    view = cm.view_from_axes(position, y_axis, z_axis, focus_distance(ob) * MM_PER_BU)

    fit = _FIT_FROM_BLENDER[cam.sensor_fit]
    return {
        "type": "perspective" if cam.type == "PERSP" else "orthographic",
        "position": _round(view["position"], 6),
        "target": _round(view["target"], 6),
        "up": _round(view["up"], 7),
        "fov_deg": _round(cm.fov_from_lens(cam.lens, cm.sensor_size(fit, cam.sensor_width, cam.sensor_height)), 5),
        "width": _round(cam.ortho_scale * MM_PER_BU, 6),
        "sensor_fit": fit,
        "shift": _round((cam.shift_x, cam.shift_y), 6),
        **design_exposure(bl_scene),
    }


def design_exposure(bl_scene) -> dict:
    """The design's exposure fields of its camera (``exposure``, ``ev100``): Blender's camera has no
    exposure of its own, so the camera a render uses keeps the design's (an EV100 fixed for every
    design rendered through it, docs/scene-format.md)."""
    group = bl_scene.lamp_design.camera
    return {"exposure": group.exposure, "ev100": design_properties.from_float32(group.ev100)}


def focus_distance(ob) -> float:
    """The camera's focus distance in Blender units, as ``BKE_camera_object_dof_distance``."""
    dof = ob.data.dof
    if dof.focus_object is not None:
        view_dir = ob.matrix_world.col[2].xyz.normalized()
        offset = ob.matrix_world.translation - dof.focus_object.matrix_world.translation
        return max(abs(view_dir.dot(offset)), 1e-5)
    return max(dof.focus_distance, 1e-5)


def apply_camera(ob, cam_dict: dict, bl_scene=None) -> None:
    """Set a Blender camera object from ``scene["camera"]`` (a normalised scene's camera) in the model
    space of ``bl_scene``'s design (world space when ``bl_scene`` is None or has no design root)."""
    from mathutils import Matrix

    cam = ob.data
    right, up, back = cm.look_at_axes(cam_dict["position"], cam_dict["target"], cam_dict["up"])
    loc = [x / MM_PER_BU for x in cam_dict["position"]]
    model = Matrix((
        (right[0], up[0], back[0], loc[0]),
        (right[1], up[1], back[1], loc[1]),
        (right[2], up[2], back[2], loc[2]),
        (0.0, 0.0, 0.0, 1.0),
    ))
    ob.matrix_world = model if bl_scene is None else design_root.world_from_design(bl_scene) @ model
    fit = cam_dict["sensor_fit"]
    cam.sensor_fit = _FIT_TO_BLENDER[fit]
    cam.type = "PERSP" if cam_dict["type"] == "perspective" else "ORTHO"
    cam.lens_unit = "MILLIMETERS"
    cam.lens = cm.lens_from_fov(cam_dict["fov_deg"], cm.sensor_size(fit, cam.sensor_width, cam.sensor_height))
    cam.ortho_scale = cam_dict["width"] / MM_PER_BU
    cam.shift_x, cam.shift_y = cam_dict["shift"]
    distance = math.dist(cam_dict["position"], cam_dict["target"]) / MM_PER_BU
    cam.dof.focus_object = None
    cam.dof.focus_distance = distance
    # A lamp is ~1 m away and a few cm deep: a near clip of 1 mm never cuts it, and the far clip
    # leaves room for the whole body behind the target.
    cam.clip_start = 0.001
    cam.clip_end = max(100.0, 10.0 * distance)


def set_render_size(bl_scene, image: dict) -> None:
    """Render resolution from ``scene["image"]``: 100 %, square pixels."""
    render = bl_scene.render
    render.resolution_x = image["width"]
    render.resolution_y = image["height"]
    render.resolution_percentage = 100
    render.pixel_aspect_x = render.pixel_aspect_y = 1.0


def evaluated_camera(bl_scene):
    """The scene camera as the depsgraph evaluates it (constraints, drivers, animation): the one
    F12 renders. Falls back to the object itself for a scene that is not the context's."""
    ob = bl_scene.camera
    if ob is None or bl_scene != bpy.context.scene:
        return ob
    return ob.evaluated_get(bpy.context.evaluated_depsgraph_get())


def scene_for_render(bl_scene, *, camera_object=None, size: tuple[int, int] | None = None) -> dict:
    """The normalised scene the tracer renders for this Blender scene: the design from the
    panel (``design.properties.design_to_scene``) seen through Blender's scene camera (evaluated, or
    ``camera_object``) at the render resolution (or ``size``). Raises ``SceneError``.

    The Blender camera and size replace the design's own camera and image sections before the
    scene is checked: the design's camera is not what renders, so it cannot block a render."""
    if camera_object is None:
        camera_object = evaluated_camera(bl_scene)
    render = bl_scene.render
    width, height = size if size is not None else cm.render_size(
        render.resolution_x, render.resolution_y, render.resolution_percentage)
    # The design's samples per pixel (and edge samples) go with it (F12 renders them); only the size is Blender's.
    own_image = bl_scene.lamp_design.image
    image = {"width": int(width), "height": int(height), "samples": int(own_image.samples),
             "edge_samples": int(own_image.edge_samples)}
    seen = scene_camera_to_dict(bl_scene, camera_object)
    own = _design_camera(bl_scene)
    if own is not None and same_view(seen, own):
        seen = own  # the design's own view (a preset just applied): its numbers, free of single precision
    scene = design_properties.design_to_scene(bl_scene, camera=seen, image=image)
    return design_curves.with_curves(bl_scene, scene)  # photometric: measured curves by their full paths


# Blender keeps a camera in single precision (a relative error of about 1e-7): a view read back from
# the camera object that differs from the design's by less than this, relative to the view's size, is
# the design's view.
SAME_VIEW = 1e-6


def _design_camera(bl_scene) -> dict | None:
    """The design's own camera section, normalised, or None when it is not a valid view."""
    from ...core_tracer.scene.reading import SceneError

    try:
        return design_properties.design_to_scene(bl_scene)["camera"]
    except SceneError:
        return None


def _image_up(cam: dict) -> list[float]:
    """The camera's up as the image shows it: ``up`` made square to the view direction, unit length."""
    d = [t - p for t, p in zip(cam["target"], cam["position"], strict=True)]
    d = [c / (math.hypot(*d) or 1.0) for c in d]
    u = cam["up"]
    along = sum(p * q for p, q in zip(u, d, strict=True))
    u = [p - along * q for p, q in zip(u, d, strict=True)]
    return [c / (math.hypot(*u) or 1.0) for c in u]


def same_view(a: dict, b: dict) -> bool:
    """Whether two normalised camera sections show the same view, up to Blender's single precision."""
    if (a["type"], a["sensor_fit"]) != (b["type"], b["sensor_fit"]):
        return False
    reach = max(math.dist(a["position"], a["target"]), a["width"], 1.0)  # mm: the size of the view
    sizes = {"position": reach, "target": reach, "width": reach, "up": 1.0, "fov_deg": 180.0, "shift": 1.0}
    for key, size in sizes.items():
        x, y = (v if isinstance(v, list) else [v] for v in (a[key], b[key]))
        if key == "up":  # the image's up: the design may give it unnormalised or not square to the view
            x, y = _image_up(a), _image_up(b)
        if not all(abs(p - q) <= SAME_VIEW * size for p, q in zip(x, y, strict=True)):
            return False
    return all(a[key] == b[key] for key in a if key not in sizes and key in b)


# ---------------------------------------------------------------------------------------------
# The add-on's own camera


def is_lamp_camera(ob) -> bool:
    """Whether ``ob`` is the camera the add-on made, not a camera of the user's. Files of earlier
    versions marked it by its name only ("Lamp Camera", "Lamp Camera.001", ...)."""
    if ob is None or ob.type != "CAMERA":
        return False
    mark = ob.get(LAMP_CAMERA_KEY)
    if mark is not None:
        return bool(mark)
    return re.fullmatch(re.escape(CAMERA_NAME) + r"(\.\d{3,})?", ob.name) is not None


def find_lamp_camera(bl_scene):
    """The add-on's camera in ``bl_scene`` (the scene camera first), or None."""
    if is_lamp_camera(bl_scene.camera):
        return bl_scene.camera
    return next((ob for ob in bl_scene.objects if is_lamp_camera(ob)), None)


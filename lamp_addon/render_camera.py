"""The scene camera: the one view both renderers use (issue 3, item 5).

The scene description's camera (``scene["camera"]``, millimetres, MODEL.md §2) and Blender's
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

The conversion math is in small functions that use no ``bpy``, which the tests check directly.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import bpy

from . import design_panels, design_properties
from .convert import units

MM_PER_BU = units.MM_PER_BU
CAMERA_NAME = "Lamp Camera"

_FIT_TO_BLENDER = {"auto": "AUTO", "horizontal": "HORIZONTAL", "vertical": "VERTICAL"}
_FIT_FROM_BLENDER = {v: k for k, v in _FIT_TO_BLENDER.items()}

Vec3 = tuple[float, float, float]


# ---------------------------------------------------------------------------------------------
# Pure conversion math


def render_size(resolution_x: int, resolution_y: int, percentage: int) -> tuple[int, int]:
    """The rendered size in pixels, as Blender computes it (integer division by 100)."""
    return resolution_x * percentage // 100, resolution_y * percentage // 100


def fitted_side(sensor_fit: str, width: float, height: float) -> str:
    """``"horizontal"`` or ``"vertical"``: the image side the field of view spans.

    ``width`` and ``height`` are the pixel counts times the pixel aspect (Blender's
    ``BKE_camera_sensor_fit``: AUTO picks horizontal when width >= height)."""
    if sensor_fit == "auto":
        return "horizontal" if width >= height else "vertical"
    return sensor_fit


def sensor_size(sensor_fit: str, sensor_width: float, sensor_height: float) -> float:
    """The sensor size the lens is fitted to (``BKE_camera_sensor_size``: AUTO uses the width)."""
    return sensor_height if sensor_fit == "vertical" else sensor_width


def fov_from_lens(lens_mm: float, sensor_mm: float) -> float:
    """Full field of view in degrees across a sensor of ``sensor_mm`` for a focal length."""
    return math.degrees(2.0 * math.atan(sensor_mm / (2.0 * lens_mm)))


def lens_from_fov(fov_deg: float, sensor_mm: float) -> float:
    """Focal length in mm giving ``fov_deg`` across ``sensor_mm``."""
    return sensor_mm / (2.0 * math.tan(math.radians(fov_deg) / 2.0))


def _sub(a: Sequence[float], b: Sequence[float]) -> Vec3:
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def _cross(a: Sequence[float], b: Sequence[float]) -> Vec3:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _dot(a: Sequence[float], b: Sequence[float]) -> float:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _unit(a: Sequence[float]) -> Vec3:
    n = math.sqrt(_dot(a, a))
    return (a[0] / n, a[1] / n, a[2] / n)


def look_at_axes(position: Sequence[float], target: Sequence[float], up: Sequence[float]) -> tuple[Vec3, Vec3, Vec3]:
    """The camera's local X (right), Y (up) and Z (back) axes in world space.

    A Blender camera looks along its local -Z with +Y up in the image."""
    forward = _unit(_sub(target, position))
    right = _unit(_cross(forward, up))
    true_up = _cross(right, forward)
    back = (-forward[0], -forward[1], -forward[2])
    return right, true_up, back


def view_from_axes(position_mm: Sequence[float], y_axis: Sequence[float], z_axis: Sequence[float],
                   target_distance_mm: float) -> dict:
    """Position, target and up of the scene camera from the camera's world axes.

    ``up`` is written as world +Z when the camera has no roll (its right axis is horizontal and
    its image up points upward), so that a camera made from ``up = [0, 0, 1]`` reads back as
    such; otherwise it is the camera's own (unit) up axis."""
    forward = _unit((-z_axis[0], -z_axis[1], -z_axis[2]))
    cam_up = _unit(y_axis)
    right = _cross(forward, cam_up)
    level = abs(right[2]) < 1e-6 and cam_up[2] > 1e-6
    up = (0.0, 0.0, 1.0) if level else cam_up
    target = tuple(p + target_distance_mm * f for p, f in zip(position_mm, forward, strict=True))
    return {"position": [float(x) for x in position_mm], "target": [float(x) for x in target],
            "up": [float(x) for x in up]}


# ---------------------------------------------------------------------------------------------
# Blender side


def _round(values, digits: int):
    if isinstance(values, (list, tuple)):
        return [round(float(v), digits) + 0.0 for v in values]  # + 0.0 turns -0.0 into 0.0
    return round(float(values), digits) + 0.0


def scene_camera_to_dict(bl_scene, camera_object=None) -> dict:
    """``scene["camera"]`` (mm, degrees) read from Blender's scene camera.

    ``camera_object`` overrides ``bl_scene.camera`` (the render engine's camera override).
    Raises ``SceneError`` for what the tracer cannot render (no camera, panoramic camera,
    non-square pixels)."""
    from ..core_tracer.scene.validate import SceneError

    ob = camera_object if camera_object is not None else bl_scene.camera
    if ob is None:
        raise SceneError("camera", "the scene has no camera; add one or build the lamp to create it")
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

    matrix = ob.matrix_world
    position = [matrix[i][3] * MM_PER_BU for i in range(3)]
    y_axis = [matrix[i][1] for i in range(3)]
    z_axis = [matrix[i][2] for i in range(3)]
    view = view_from_axes(position, y_axis, z_axis, focus_distance(ob) * MM_PER_BU)

    fit = _FIT_FROM_BLENDER[cam.sensor_fit]
    out = {
        "type": "perspective" if cam.type == "PERSP" else "orthographic",
        "position": _round(view["position"], 6),
        "target": _round(view["target"], 6),
        "up": _round(view["up"], 7),
        "fov_deg": _round(fov_from_lens(cam.lens, sensor_size(fit, cam.sensor_width, cam.sensor_height)), 5),
        "width": _round(cam.ortho_scale * MM_PER_BU, 6),
        "sensor_fit": fit,
        "shift": _round((cam.shift_x, cam.shift_y), 6),
    }
    return out


def focus_distance(ob) -> float:
    """The camera's focus distance in Blender units, as ``BKE_camera_object_dof_distance``."""
    dof = ob.data.dof
    if dof.focus_object is not None:
        view_dir = ob.matrix_world.col[2].xyz.normalized()
        offset = ob.matrix_world.translation - dof.focus_object.matrix_world.translation
        return max(abs(view_dir.dot(offset)), 1e-5)
    return max(dof.focus_distance, 1e-5)


def apply_camera(ob, cam_dict: dict) -> None:
    """Set a Blender camera object from ``scene["camera"]`` (a normalised scene's camera)."""
    from mathutils import Matrix

    cam = ob.data
    right, up, back = look_at_axes(cam_dict["position"], cam_dict["target"], cam_dict["up"])
    loc = [x / MM_PER_BU for x in cam_dict["position"]]
    ob.matrix_world = Matrix((
        (right[0], up[0], back[0], loc[0]),
        (right[1], up[1], back[1], loc[1]),
        (right[2], up[2], back[2], loc[2]),
        (0.0, 0.0, 0.0, 1.0),
    ))
    fit = cam_dict["sensor_fit"]
    cam.sensor_fit = _FIT_TO_BLENDER[fit]
    cam.type = "PERSP" if cam_dict["type"] == "perspective" else "ORTHO"
    cam.lens_unit = "MILLIMETERS"
    cam.lens = lens_from_fov(cam_dict["fov_deg"], sensor_size(fit, cam.sensor_width, cam.sensor_height))
    cam.ortho_scale = cam_dict["width"] / MM_PER_BU
    cam.shift_x, cam.shift_y = cam_dict["shift"]
    distance = math.dist(cam_dict["position"], cam_dict["target"]) / MM_PER_BU
    cam.dof.focus_object = None
    cam.dof.focus_distance = distance
    # A lamp is ~1 m away and a few cm deep: a near clip of 1 mm never cuts it, and the far clip
    # leaves room for the whole body behind the target.
    cam.clip_start = 0.001
    cam.clip_end = max(100.0, 10.0 * distance)


def ensure_scene_camera(bl_scene, scene: dict):
    """The scene camera; when the Blender scene has none, create one matching ``scene["camera"]``
    and set the render resolution from ``scene["image"]``. Returns the camera object."""
    if bl_scene.camera is not None:
        return bl_scene.camera
    data = bpy.data.cameras.new(CAMERA_NAME)
    ob = bpy.data.objects.new(CAMERA_NAME, data)
    bl_scene.collection.objects.link(ob)
    apply_camera(ob, scene["camera"])
    bl_scene.camera = ob
    set_render_size(bl_scene, scene["image"])
    return ob


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
    panel (``design_properties.design_to_scene``) seen through Blender's scene camera (evaluated, or
    ``camera_object``) at the render resolution (or ``size``). Raises ``SceneError``.

    The Blender camera and size replace the design's own camera and image sections before the
    scene is checked: the design's camera is not what renders, so it cannot block a render."""
    if camera_object is None:
        camera_object = evaluated_camera(bl_scene)
    render = bl_scene.render
    width, height = size if size is not None else render_size(
        render.resolution_x, render.resolution_y, render.resolution_percentage)
    return design_properties.design_to_scene(bl_scene, camera=scene_camera_to_dict(bl_scene, camera_object),
                                      image={"width": int(width), "height": int(height)})


# ---------------------------------------------------------------------------------------------
# Operators: the design's camera section and the scene camera, either way


class LAMP_OT_camera_from_design(bpy.types.Operator):
    """Set the scene camera (created if there is none) and the render size from the design's camera and image"""

    bl_idname = "lamp.camera_from_design"
    bl_label = "Scene Camera from Design"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return design_properties.poll_design(cls, context)

    def execute(self, context):
        from ..core_tracer.scene.validate import SceneError

        bl_scene = context.scene
        try:
            design = design_properties.design_to_scene(bl_scene)
        except SceneError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        if bl_scene.camera is None or bl_scene.camera.type != "CAMERA":
            bl_scene.camera = None
            ensure_scene_camera(bl_scene, design)
        else:
            apply_camera(bl_scene.camera, design["camera"])
            set_render_size(bl_scene, design["image"])
        return {"FINISHED"}


class LAMP_OT_camera_to_design(bpy.types.Operator):
    """Store the scene camera's view and the render size in the design (what a saved preset records)"""

    bl_idname = "lamp.camera_to_design"
    bl_label = "Design Camera from Scene Camera"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        if not design_properties.poll_design(cls, context):
            return False
        if context.scene.camera is None:
            cls.poll_message_set("The scene has no camera")
            return False
        return True

    def execute(self, context):
        from ..core_tracer.scene.validate import SceneError

        try:
            design_properties.scene_to_design(context.scene, scene_for_render(context.scene))
        except SceneError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        return {"FINISHED"}


classes = (LAMP_OT_camera_from_design, LAMP_OT_camera_to_design)


register, unregister = design_panels.register_actions_factory(classes, (
    ("lamp.camera_from_design", "Scene Camera from Design", "CAMERA_DATA"),
    ("lamp.camera_to_design", "Design Camera from Scene Camera", "OUTLINER_OB_CAMERA"),
))

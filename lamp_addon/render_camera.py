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
``design_root.world_from_design``), so a lamp moved or parented to a car is seen the same way.

One source of truth for the view and the size: the design's Camera & Image fields ARE the add-on's
"Lamp Camera" and the render resolution. ``sync_view`` keeps them equal, the side changed last
winning (a design edit moves the Lamp Camera and sets the resolution; moving the Lamp Camera in the
viewport or changing the resolution writes the design). It runs from a depsgraph handler and a
message-bus subscription in the interface and at the start of every operator that renders or frames.
The link starts when the add-on makes its camera (``ensure_lamp_camera``), so a file the add-on has
not been used in is never changed. A camera of the user's made the scene camera is rendered as it
is and never moved; the panel then says that the design's camera fields are not used.

The mathematics (conversions, projection, framing) is bpy-free in ``convert/camera.py``.
"""

from __future__ import annotations

import json
import math
import re

import bpy

from . import actions, design_properties, design_root
from .convert import camera as cm
from .convert import units
from .design_operator import DesignOperator

MM_PER_BU = units.MM_PER_BU
CAMERA_NAME = "Lamp Camera"
LAMP_CAMERA_KEY = "lamp_camera"  # custom property marking the camera the add-on made (found by it, not by name)
CARRIED_KEY = "lamp_carried"  # the Lamp Camera was parented to the design's root once (``carry_with_root``)
LINK_KEY = "lamp_view_link"  # scene custom property: the view last seen in the design and in Blender

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
    from ..core_tracer.scene.reading import SceneError

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
    }


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
    panel (``design_properties.design_to_scene``) seen through Blender's scene camera (evaluated, or
    ``camera_object``) at the render resolution (or ``size``). Raises ``SceneError``.

    The Blender camera and size replace the design's own camera and image sections before the
    scene is checked: the design's camera is not what renders, so it cannot block a render."""
    if camera_object is None:
        camera_object = evaluated_camera(bl_scene)
    render = bl_scene.render
    width, height = size if size is not None else cm.render_size(
        render.resolution_x, render.resolution_y, render.resolution_percentage)
    # The design's samples per pixel go with it (F12 renders them); only the size is Blender's.
    image = {"width": int(width), "height": int(height), "samples": int(bl_scene.lamp_design.image.samples)}
    return design_properties.design_to_scene(bl_scene, camera=scene_camera_to_dict(bl_scene, camera_object),
                                             image=image)


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


def _design_view(bl_scene) -> tuple[dict, dict]:
    """The design's camera and image sections as the properties hold them (unchecked)."""
    doc = design_properties.design_document(bl_scene)
    return doc["camera"], doc["image"]


def _usable_view(bl_scene) -> dict:
    """The design's camera if it is a valid view, else the default camera that frames its body."""
    from ..core_tracer.scene.derived import default_camera
    from ..core_tracer.scene.reading import SceneError
    from ..core_tracer.scene.validate import parse_scene

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
    _, image = _design_view(bl_scene)
    set_render_size(bl_scene, image)
    if frame:
        _frame(bl_scene, ob, _usable_view(bl_scene))
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
    _, image = _design_view(bl_scene)
    set_render_size(bl_scene, image)
    apply_camera(ob, _usable_view(bl_scene), bl_scene)
    _remember(bl_scene)


def _frame(bl_scene, ob, view: dict) -> None:
    """Frame the body with camera ``ob`` from ``view``'s direction; the design's camera fields follow."""
    doc = design_properties.design_document(bl_scene)
    render = bl_scene.render
    framed = cm.frame_view(view, cm.body_box(doc), (render.resolution_x, render.resolution_y))
    apply_camera(ob, framed, bl_scene)
    _write_design_camera(bl_scene, framed)
    _remember(bl_scene)


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
        _frame(bl_scene, ob, scene_camera_to_dict(bl_scene, ob))
        return True
    from ..core_tracer.scene.reading import SceneError
    from ..core_tracer.scene.validate import parse_scene

    doc = design_properties.design_document(bl_scene)
    try:
        camera = parse_scene(doc)["camera"]
    except SceneError:
        return False  # the design is not valid yet: the panel says why
    size = (doc["image"]["width"], doc["image"]["height"])
    _write_design_camera(bl_scene, cm.frame_view(camera, cm.body_box(doc), size))
    return True


# ---------------------------------------------------------------------------------------------
# One source of truth: the design's Camera & Image fields and the Lamp Camera / render size


def _write_design_camera(bl_scene, camera: dict) -> None:
    group = bl_scene.lamp_design.camera
    for key, value in camera.items():
        if hasattr(group, key) and getattr(group, key) != value:
            setattr(group, key, value)


def _blender_view(bl_scene) -> dict:
    ob = find_lamp_camera(bl_scene)
    render = bl_scene.render
    camera = None
    if ob is not None and ob.data.type in {"PERSP", "ORTHO"}:
        camera = scene_camera_to_dict(bl_scene, ob)
    return {"camera": camera, "image": {"width": render.resolution_x, "height": render.resolution_y}}


def _remember(bl_scene) -> None:
    camera, image = _design_view(bl_scene)
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
    camera, image = _design_view(bl_scene)
    design = {"camera": camera, "image": image}
    blender = _blender_view(bl_scene)
    written = ""
    if not _same(blender, last["blender"]):
        if blender["camera"] is not None and not _same(blender["camera"], last["blender"]["camera"]):
            _write_design_camera(bl_scene, blender["camera"])
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
        if image != last["design"]["image"]:
            set_render_size(bl_scene, image)
        written = "blender"
    if written:
        _remember(bl_scene)
    return written


def view_status(bl_scene) -> tuple[str, str]:
    """What the panel says about the view: (text, icon)."""
    ob = bl_scene.camera
    if ob is None:
        return "No scene camera: Frame Lamp makes the Lamp Camera", "INFO"
    if is_lamp_camera(ob):
        return f'Rendering through "{ob.name}": the fields below are its view', "CHECKMARK"
    return f'Rendering through your "{ob.name}": the camera fields below are not used', "ERROR"


# ---------------------------------------------------------------------------------------------
# Keeping the link live in the interface


_syncing: list[bool] = []  # re-entrancy guard: writing one side triggers the handlers again


def _sync_quietly(bl_scene) -> None:
    if _syncing or bl_scene is None:
        return
    _syncing.append(True)
    try:
        sync_view(bl_scene)
    except Exception as e:  # a handler must never break Blender's update loop; say it once
        print(f"Lamp Styling: the design's view and the Lamp Camera could not be synchronised: {e}")
    finally:
        _syncing.clear()


@bpy.app.handlers.persistent
def _on_depsgraph_update(scene, depsgraph) -> None:
    # Blender's side changed: the Lamp Camera moved or its lens changed, or the resolution (the Scene).
    # Other objects moving (every step of a drag) are not looked at.
    if not is_linked(scene):
        return
    ob = find_lamp_camera(scene)
    watched = {scene.as_pointer()}
    if ob is not None:
        watched |= {ob.as_pointer(), ob.data.as_pointer()}
    if any(u.id.original.as_pointer() in watched for u in depsgraph.updates):
        if ob is not None and not ob.get(CARRIED_KEY) and not _syncing:
            carry_with_root(scene, ob)  # the first build by Auto Build made the root the camera goes with
        _sync_quietly(scene)


_MSGBUS_OWNER = object()


def _on_design_view_edit(*_args) -> None:
    _sync_quietly(bpy.context.scene)


def _subscribe() -> None:
    # Edits of the design's properties do not reach the depsgraph; the message bus reports them.
    properties = design_properties.LampDesign.bl_rna.properties
    wanted = {properties[key].fixed_type.identifier for key in ("camera", "image")}
    for group in design_properties.classes:
        if group.bl_rna.identifier in wanted:
            bpy.msgbus.subscribe_rna(key=group, owner=_MSGBUS_OWNER, args=(), notify=_on_design_view_edit)


@bpy.app.handlers.persistent
def _on_load_post(*_args) -> None:
    bpy.msgbus.clear_by_owner(_MSGBUS_OWNER)  # a loaded file starts with no subscriptions
    _subscribe()


# ---------------------------------------------------------------------------------------------
# Operators and the camera area of the panel


class LAMP_OT_frame_design(DesignOperator, bpy.types.Operator):
    """Point the Lamp Camera at the whole lamp body with a margin, from the current viewing direction
    (the 3D View's when used there, else the Lamp Camera's own); makes it the scene camera.
    A camera of yours is never moved"""

    bl_idname = "lamp.frame_design"
    bl_label = "Frame Lamp"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        return self._frame(context, None)

    def invoke(self, context, event):
        region = context.region_data
        direction = None
        if region is not None and getattr(region, "view_perspective", "CAMERA") != "CAMERA":
            direction = region.view_rotation.to_matrix()  # the 3D View's axes: look along -Z, +Y up
        return self._frame(context, direction)

    def _frame(self, context, view_axes):
        bl_scene = context.scene
        ob, made = ensure_lamp_camera(bl_scene)
        if ob.data.type not in {"PERSP", "ORTHO"}:
            return self.cancelled(f'"{ob.name}" is a panoramic camera; set it to Perspective or Orthographic')
        view = scene_camera_to_dict(bl_scene, ob)
        if view_axes is not None:  # the 3D View's axes in the design's model space
            model = design_root.world_from_design(bl_scene).to_3x3().inverted() @ view_axes
            view = cm.looking_along(view, [-model[i][2] for i in range(3)], [model[i][1] for i in range(3)])
        previous = bl_scene.camera
        bl_scene.camera = ob
        _frame(bl_scene, ob, view)
        if not made and previous is not ob and previous is not None:
            made = f'"{ob.name}" is the scene camera again (your "{previous.name}" was not moved)'
        self.report({"INFO"}, f'Framed the lamp with "{ob.name}"' + (f"; {made}" if made else ""))
        return {"FINISHED"}


class LAMP_OT_camera_to_design(DesignOperator, bpy.types.Operator):
    """Copy your scene camera's view and the render size into the design's camera fields (what a saved
    preset records); the Lamp Camera takes that view. Your camera is not changed"""

    bl_idname = "lamp.camera_to_design"
    bl_label = "Copy Scene Camera to Design"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def refusal(cls, context):
        if context.scene.camera is None:
            return "The scene has no camera"
        if is_lamp_camera(context.scene.camera):
            return "The scene camera is the Lamp Camera: the design's fields already are its view"
        return None

    def execute(self, context):
        from ..core_tracer.scene.reading import SceneError

        bl_scene = context.scene
        try:
            seen = scene_for_render(bl_scene)
        except SceneError as e:
            return self.cancelled(e)
        sync_view(bl_scene)
        _write_design_camera(bl_scene, seen["camera"])
        bl_scene.lamp_design.image.width, bl_scene.lamp_design.image.height = (
            bl_scene.render.resolution_x, bl_scene.render.resolution_y)
        sync_view(bl_scene)  # the design changed: the Lamp Camera, if any, follows
        return {"FINISHED"}


class LAMP_PT_camera_view(bpy.types.Panel):
    """In the design's Camera & Image panel: which camera renders, and the camera actions."""

    bl_label = "Scene Camera"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Lamp"
    bl_parent_id = "LAMP_PT_camera"
    bl_order = 0

    def draw(self, context):
        layout = self.layout
        text, icon = view_status(context.scene)
        layout.label(text=text, icon=icon)
        row = layout.row(align=True)
        row.operator("lamp.frame_design", icon="VIEW_CAMERA")
        if context.scene.camera is not None and not is_lamp_camera(context.scene.camera):
            row.operator("lamp.camera_to_design", icon="OUTLINER_OB_CAMERA")


classes = (LAMP_OT_frame_design, LAMP_OT_camera_to_design, LAMP_PT_camera_view)

_register_classes, _unregister_classes = actions.register_actions_factory(
    classes, (("lamp.frame_design", "Frame Lamp", "VIEW_CAMERA"),))


def register() -> None:
    _register_classes()
    bpy.app.handlers.depsgraph_update_post.append(_on_depsgraph_update)
    bpy.app.handlers.load_post.append(_on_load_post)
    _subscribe()


def unregister() -> None:
    bpy.msgbus.clear_by_owner(_MSGBUS_OWNER)
    for handlers, handler in ((bpy.app.handlers.load_post, _on_load_post),
                              (bpy.app.handlers.depsgraph_update_post, _on_depsgraph_update)):
        while handler in handlers:
            handlers.remove(handler)
    _unregister_classes()

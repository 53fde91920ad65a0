"""The 3D View framed on the lamp, and what stands in the way of seeing it.

The first lamp of a file and *Frame Lamp* frame the 3D Views the user looks at on the design, as
*View Selected* does: the view keeps its direction and moves its centre and distance so that the
design's box (the body's, where every part of a valid design lies) fills the region with a margin.
A view through the scene camera is left as it is (that camera is the framed Lamp Camera, or one of
the user's). Nothing of the user's is hidden or moved: when an object of theirs encloses the lamp
(the startup file's Cube does), the report names it and *Hide Other Objects* hides the others in
the viewport, as one undo step (Alt+H shows them again).
"""

from __future__ import annotations

import bpy
from mathutils import Matrix, Vector

from .. import actions, reports
from ..convert import camera as cm
from ..convert.units import BU_PER_MM
from . import properties as design_properties
from . import root as design_root
from .camera import is_lamp_camera

MARGIN = 0.8  # the design's box fills at most this fraction of the region's half-width and half-height


def design_corners(bl_scene) -> list[Vector]:
    """The 8 corners of the design's box (the body's, in model space) in world coordinates."""
    doc = design_properties.design_document(bl_scene)
    world = design_root.world_from_design(bl_scene)
    return [world @ (Vector(corner) * BU_PER_MM) for corner in cm.box_corners(*cm.body_box(doc))]


def views_of(bl_scene) -> list[tuple[bpy.types.Area, bpy.types.Region, bpy.types.RegionView3D]]:
    """The 3D Views the user looks at in the windows that show ``bl_scene``: (area, its main
    region, its view), those looking through the scene camera left out."""
    views = []
    wm = bpy.context.window_manager
    for window in wm.windows if wm is not None else ():
        if window.scene != bl_scene or window.screen is None:
            continue
        for area in window.screen.areas:
            if area.type != "VIEW_3D":
                continue
            region = next((r for r in area.regions if r.type == "WINDOW"), None)
            view = area.spaces.active.region_3d
            if region is None or view is None or region.width < 2 or region.height < 2:
                continue
            if view.view_perspective != "CAMERA":
                views.append((area, region, view))
    return views


# Blender's 3D View sees through a 36 mm sensor at twice the zoom of a camera (``DEFAULT_SENSOR_WIDTH``
# and ``CAMERA_PARAM_ZOOM_INIT_PERSP`` in its ``BKE_camera_params_from_view3d``): the tangent of the
# half field of the region's longer side is SENSOR_MM * ZOOM / (2 lens).
SENSOR_MM, ZOOM = 36.0, 2.0


def view_matrix(view: bpy.types.RegionView3D) -> Matrix:
    """The view's world-to-eye matrix from its centre, rotation and distance, as Blender defines it
    (``RegionView3D.view_matrix`` is only brought up to date when the region is drawn)."""
    eye = Matrix.Translation(view.view_location) @ view.view_rotation.to_matrix().to_4x4()
    return (eye @ Matrix.Translation((0.0, 0.0, view.view_distance))).inverted()


def _half_extent(view, region, space) -> tuple[float, float]:
    """Half the region's width and height on the view plane at distance 1 (perspective) or in units (ortho)."""
    half = SENSOR_MM * ZOOM / (2.0 * space.lens)
    if not view.is_perspective:
        half *= view.view_distance
    width, height = region.width, region.height
    return (half, half * height / width) if width >= height else (half * width / height, half)


def reach(view, region, space, corners: list[Vector]) -> float:
    """How far the corners reach in the view's normalised device coordinates (1: the region's edge;
    infinity when one is behind the eye)."""
    to_eye = view_matrix(view)
    half_x, half_y = _half_extent(view, region, space)
    out = 0.0
    for corner in corners:
        x, y, z = to_eye @ corner
        depth = -z if view.is_perspective else 1.0
        if depth <= 0.0:
            return float("inf")
        out = max(out, abs(x / depth) / half_x, abs(y / depth) / half_y)
    return out


def frame_view(view, region, space, corners: list[Vector]) -> None:
    """Centre ``view`` on the corners and set its distance so that they fill ``MARGIN`` of the region
    (its direction kept), as View Selected does."""
    center = sum(corners, Vector()) / len(corners)
    radius = max((c - center).length for c in corners) or 0.01
    view.view_location = center
    view.view_distance = 4.0 * radius
    for _ in range(20):
        now = reach(view, region, space, corners)
        if abs(now - MARGIN) < 0.005:
            break
        scale = 2.0 if now == float("inf") else max(0.25, min(4.0, now / MARGIN))
        view.view_distance = view.view_distance * scale


def frame_views(bl_scene) -> int:
    """Frame every 3D View the user looks at on the design (``views_of``); how many were framed."""
    corners = design_corners(bl_scene)
    framed = 0
    for area, region, view in views_of(bl_scene):
        frame_view(view, region, area.spaces.active, corners)
        area.tag_redraw()
        framed += 1
    return framed


def is_lamp_object(ob: bpy.types.Object) -> bool:
    """Whether ``ob`` is the lamp's: a part, the root, the Lamp Camera or a free-form part with a role."""
    role = getattr(ob, "lamp_role", None)
    return bool(ob.get(design_root.PART_KEY)) or is_lamp_camera(ob) or (role is not None and role.role != "NONE")


def enclosing(bl_scene) -> list[str]:
    """The names of visible objects of the user's whose box encloses the design's (the startup Cube)."""
    corners = design_corners(bl_scene)
    names = []
    for ob in bl_scene.objects:
        if ob.type != "MESH" or is_lamp_object(ob) or not ob.visible_get():
            continue
        box = [ob.matrix_world @ Vector(c) for c in ob.bound_box]
        lo = Vector([min(c[i] for c in box) for i in range(3)])
        hi = Vector([max(c[i] for c in box) for i in range(3)])
        if all(lo[i] <= c[i] <= hi[i] for c in corners for i in range(3)):
            names.append(ob.name)
    return names


def hidden_note(bl_scene) -> str:
    """A phrase for a report when an object of the user's hides the lamp ("" when none does)."""
    names = enclosing(bl_scene)
    if not names:
        return ""
    return f'the lamp is inside "{names[0]}": Hide Other Objects (Lamp tab) shows it'


class LAMP_OT_hide_others(bpy.types.Operator):
    """Hide every object that is not the lamp's in the viewport (the startup Cube around it, say);
    Alt+H in the 3D View shows them again. Renders are not changed"""

    bl_idname = "lamp.hide_others"
    bl_label = "Hide Other Objects"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        if context.view_layer is None:
            return False
        if not any(not is_lamp_object(ob) and ob.visible_get() for ob in context.view_layer.objects):
            cls.poll_message_set("Only the lamp is visible")
            return False
        return True

    def execute(self, context):
        others = [ob for ob in context.view_layer.objects if not is_lamp_object(ob) and ob.visible_get()]
        for ob in others:
            ob.hide_set(True)
        names = ", ".join(ob.name for ob in others[:3]) + (", ..." if len(others) > 3 else "")
        reports.say(self, "INFO", f"Hid {len(others)} objects in the viewport ({names}); Alt+H shows them again")
        return {"FINISHED"}


classes = (LAMP_OT_hide_others,)

register, unregister = actions.register_actions_factory(
    classes, (("lamp.hide_others", "Hide Other Objects", "HIDE_ON"),))

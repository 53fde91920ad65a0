"""The camera's operators: Frame Lamp (also a button of the actions area) and Copy Scene Camera to
Design."""

from __future__ import annotations

import bpy

from .. import actions, reports
from ..convert import camera as cm
from ..design import root as design_root
from ..design import view_frame
from ..design.camera import is_lamp_camera, scene_camera_to_dict, scene_for_render
from ..design.lamp_camera import ensure_lamp_camera, frame_on_body
from ..design.operator import DesignOperator
from ..design.view_link import sync_view, write_design_camera


class LAMP_OT_frame_design(DesignOperator, bpy.types.Operator):
    """Point the Lamp Camera at the whole lamp body with a margin, from the current viewing direction
    (the 3D View's when used there, else the Lamp Camera's own), make it the scene camera and frame the
    3D View on the lamp. A camera of yours is never moved"""

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
        frame_on_body(bl_scene, ob, view)
        if not made and previous is not ob and previous is not None:
            made = f'"{ob.name}" is the scene camera again (your "{previous.name}" was not moved)'
        views = view_frame.frame_views(bl_scene)
        hidden = view_frame.hidden_note(bl_scene)
        more = [made] if made else []
        if views:
            more.append(f"Framed {views} 3D Views on the lamp")
        return reports.finished(self, f'Framed the lamp with "{ob.name}"' + (f"; {hidden}" if hidden else ""), more)


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
        from ...core_tracer.scene.reading import SceneError

        bl_scene = context.scene
        try:
            seen = scene_for_render(bl_scene)
        except SceneError as e:
            return self.cancelled(e)
        sync_view(bl_scene)
        write_design_camera(bl_scene, seen["camera"])
        bl_scene.lamp_design.image.width, bl_scene.lamp_design.image.height = (
            bl_scene.render.resolution_x, bl_scene.render.resolution_y)
        sync_view(bl_scene)  # the design changed: the Lamp Camera, if any, follows
        return {"FINISHED"}


classes = (LAMP_OT_frame_design, LAMP_OT_camera_to_design)

register, unregister = actions.register_actions_factory(classes, (("lamp.frame_design", "Frame Lamp", "VIEW_CAMERA"),))

"""The camera area of the design's Camera & Image panel: which camera renders, and the camera's
buttons."""

from __future__ import annotations

import bpy

from ..design.camera import is_lamp_camera
from ..design.panels import LampTab
from ..design.view_link import view_status


class LAMP_PT_camera_view(LampTab, bpy.types.Panel):
    """In the design's Camera & Image panel: which camera renders, and the camera actions."""

    bl_label = "Scene Camera"
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



classes = (LAMP_PT_camera_view,)

register, unregister = bpy.utils.register_classes_factory(classes)

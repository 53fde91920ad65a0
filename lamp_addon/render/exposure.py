# SPDX-License-Identifier: GPL-3.0-or-later
"""*Exposure from Design*: the scene's exposure set to the design's automatic exposure.

F12 renders with the Lamp Tracer engine and the viewport's Rendered shading are shown through the
scene's colour management (Render Properties > Color Management), like any engine's. A lit lens is
ten or more times brighter than display white, so at the default exposure it shows as a flat,
pale disk. This operator measures the design from the scene camera on a small preview render
(``image_view.design_exposure``) and sets the scene's exposure to it; the designer can set
another value afterwards as usual. The add-on's own images (Lamp Tracer, Lamp Compare, Lamp
Study) are shown at the design's exposure whatever the scene's is (``image_view.show_linear``).
"""

from __future__ import annotations

import bpy

from ...core_tracer.scene.reading import SceneError
from .. import actions
from ..design.operator import DesignOperator
from . import camera, setup


class LAMP_OT_exposure_from_design(DesignOperator, bpy.types.Operator):
    """Set the scene's exposure so the lit lens shows its cut pattern instead of a flat disk (measured
    on a small render of the design from the scene camera)"""

    bl_idname = "lamp.exposure_from_design"
    bl_label = "Exposure from Design"
    bl_options = {"REGISTER", "UNDO"}  # changes the scene's colour management

    @classmethod
    def refusal(cls, context):
        return "The scene has no camera to measure the design from" if context.scene.camera is None else None

    def execute(self, context):
        try:
            camera.scene_for_render(context.scene)
        except SceneError as e:
            return self.cancelled(e)
        setup.follow_design_exposure(context.scene, force=True)
        settings = context.scene.view_settings
        self.report({"INFO"}, f"Exposure {settings.exposure:+.1f} EV ({settings.view_transform}): the lit lens "
                              "shows its cut pattern; Build Lamp keeps it at the design's until you set your own")
        return {"FINISHED"}


classes = (LAMP_OT_exposure_from_design,)

register, unregister = actions.register_actions_factory(
    classes, (("lamp.exposure_from_design", "Exposure from Design", "LIGHT_SUN"),))

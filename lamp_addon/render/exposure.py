# SPDX-License-Identifier: GPL-3.0-or-later
"""*Exposure from Design*: the scene's exposure set to the design's automatic exposure.

The exposure belongs to the view, not to the design (``setup``): F12 renders with the Lamp Tracer
engine and the viewport's Rendered shading are shown through the scene's colour management (Render
Properties > Color Management), like any engine's, and Build Lamp and Apply Preset never change it,
so designs compare under one exposure. A lit lens is ten or more times brighter than display white;
this operator is the explicit way to expose for the design in view: it measures the design from the
scene camera on a small preview render (``image_view.design_exposure``, with the bulbs on when every
bulb is off) and sets the scene's exposure to it. Render with Lamp Tracer's image is shown at the
scene's exposure too, as F12 is; the add-on's sheets (Lamp Compare, Lamp Study) are each shown under
one exposure for all their pictures (``image_view.show_linear``). Each light model keeps its own
exposure (``setup.follow_light_model``): a photometric image is already exposed by its EV100, so
the paper model's exposure would show it nearly black.
"""

from __future__ import annotations

import bpy

from ...core_tracer.images import display
from ...core_tracer.scene.reading import SceneError
from .. import actions, reports
from ..design import properties as design_properties
from ..design import setup
from ..design.operator import DesignOperator


class LAMP_OT_exposure_from_design(DesignOperator, bpy.types.Operator):
    """Expose the view for the design in it, so that the lit lens shows its cut pattern instead of a flat
    disk (Build Lamp and Apply Preset keep the exposure, so designs compare)"""

    bl_idname = "lamp.exposure_from_design"
    bl_label = "Exposure from Design"
    bl_options = {"REGISTER", "UNDO"}  # changes the scene's colour management

    @classmethod
    def refusal(cls, context):
        return "The scene has no camera to measure the design from" if context.scene.camera is None else None

    def execute(self, context):
        try:
            exposure, lit = setup.set_design_exposure(context.scene)
        except SceneError as e:
            return self.cancelled(e)
        if not lit:
            return reports.finished(self, f"Nothing is lit (every bulb is off): exposure {exposure:+.1f} EV, "
                                          "for the bulbs on")
        return reports.finished(self, f"Exposure {exposure:+.1f} EV: the lit lens shows its cut pattern")


class LAMP_OT_lamp_view(bpy.types.Operator):
    """Show the scene through the lamp view (Filmic): lit red and amber lamps keep their hue, where AgX,
    Blender's default, washes red to salmon and amber to peach"""

    bl_idname = "lamp.lamp_view"
    bl_label = "Lamp View"
    bl_options = {"REGISTER", "UNDO"}  # changes the scene's colour management, on request only

    @classmethod
    def poll(cls, context):
        if context.scene is None:
            return False
        if context.scene.view_settings.view_transform == display.LAMP_VIEW:
            cls.poll_message_set(f"The scene is shown through {display.LAMP_VIEW} already")
            return False
        return True

    def execute(self, context):
        settings = context.scene.view_settings
        before = settings.view_transform
        try:
            settings.view_transform = display.LAMP_VIEW
        except TypeError:  # a colour configuration without it (OCIO set to another one)
            return reports.cancelled(self, f"This Blender's colour management has no {display.LAMP_VIEW} view; "
                                           "choose a view in Render Properties > Color Management")
        settings.look = "None"  # a look belongs to the view it was made for
        return reports.finished(self, f"View transform {display.LAMP_VIEW} (was {before}): lit red and amber "
                                      "keep their hue; Ctrl+Z goes back")


classes = (LAMP_OT_exposure_from_design, LAMP_OT_lamp_view)

_register, _unregister = actions.register_actions_factory(
    classes, (("lamp.exposure_from_design", "Exposure from Design", "LIGHT_SUN"),
              ("lamp.lamp_view", "Lamp View", "COLOR")))


def register() -> None:
    _register()
    design_properties.EDIT_LISTENERS.append(setup.light_model_edited)  # one exposure per light model


def unregister() -> None:
    if setup.light_model_edited in design_properties.EDIT_LISTENERS:
        design_properties.EDIT_LISTENERS.remove(setup.light_model_edited)
    _unregister()

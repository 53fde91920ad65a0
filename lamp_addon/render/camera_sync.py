"""Keeping the link between the design's view and the Lamp Camera live in the interface: a depsgraph
handler for Blender's side (the Lamp Camera moved, its lens or the resolution changed) and a
message-bus subscription for the design's (``view_link.sync_view``, once per change).
"""

from __future__ import annotations

import bpy

from ..design import properties as design_properties
from ..design.camera import find_lamp_camera
from ..design.lamp_camera import CARRIED_KEY, carry_with_root
from ..design.view_link import is_linked, sync_view

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


def register() -> None:
    bpy.app.handlers.depsgraph_update_post.append(_on_depsgraph_update)
    bpy.app.handlers.load_post.append(_on_load_post)
    _subscribe()


def unregister() -> None:
    bpy.msgbus.clear_by_owner(_MSGBUS_OWNER)
    for handlers, handler in ((bpy.app.handlers.load_post, _on_load_post),
                              (bpy.app.handlers.depsgraph_update_post, _on_depsgraph_update)):
        while handler in handlers:
            handlers.remove(handler)

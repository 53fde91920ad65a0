# SPDX-License-Identifier: GPL-3.0-or-later
"""The scene's state that applying a preset may change, kept to be put back when the apply fails
part-way (``apply.apply_preset_whole``): Blender does not undo what a cancelled operator did.
"""

from __future__ import annotations

import bpy

from ...core_tracer.scene import spec as S
from ..design import properties as design_properties

# What applying a preset may change besides the design.
_BLOCKS = ("objects", "cameras", "meshes", "materials", "collections", "images", "worlds", "lights", "node_groups")
_LENS = ("type", "lens", "sensor_width", "sensor_height", "sensor_fit", "shift_x", "shift_y", "clip_start",
         "clip_end", "ortho_scale")
_RENDER = ("engine", "resolution_x", "resolution_y", "resolution_percentage")
_VIEW = ("view_transform", "look", "exposure", "gamma")


def _plain(value):
    """An ID property's value as plain Python (groups and arrays copied, not referenced)."""
    if hasattr(value, "to_dict"):
        return value.to_dict()
    return value.to_list() if hasattr(value, "to_list") else value


class SceneState:
    """What applying a preset may change, kept to be put back when the apply fails part-way: the
    design, the scene's own custom properties, camera, world, render size and engine, colour
    management, the placement of its objects, the cameras' lenses, and which data-blocks exist
    (those made by the apply are removed)."""

    def __init__(self, bl_scene: bpy.types.Scene):
        self.design = design_properties.design_document(bl_scene)
        rna = bl_scene.bl_rna.properties
        self.custom = {key: _plain(bl_scene[key]) for key in bl_scene.keys() if key not in rna}
        self.camera, self.world = bl_scene.camera, bl_scene.world
        self.render = {key: getattr(bl_scene.render, key) for key in _RENDER}
        self.view = {key: getattr(bl_scene.view_settings, key) for key in _VIEW}
        self.placed = {ob.name: (ob.parent, ob.matrix_world.copy()) for ob in bl_scene.objects}
        self.lenses = {cam.name: {key: getattr(cam, key) for key in _LENS} for cam in bpy.data.cameras}
        self.blocks = {kind: {block.as_pointer() for block in getattr(bpy.data, kind)} for kind in _BLOCKS}

    def restore(self, bl_scene: bpy.types.Scene) -> None:
        for kind in _BLOCKS:  # objects first: they use the other data-blocks
            blocks = getattr(bpy.data, kind)
            for block in [b for b in blocks if b.as_pointer() not in self.blocks[kind]]:
                blocks.remove(block)
        for name, (parent, matrix) in self.placed.items():
            ob = bpy.data.objects.get(name)
            if ob is not None:
                ob.parent = parent
                ob.matrix_world = matrix
        for name, lens in self.lenses.items():
            cam = bpy.data.cameras.get(name)
            for key, value in (lens.items() if cam is not None else ()):
                setattr(cam, key, value)
        for key, value in self.render.items():
            setattr(bl_scene.render, key, value)
        for key, value in self.view.items():
            setattr(bl_scene.view_settings, key, value)
        bl_scene.camera, bl_scene.world = self.camera, self.world
        rna = bl_scene.bl_rna.properties
        for key in [k for k in bl_scene.keys() if k not in rna and k not in self.custom]:
            del bl_scene[key]
        for key, value in self.custom.items():
            bl_scene[key] = value
        design_properties.write_section(bl_scene.lamp_design, S.SCENE, self.design)

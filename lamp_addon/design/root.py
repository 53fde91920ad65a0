"""The design's root object: one Empty that carries the whole built lamp.

Every object the builder makes is parented to the root, so a designer moves the lamp, or parents it
to a car body, by moving or parenting the root. The tracer's model space is the root's local space
(in millimetres): a camera anywhere in the world sees the lamp the same way in Cycles and in the
tracer, wherever the root stands.

Objects the add-on made carry the custom property ``PART_KEY`` naming their part (``"root"``,
``"lamps[0].lens"``, ...); they are found by it, never by name, so the designer may rename them.
"""

from __future__ import annotations

import bpy
from mathutils import Matrix

PART_KEY = "lamp_part"
ROOT_PART = "root"
ROOT_NAME = "Lamp Design"
COLLECTION_NAME = "Lamp Design"


def find_root(bl_scene: bpy.types.Scene) -> bpy.types.Object | None:
    """The root object of the design built in ``bl_scene``, or None before the first build."""
    for obj in bl_scene.objects:
        if obj.get(PART_KEY) == ROOT_PART:
            return obj
    return None


def world_from_design(bl_scene: bpy.types.Scene) -> Matrix:
    """The matrix taking the design's model space (in Blender units) to the world: the root's
    world matrix, or the identity before the first build."""
    root = find_root(bl_scene)
    return root.matrix_world.copy() if root is not None else Matrix.Identity(4)

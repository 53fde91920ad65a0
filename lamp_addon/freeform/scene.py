"""The scene document of a design with free-form parts: the design from the Lamp panel plus a
``freeform`` section listing the scene's mesh objects with a role (``lamp-scene/2``).

The mesh file named in the section is what an export writes beside the JSON; inside Blender the
meshes come from the objects themselves (``freeform.meshes``) and the name is a placeholder.
"""

from __future__ import annotations

import bpy

from ...core_tracer.scene.reading import SceneError
from ...core_tracer.scene.validate import parse_scene
from ..design.camera import scene_for_render
from . import meshes as freeform_meshes
from . import parametric, properties

IN_BLENDER_MESH_FILE = "blender-objects.glb"  # the section needs a name; nothing is read from it


def freeform_section(objects, mesh_file: str = IN_BLENDER_MESH_FILE, built: tuple = ()) -> dict:
    """The ``freeform`` section of ``objects`` (mesh objects with a role) followed by the entries
    ``built`` of the parametric lamps traced with them (``freeform.parametric.part_documents``)."""
    return {"mesh_file": mesh_file,
            "parts": [properties.part_document(obj) for obj in objects] + list(built)}


def with_freeform(scene: dict, objects, mesh_file: str = IN_BLENDER_MESH_FILE, built: tuple = ()) -> dict:
    """``scene`` (a normalised design) with the free-form parts of ``objects`` and the entries ``built``
    of its parametric lamps, checked; raises ``SceneError`` naming the part's field when a role value
    is not allowed."""
    if not objects:
        return scene
    return parse_scene({**scene, "freeform": freeform_section(objects, mesh_file, built)})


def design_for_export(bl_scene: bpy.types.Scene, mesh_file: str, objects, built=()) -> tuple[dict, dict]:
    """The checked scene of an export (the design as F12 renders it: the scene camera's numbers as F12
    reads them, at the render size, with the parts and the built parametric parts ``built``) and their
    meshes; raises ``SceneError`` when there are no parts or something is not allowed."""
    if not objects:
        raise SceneError("freeform.parts", "no object has a lamp role; allowed 1 or more mesh objects with a role "
                                           "(Lamp tab, Free-form Parts, +)")
    depsgraph = bpy.context.evaluated_depsgraph_get()
    design = scene_for_render(bl_scene)
    scene = with_freeform(design, objects, mesh_file, parametric.part_documents(built, design))
    meshes = freeform_meshes.scene_meshes(bl_scene, depsgraph, objects)
    meshes.update(parametric.part_meshes(bl_scene, depsgraph, built))
    return scene, meshes

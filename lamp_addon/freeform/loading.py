"""A free-form design's parts brought into Blender: applying or importing a ``lamp-scene/2`` preset
with a ``freeform`` section makes one mesh object per part, with its role and values.

The meshes are read and checked by the core (``core_tracer.freeform.loading.load_meshes``: the .glb
beside the JSON, never outside its folder, within the size and triangle limits) *before* anything in
the scene changes, so a missing or hostile mesh file refuses the whole preset. The objects go into a
new collection "Lamp Free-form", in the design root's frame (children of the root when there is one),
with the file's normals as free custom normals (``normals_exporting_as``: the tracer inside Blender,
and Blender's exporter, give back the file's very numbers, so F12 equals the command line's render
pixel for pixel) and their role material, as Convert to Free-form makes them. The scene's other
objects, parts with roles included, are left as they are.
"""

from __future__ import annotations

import bpy
import numpy as np

from ..convert import units
from ..design import root as design_root
from . import materials, properties
from . import meshes as freeform_meshes

COLLECTION_NAME = "Lamp Free-form"


def read_parts(json_path: str, scene: dict) -> dict:
    """The parts' meshes of a loaded free-form scene by object name; raises ``SceneError``."""
    from ...core_tracer.freeform.loading import load_meshes

    meshes = load_meshes(json_path, scene)
    from ...core_tracer.freeform.geometry import part_meshes

    part_meshes(scene, meshes)  # every part names a mesh of the file
    return meshes


def _mesh(name: str, data) -> bpy.types.Mesh:
    mesh = bpy.data.meshes.new(name)
    verts = (np.asarray(data.vertices, np.float64) * units.BU_PER_MM).astype(np.float32)
    tris = np.asarray(data.triangles, np.int32)
    mesh.vertices.add(len(verts))
    mesh.vertices.foreach_set("co", verts.ravel())
    mesh.loops.add(3 * len(tris))
    mesh.loops.foreach_set("vertex_index", tris.ravel())
    mesh.polygons.add(len(tris))
    mesh.polygons.foreach_set("loop_start", np.arange(0, 3 * len(tris), 3, dtype=np.int32))
    mesh.update(calc_edges=True)
    mesh.validate(clean_customdata=False)
    if data.corner_normals is not None:
        # Free custom normals (a float ``custom_normal`` attribute), which Blender gives back as
        # stored; its encoded custom normals would move them by up to 1e-4 and average a fan's.
        normals = mesh.attributes.new("custom_normal", "FLOAT_VECTOR", "CORNER")
        normals.data.foreach_set("vector", freeform_meshes.normals_exporting_as(
            np.asarray(data.corner_normals).reshape(-1, 3)).ravel())
        mesh.update()
    return mesh


def make_parts(bl_scene: bpy.types.Scene, scene: dict, meshes: dict) -> list[str]:
    """One object per part of ``scene["freeform"]`` from ``meshes``; returns their names."""
    coll = bpy.data.collections.new(COLLECTION_NAME)
    bl_scene.collection.children.link(coll)
    root = design_root.find_root(bl_scene)
    made = []
    for part in scene["freeform"]["parts"]:
        name, role = part["object"], part["role"]
        obj = bpy.data.objects.new(name, _mesh(name, meshes[name]))
        coll.objects.link(obj)
        if root is not None:
            obj.parent = root  # model space is the root's frame: no transform of its own
        properties.set_role(obj, role, part[role])
        materials.give_role_material(obj)
        made.append(obj.name)
    return made

"""Convert to Free-form: the built parametric lamp as meshes with lamp roles, to reshape by hand.

Each mesh part the builder made (``design_root.PART_KEY``) is copied, as the viewport shows it
(the designer's modifiers applied), into a new collection "Lamp Free-form", parented to the design
root where the part stands, with the role and values its part has in the design: the lens as a
``lens`` (its glass: cut surface, outer face and the rim band between them, a closed solid) and a
``side_wall`` (the opaque rim of the parametric model, MODEL.md §3: from the outer face to the cut
apex plane), the reflector, bulb, socket and body as themselves. Each copy gets a role material
(``freeform_materials``) so that Cycles renders it as the tracer traces it.

The parametric lamp's own objects are hidden afterwards (viewport and render), since the copies
stand in their place; the designer's objects are never touched. Nothing is deleted: Undo takes
the conversion back, and unhiding the parametric objects shows them again.

The side wall lies ``SIDE_WALL_INSET_MM`` inside the lens rim, so that a ray travelling in the glass
meets the opaque wall, not the glass's own rim face, as in the parametric model where such a ray
ends at the side wall (Table 1 ⑦); the inset is well below the meshes' chord tolerance.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

import bmesh
import bpy
import numpy as np

from ..core_tracer.scene import spec as S
from ..core_tracer.scene.reading import SceneError
from . import design_builder, design_properties, design_root, freeform_materials, freeform_properties
from .convert import meshes, units

COLLECTION_NAME = "Lamp Free-form"
SUFFIX = " (Free-form)"
SIDE_WALL_INSET_MM = 0.005
_PART = re.compile(r"lamps\[(\d+)\]\.(lens|reflector|bulb|socket)$")


@dataclass
class ConvertReport:
    objects: list[str] = field(default_factory=list)
    hidden: list[str] = field(default_factory=list)
    built: bool = False  # the lamp was built (or brought up to date) first
    earlier_parts: int = 0  # parts with roles the scene had already (traced too)


def _values(role: str, source: dict) -> dict:
    """The role's values taken from a parametric section (same keys, same meaning)."""
    return {key: source[key] for key in S.FREEFORM_ROLE_SECTIONS[role].fields if key in source}


def _roles_of(part: str, scene: dict) -> list[tuple[str, dict]]:
    """(role, values) of the copies of built part ``part``: two for a lens, one otherwise."""
    if part == "body":
        return [("body", _values("body", scene["body"]))]
    m = _PART.match(part)
    if m is None:
        return []
    lamp = scene["lamps"][int(m[1])]
    kind = m[2]
    if kind == "lens":
        return [("lens", _values("lens", lamp["lens"])), ("side_wall", {"color": lamp["lens"]["side_wall_color"]})]
    return [(kind, _values(kind, lamp[kind]))]


def _keep_faces(mesh: bpy.types.Mesh, keep: np.ndarray) -> None:
    """Delete the faces of ``mesh`` where ``keep`` is False (and the vertices left without a face)."""
    bm = bmesh.new()
    bm.from_mesh(mesh)
    bm.faces.ensure_lookup_table()
    doomed = [f for f, k in zip(bm.faces, keep, strict=False) if not k]
    bmesh.ops.delete(bm, geom=doomed, context="FACES")
    bm.to_mesh(mesh)
    bm.free()


def _split_lens(mesh: bpy.types.Mesh) -> tuple[bpy.types.Mesh, bpy.types.Mesh]:
    """The lens mesh (axis frame, BU) as the closed glass and the side wall pushed inward."""
    n = len(mesh.polygons)
    material = np.empty(n, np.int32)
    mesh.polygons.foreach_get("material_index", material)
    co = np.empty(len(mesh.vertices) * 3, np.float32)
    mesh.vertices.foreach_get("co", co)
    co = co.reshape(-1, 3)
    # The glass's rim band is the side-wall quad touching the outer face (the lowest y): with it the
    # glass is watertight; the collar above the cut surface is open, so it stays with the wall only.
    y_outer = co[:, 1].min()
    starts = np.empty(n, np.int32)
    mesh.polygons.foreach_get("loop_start", starts)
    corner_vertex = np.empty(len(mesh.loops), np.int32)
    mesh.loops.foreach_get("vertex_index", corner_vertex)
    low = co[corner_vertex, 1] <= y_outer + 1e-9
    touches_outer = (material == meshes.LENS_SIDE_WALL) & np.logical_or.reduceat(low, starts)
    glass = mesh.copy()
    _keep_faces(glass, (material == meshes.LENS_GLASS) | touches_outer)
    wall = mesh.copy()
    _keep_faces(wall, material == meshes.LENS_SIDE_WALL)
    wco = np.empty(len(wall.vertices) * 3, np.float32)
    wall.vertices.foreach_get("co", wco)
    wco = wco.reshape(-1, 3).astype(np.float64)
    radius = np.hypot(wco[:, 0], wco[:, 2])
    scale = np.where(radius > 0, 1.0 - SIDE_WALL_INSET_MM * units.BU_PER_MM / np.maximum(radius, 1e-12), 1.0)
    wco[:, 0] *= scale
    wco[:, 2] *= scale
    wall.vertices.foreach_set("co", wco.astype(np.float32).ravel())
    wall.update()
    return glass, wall


def _collection(bl_scene: bpy.types.Scene) -> bpy.types.Collection:
    coll = bpy.data.collections.new(COLLECTION_NAME)  # a new one each time: earlier conversions stay
    bl_scene.collection.children.link(coll)
    return coll


def convert_to_freeform(bl_scene: bpy.types.Scene) -> ConvertReport:
    """Copy the built parametric lamp of ``bl_scene`` into free-form parts; raises ``SceneError`` when the
    design is not valid (nothing is changed then)."""
    report = ConvertReport(earlier_parts=len(freeform_properties.role_objects(bl_scene)))
    scene = design_properties.design_to_scene(bl_scene)  # raises SceneError before anything changes
    if not design_builder.is_up_to_date(bl_scene):
        design_builder.build_lamp(bl_scene, scene)
        report.built = True
    root = design_root.find_root(bl_scene)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    parts = sorted((obj for obj in bl_scene.objects
                    if obj.type == "MESH" and _roles_of(obj.get(design_root.PART_KEY, ""), scene)),
                   key=lambda obj: obj.get(design_root.PART_KEY))
    if not parts:
        raise SceneError("lamps", "no built lamp part was found to convert; allowed a design built with Build Lamp")
    coll = _collection(bl_scene)
    for obj in parts:
        roles = _roles_of(obj[design_root.PART_KEY], scene)
        mesh = bpy.data.meshes.new_from_object(obj.evaluated_get(depsgraph))
        if roles[0][0] == "lens":
            glass, wall = _split_lens(mesh)
            bpy.data.meshes.remove(mesh)
            made = [(glass, obj.name), (wall, obj.name.replace(" Lens", " Side Wall"))]
        else:
            made = [(mesh, obj.name)]
        for (data, name), (role, values) in zip(made, roles, strict=True):
            data.materials.clear()  # after the split, which reads the faces' material indices
            data.name = name + SUFFIX
            copy = bpy.data.objects.new(name + SUFFIX, data)
            coll.objects.link(copy)
            copy.parent = root
            copy.matrix_world = obj.matrix_world
            freeform_properties.set_role(copy, role, values)
            freeform_materials.give_role_material(copy)
            report.objects.append(copy.name)
        obj.hide_set(True)
        obj.hide_render = True
        report.hidden.append(obj.name)
    return report

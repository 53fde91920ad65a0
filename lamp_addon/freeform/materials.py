"""Cycles materials of free-form parts, made from their role values as the parametric parts' are
(``design.materials``), so that Compare shows Cycles the same lamp the tracer traces.

A role material is the add-on's own: it carries ``ROLE_MATERIAL_KEY`` (the object it belongs to) and
is named "<object> (Lamp Role)". It is given to an object only when asked (Assign Lamp Role's
"Cycles Material", Convert to Free-form), in a slot of its own at the end, and every face uses it;
``sync`` writes the role values into it again before Compare renders. A material the designer put
on the object is never changed: an object without a role material keeps its own, and Compare says so.
"""

from __future__ import annotations

import bpy
import numpy as np
from mathutils import Vector

from ..convert import units
from ..design import materials as design_materials
from . import properties

ROLE_MATERIAL_KEY = "lamp_role_material"


def _lamp_values(role: str, values: dict) -> dict:
    """The role values in the shape ``design.materials`` reads (a lamp's sections)."""
    if role == "lens":
        # The solid-view colour is the colour seen through the reference thickness (3 mm by default).
        return {"lens": {**values, "thickness": values.get("reference_thickness", 3.0)}}
    return {role: values}


def _drive(mat: bpy.types.Material, role: str, values: dict, new: bool, obj: bpy.types.Object | None = None
           ) -> list[str]:
    lamp = _lamp_values(role, values)
    if role == "lens":
        return design_materials.lens_glass(mat, lamp, new=new)
    if role == "reflector":
        bulb = reflector_bulb(obj) if obj is not None else None
        if bulb is None:  # no bulb part to aim at: the reflector keeps its lobe (design.materials)
            return design_materials.reflector(mat, lamp, new=new)
        centre, values = bulb
        return design_materials.reflector(mat, {**lamp, "bulb": values}, new=new, bulb_center=centre)
    if role == "bulb":
        return design_materials.bulb(mat, lamp, new=new)
    node = {"socket": "Socket BSDF", "side_wall": "Side Wall BSDF", "body": "Body BSDF"}[role]
    return design_materials.diffuse(mat, values["color"], node, new=new)


def role_material(obj: bpy.types.Object) -> bpy.types.Material | None:
    """The add-on's role material in one of ``obj``'s slots, or None."""
    for slot in obj.material_slots:
        if slot.material is not None and slot.material.get(ROLE_MATERIAL_KEY) == obj.name:
            return slot.material
    return None


def give_role_material(obj: bpy.types.Object) -> bpy.types.Material:
    """Make (or remake, when the role changed) the role material of ``obj`` and let every face use it."""
    role = obj.lamp_role.role
    mat = role_material(obj)
    new = mat is None or mat.get("lamp_role") != role  # a different role: a different node tree
    if mat is None:
        mat = bpy.data.materials.new(f"{obj.name} (Lamp Role)")
        mat[ROLE_MATERIAL_KEY] = obj.name
        obj.data.materials.append(mat)
    mat["lamp_role"] = role
    _drive(mat, role, properties.role_values(obj), new, obj)
    index = next(i for i, slot in enumerate(obj.material_slots) if slot.material == mat)
    mesh = obj.data
    mesh.polygons.foreach_set("material_index", [index] * len(mesh.polygons))
    mesh.update()
    return mat


def sync(bl_scene: bpy.types.Scene) -> list[str]:
    """Write the role values into every role material of the scene's parts; the names of parts that
    have none (Cycles renders them with their own materials)."""
    without = []
    for obj in properties.role_objects(bl_scene):
        mat = role_material(obj)
        if mat is None:
            without.append(obj.name)
        elif mat.get("lamp_role") != obj.lamp_role.role:
            give_role_material(obj)
        else:
            _drive(mat, obj.lamp_role.role, properties.role_values(obj), False, obj)
    return without


def _polygons_in_world(obj: bpy.types.Object) -> tuple[np.ndarray, np.ndarray]:
    """The object's polygon centres and areas in world coordinates (Blender units)."""
    mesh = obj.data
    n = len(mesh.polygons)
    centres, areas = np.zeros(n * 3), np.zeros(n)
    mesh.polygons.foreach_get("center", centres)
    mesh.polygons.foreach_get("area", areas)
    matrix = np.array(obj.matrix_world)
    centres = centres.reshape(-1, 3) @ matrix[:3, :3].T + matrix[:3, 3]
    scale = abs(np.linalg.det(matrix[:3, :3])) ** (2.0 / 3.0)  # areas under a uniform scale
    return centres, areas * scale


def reflector_bulb(obj: bpy.types.Object) -> tuple[list[float], dict] | None:
    """The bulb part the free-form reflector ``obj`` scatters toward, as the tracer chooses it
    (``core_tracer.freeform.roles``: a bulb whose centre, its surface's area-weighted centroid, lies in
    the reflector's bounding box, else the nearest): its centre in the reflector object's own frame (mm)
    and its role values. With several in the box, the brightest (the Cycles emission aims at one bulb).
    None without a bulb part in the scene."""
    scenes = obj.users_scene
    bulbs = [b for b in properties.role_objects(scenes[0]) if b.lamp_role.role == "bulb" and b.type == "MESH"
             and len(b.data.polygons)] if scenes else []
    if not bulbs or obj.type != "MESH" or not len(obj.data.vertices):
        return None
    centres = []
    for b in bulbs:
        c, a = _polygons_in_world(b)
        centres.append((c * a[:, None]).sum(axis=0) / max(a.sum(), 1e-300))
    centres = np.array(centres)
    corners = np.array([obj.matrix_world @ Vector(v.co) for v in obj.data.vertices])
    lo, hi = corners.min(axis=0), corners.max(axis=0)
    inside = np.flatnonzero(np.all((centres >= lo) & (centres <= hi), axis=1))
    if len(inside):
        values = [properties.role_values(bulbs[i]) for i in inside]
        pick = inside[int(np.argmax([max(v["intensity"]) if v["on"] else 0.0 for v in values]))]
    else:
        pick = int(np.argmin(np.linalg.norm(centres - (lo + hi) / 2, axis=1)))
    local = obj.matrix_world.inverted() @ Vector(centres[pick].tolist())
    return [c / units.BU_PER_MM for c in local], properties.role_values(bulbs[pick])

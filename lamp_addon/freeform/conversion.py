"""Convert to Free-form: the built parametric lamp as meshes with lamp roles, to reshape by hand.

Each mesh part the builder made (``design.root.PART_KEY``) is copied, as the viewport shows it
(the designer's modifiers applied), into a new collection "Lamp Free-form", parented to the design
root where the part stands, with the role and values its part has in the design: the lens as a
``lens`` (its glass: cut surface, outer face and the rim band between them, a closed solid) and a
``side_wall`` (the opaque rim of the parametric model, docs/model.md §3: from the outer face to the cut
apex plane or the reflector's edge), a prism plate as a ``lens`` (its glass closed at the rim, the
plate's index and absorption) and its housing as a ``side_wall`` (it ends a path with its colour,
⑲), the reflector, bulb, socket and body as themselves. Each copy gets a role material
(``freeform.materials``) so that Cycles renders it as the tracer traces it. How the meshes are made
into solids and walls is ``freeform.solids``. The meshes are made finer than Build's for this
(``convert.meshes.builder.tolerances``: chord 0.0125 mm, cut surfaces 0.0025 mm, issue 32) and the parts
built again to Build's afterwards, so that the free-form lamp traces as the parametric one does (the
photometric stop lamp's lit lens within 0.5 %, its R148 grid within 1 %: benchmarks/RESULTS.md).

The parametric lamp's own objects are hidden afterwards (viewport and render), since the copies
stand in their place; the designer's objects are never touched. Nothing is deleted: Undo takes
the conversion back, and unhiding the parametric objects shows them again.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

import bpy

from ...core_tracer.scene import spec as S
from ...core_tracer.scene.reading import SceneError
from ..convert.meshes import builder as mesh_builder
from ..design import builder as design_builder
from ..design import properties as design_properties
from ..design import root as design_root
from . import materials, properties, solids

COLLECTION_NAME = "Lamp Free-form"
SUFFIX = " (Free-form)"
_PART = re.compile(r"lamps\[(\d+)\]\.(lens|reflector|bulb|socket|prism_plate|housing)$")


@dataclass
class ConvertReport:
    objects: list[str] = field(default_factory=list)
    hidden: list[str] = field(default_factory=list)
    built: bool = False  # the lamp was built (or brought up to date) first
    earlier_parts: int = 0  # parts with roles the scene had already (traced too)


def _values(role: str, source: dict) -> dict:
    """The role's values taken from a parametric section (same keys, same meaning)."""
    return {key: source[key] for key in S.FREEFORM_ROLE_SECTIONS[role].fields if key in source}


def is_convertible(part: str) -> bool:
    """Whether built part ``part`` (its ``PART_KEY``) becomes free-form parts."""
    return part == "body" or _PART.match(part) is not None


def roles_of(part: str, scene: dict) -> list[tuple[str, dict]]:
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
    if kind == "prism_plate":  # glass with the plate's index and absorption; no shading of its own
        plate = lamp["prism_plate"]
        return [("lens", {"ior": plate["ior"], "absorption": plate["absorption"], "diffuse_color": (0.0, 0.0, 0.0),
                          "specular": 0.0, "shininess": lamp["lens"]["shininess"]})]
    if kind == "housing":  # ends a path with its colour (⑲), in the side wall's pass as the tracer's
        return [("side_wall", {"color": lamp["prism_plate"]["housing_color"]})]
    return [(kind, _values(kind, lamp[kind]))]


def _collection(bl_scene: bpy.types.Scene) -> bpy.types.Collection:
    coll = bpy.data.collections.new(COLLECTION_NAME)  # a new one each time: earlier conversions stay
    bl_scene.collection.children.link(coll)
    return coll


def convert_to_freeform(bl_scene: bpy.types.Scene) -> ConvertReport:
    """Copy the built parametric lamp of ``bl_scene`` into free-form parts; raises ``SceneError`` when the
    design is not valid (nothing is changed then)."""
    report = ConvertReport(earlier_parts=len(properties.role_objects(bl_scene)))
    scene = design_properties.design_to_scene(bl_scene)  # raises SceneError before anything changes
    report.built = not design_builder.is_up_to_date(bl_scene)
    with mesh_builder.tolerances(mesh_builder.FREEFORM_CHORD_TOLERANCE_MM, mesh_builder.FREEFORM_CUT_TOLERANCE_MM):
        design_builder.build_lamp(bl_scene, scene)
    root = design_root.find_root(bl_scene)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    parts = sorted((obj for obj in bl_scene.objects
                    if obj.type == "MESH" and roles_of(obj.get(design_root.PART_KEY, ""), scene)),
                   key=lambda obj: obj.get(design_root.PART_KEY))
    if not parts:
        raise SceneError("lamps", "no built lamp part was found to convert; allowed a design built with Build Lamp")
    meshes = [bpy.data.meshes.new_from_object(obj.evaluated_get(depsgraph)) for obj in parts]
    design_builder.build_lamp(bl_scene, scene)  # the parametric parts back to Build's tolerances
    coll = _collection(bl_scene)
    for obj, mesh in zip(parts, meshes, strict=True):
        roles = roles_of(obj[design_root.PART_KEY], scene)
        kind = obj[design_root.PART_KEY].rsplit(".", 1)[-1]
        if kind == "lens":
            glass, wall = solids.split_lens(mesh)
            bpy.data.meshes.remove(mesh)
            made = [(glass, obj.name), (wall, obj.name.replace(" Lens", " Side Wall"))]
        else:
            if kind == "prism_plate":
                solids.close_plate(mesh)
            elif kind == "housing":
                solids.inset(mesh)
            made = [(mesh, obj.name)]
        for (data, name), (role, values) in zip(made, roles, strict=True):
            data.materials.clear()  # after the split, which reads the faces' material indices
            data.name = name + SUFFIX
            copy = bpy.data.objects.new(name + SUFFIX, data)
            coll.objects.link(copy)
            copy.parent = root
            copy.matrix_world = obj.matrix_world
            properties.set_role(copy, role, values)
            materials.give_role_material(copy)
            report.objects.append(copy.name)
        obj.hide_set(True)
        obj.hide_render = True
        report.hidden.append(obj.name)
    return report

"""Lamp roles on the designer's own mesh objects (``Object.lamp_role``), generated from the core spec.

Any mesh object can be a free-form part of the lamp: a lens, reflector, bulb, socket, side wall or
body, with that role's values. The value groups are made from ``spec.FREEFORM_ROLE_SECTIONS`` exactly
as the design's properties are made from ``spec.SCENE`` (``design.properties.make_groups``), so names,
ranges, defaults and the lens's either/or colour follow the declaration; the role itself is an enum
(``NONE`` = not part of the lamp). Every role's group exists on every object, so switching a role and
back keeps the values the designer set.

The parts of a scene are its mesh objects with a role (``role_objects``); ``part_document`` is one
entry of the ``lamp-scene/2`` document's ``freeform.parts`` list, named by the object's name (the
name the glTF exporter gives its mesh node).
"""

from __future__ import annotations

import bpy
from bpy.props import EnumProperty, IntProperty, PointerProperty

from ...core_tracer.scene import spec as S
from ..design import properties as design_properties

NONE = "NONE"
ROLES = S.FREEFORM_ROLES
ROLE_ICONS = {"lens": "SHADING_RENDERED", "reflector": "MOD_MIRROR", "bulb": "LIGHT_POINT",
              "socket": "MESH_CYLINDER", "side_wall": "MESH_TUBE", "body": "MESH_CUBE"}


def role_label(role: str) -> str:
    return design_properties.display_name(role)


def _role_changed(self, context) -> None:
    obj = self.id_data
    if isinstance(obj, bpy.types.Object):
        obj.update_tag()  # the engine's depsgraph update sees the changed role


_value_groups: list[type] = []
_role_pointers = {
    role: PointerProperty(type=design_properties.make_groups(section, f"LAMP_PG_role_{role}", _value_groups),
                          name=role_label(role), description=section.doc)
    for role, section in S.FREEFORM_ROLE_SECTIONS.items()
}


class LAMP_PG_object_role(bpy.types.PropertyGroup):
    """What a mesh object is in the lamp, and the values of each role."""

    __annotations__ = {
        "role": EnumProperty(
            name="Lamp Role", default=NONE, update=_role_changed,
            description="What this mesh is in the lamp traced by the Lamp Tracer (None: not part of it)",
            items=((NONE, "None", "Not part of the lamp"),
                   *((role, role_label(role), S.FREEFORM_ROLE_SECTIONS[role].doc) for role in ROLES))),
        **_role_pointers,
    }


def has_role(obj) -> bool:
    return obj is not None and obj.type == "MESH" and obj.lamp_role.role != NONE


def role_objects(bl_scene: bpy.types.Scene) -> list[bpy.types.Object]:
    """The scene's mesh objects with a lamp role, by name (the order of ``freeform.parts``)."""
    return sorted((obj for obj in bl_scene.objects if has_role(obj)), key=lambda obj: obj.name)


def role_values(obj: bpy.types.Object) -> dict:
    """The values of the object's role as a document section."""
    role = obj.lamp_role.role
    return design_properties.read_section(getattr(obj.lamp_role, role), S.FREEFORM_ROLE_SECTIONS[role])


def part_document(obj: bpy.types.Object) -> dict:
    """One ``freeform.parts`` entry: the object's name, its role and the role's values."""
    role = obj.lamp_role.role
    return {"object": obj.name, "role": role, role: role_values(obj)}


def set_role(obj: bpy.types.Object, role: str, values: dict | None = None) -> None:
    """Give ``obj`` the ``role`` (``NONE`` clears it), and set the role's values from ``values``."""
    obj.lamp_role.role = role
    if values and role != NONE:
        design_properties.write_section(getattr(obj.lamp_role, role), S.FREEFORM_ROLE_SECTIONS[role], values)


def _attach(cls) -> None:
    bpy.types.Object.lamp_role = PointerProperty(type=cls, name="Lamp Role",
                                                 description="The object's role in the free-form lamp")
    # The row of the role list that is selected (the list shows the objects with a role).
    bpy.types.Scene.lamp_role_index = IntProperty(name="Active Role Object", min=0, default=0)


def _detach(cls) -> None:
    del bpy.types.Scene.lamp_role_index
    del bpy.types.Object.lamp_role


LAMP_PG_object_role.register = classmethod(_attach)
LAMP_PG_object_role.unregister = classmethod(_detach)

classes = (*_value_groups, LAMP_PG_object_role)

register, unregister = bpy.utils.register_classes_factory(classes)

"""The "Free-form Parts" sub-panel of the Lamp tab: the scene's mesh objects with a lamp role in a
list, buttons to assign and clear roles, and the values of the selected part's role.

The values are drawn from the role's spec section (``spec.FREEFORM_ROLE_SECTIONS``) as the design's
sections are (``design.panels``), so a field added to a role shows up here by itself. When the ray
queries are missing (``core_tracer.freeform.available``) the panel says so in words, once, at its top.
"""

from __future__ import annotations

import bpy

from ...core_tracer.scene import light_models
from ...core_tracer.scene import spec as S
from ..design import panels as design_panels
from ..design import validity as design_validity
from . import properties, status
from .properties import ROLE_ICONS, role_label

_NO_STATUS = design_validity.Status(None, {})  # role values carry no cross-field limits
SHOWN = 1 << 30  # UIList.bitflag_filter_item (UILST_FLT_ITEM): the item passes the filter


class LAMP_UL_role_objects(bpy.types.UIList):
    """The scene's objects, filtered to the mesh objects with a lamp role, by name."""

    def draw_item(self, context, layout, data, item, icon, active_data, active_propname, index=0, flt_flag=0):
        role = item.lamp_role.role
        row = layout.row(align=True)
        row.label(text=item.name, icon=ROLE_ICONS.get(role, "OBJECT_DATA"))
        row.label(text=role_label(role))

    def filter_items(self, context, data, propname):
        objects = getattr(data, propname)
        flags = [SHOWN if properties.has_role(obj) else 0 for obj in objects]
        order = bpy.types.UI_UL_list.sort_items_by_name(objects, "name")
        return flags, order


def selected_part(context):
    """The object selected in the role list, if it still has a role."""
    objects = context.scene.objects
    index = context.scene.lamp_role_index
    obj = objects[index] if 0 <= index < len(objects) else None
    return obj if properties.has_role(obj) else None


def draw_role_values(layout, obj, light_model: str = "paper") -> None:
    """The role of ``obj`` and its values, the lens colour as its either/or row: the fields the
    design's ``light_model`` uses and the role's choices call for, as the parametric parts' panels."""
    layout.prop(obj.lamp_role, "role")
    role = obj.lamp_role.role
    section = S.FREEFORM_ROLE_SECTIONS[role]
    group = getattr(obj.lamp_role, role)

    def value_of(key):
        return getattr(group, key)

    for key in design_panels.leaf_keys(section):
        if section.shown(key, value_of) and light_models.used(section, key, light_model, value_of):
            layout.prop(group, key)
    for rule in section.one_of:
        if any(light_models.used(section, key, light_model, value_of) for key in rule.keys):
            design_panels.draw_rule(layout, group, rule, _NO_STATUS)


class LAMP_PT_freeform(design_panels.DesignSection, bpy.types.Panel):
    bl_label = "Free-form Parts"
    bl_order = 5

    def draw(self, context):
        layout = self.layout
        for line in status.panel_lines(context.scene):
            layout.label(text=line.text, icon=line.icon)
        row = layout.row()
        row.template_list("LAMP_UL_role_objects", "", context.scene, "objects", context.scene, "lamp_role_index",
                          rows=3)
        col = row.column(align=True)
        col.operator_menu_enum("lamp.role_assign", "role", text="", icon="ADD")
        obj = selected_part(context)
        clear = col.operator("lamp.role_clear", text="", icon="REMOVE")
        clear.object_name = obj.name if obj is not None else ""
        if obj is not None:
            draw_role_values(design_panels.LampTab._split(layout.column()), obj,
                             context.scene.lamp_design.light_model)
        elif not properties.role_objects(context.scene):
            layout.label(text="Select mesh objects and give them a role with +", icon="INFO")
        col = layout.column(align=True)
        col.operator("lamp.freeform_convert", icon="MOD_REMESH")
        col.operator("lamp.freeform_export", icon="EXPORT")


classes = (LAMP_UL_role_objects, LAMP_PT_freeform)

register, unregister = bpy.utils.register_classes_factory(classes)

"""Free-form operators: give the selected mesh objects a lamp role or take it away, convert the
built parametric lamp to free-form parts, export the design for headless use.

Assigning a role changes only the role, and, when "Cycles Material" is ticked (it is by default, and
the report says so), adds the role's material in a slot of its own so that Cycles shows what the
tracer traces; the mesh and transform stay as the designer made them. Objects the parametric builder
made (``design.root.PART_KEY``) are refused: the builder owns them and the parametric tracer already
traces them; Convert to Free-form makes free-form copies of them instead.
"""

from __future__ import annotations

import bpy
from bpy.props import BoolProperty, EnumProperty, StringProperty
from bpy_extras.io_utils import ExportHelper

from ...core_tracer import fileio
from ...core_tracer.scene.reading import SceneError
from .. import reports
from ..design import root as design_root
from ..design.operator import DesignOperator
from . import conversion, export, materials, properties
from .properties import NONE, ROLES, role_label

_ROLE_ITEMS = tuple((role, role_label(role), "") for role in ROLES)


def _candidates(context) -> list[bpy.types.Object]:
    objects = list(context.selected_objects or ())
    active = context.active_object
    if active is not None and active not in objects and active.select_get():
        objects.append(active)
    return objects


class LAMP_OT_role_assign(bpy.types.Operator):
    bl_idname = "lamp.role_assign"
    bl_label = "Assign Lamp Role"
    bl_description = "Make the selected mesh objects a free-form part of the lamp with this role"
    bl_options = {"REGISTER", "UNDO"}

    role: EnumProperty(name="Role", items=_ROLE_ITEMS, default="lens")
    material: BoolProperty(name="Cycles Material", default=True,
                           description="Add the role's Cycles material (a slot of its own, used by every face), so "
                                       "that Cycles and Compare render the part as the Lamp Tracer does")

    @classmethod
    def poll(cls, context):
        if not any(obj.type == "MESH" for obj in _candidates(context)):
            cls.poll_message_set("Select one or more mesh objects")
            return False
        return True

    def execute(self, context):
        given, skipped = [], []
        for obj in _candidates(context):
            if obj.type != "MESH":
                skipped.append(f"{obj.name} (not a mesh)")
            elif obj.get(design_root.PART_KEY) is not None:
                skipped.append(f"{obj.name} (built from the parametric design: use Convert to Free-form)")
            else:
                properties.set_role(obj, self.role)
                if self.material:
                    materials.give_role_material(obj)
                given.append(obj.name)
        if not given:
            reports.say(self, "ERROR", "No role given: " + "; ".join(skipped))
            return {"CANCELLED"}
        text = f"{role_label(self.role)}: " + ", ".join(given)
        if self.material:
            text += " (with the role's Cycles material)"
        if skipped:
            reports.say(self, "WARNING", text + "; skipped " + "; ".join(skipped))
        else:
            reports.say(self, "INFO", text)
        return {"FINISHED"}


class LAMP_OT_role_clear(bpy.types.Operator):
    bl_idname = "lamp.role_clear"
    bl_label = "Clear Lamp Role"
    bl_description = "Take the lamp role away (the object stays as it is, no longer traced as part of the lamp)"
    bl_options = {"REGISTER", "UNDO"}

    object_name: StringProperty(name="Object", description="The object to clear (empty: the selected objects)")

    def _targets(self, context) -> list[bpy.types.Object]:
        if self.object_name:
            obj = context.scene.objects.get(self.object_name)
            return [obj] if obj is not None else []
        return [obj for obj in _candidates(context) if properties.has_role(obj)]

    def execute(self, context):
        targets = [obj for obj in self._targets(context) if properties.has_role(obj)]
        if not targets:
            reports.say(self, "ERROR", f'"{self.object_name}" has no lamp role' if self.object_name
                        else "No selected object has a lamp role")
            return {"CANCELLED"}
        for obj in targets:
            properties.set_role(obj, NONE)
        reports.say(self, "INFO", "Cleared the role of " + ", ".join(obj.name for obj in targets))
        return {"FINISHED"}


def _error_text(e: Exception) -> str:
    """One line: an ``OSError`` as "<file>: <reason>", anything else as its text."""
    if isinstance(e, OSError) and e.strerror:
        return f"{e.filename}: {e.strerror}" if e.filename else e.strerror
    return str(e)


class LAMP_OT_freeform_convert(DesignOperator, bpy.types.Operator):
    bl_idname = "lamp.freeform_convert"
    bl_label = "Convert to Free-form"
    bl_description = ("Copy the built lamp into meshes with lamp roles (collection \"Lamp Free-form\") to reshape "
                      "by hand; the parametric parts are hidden, nothing is deleted")
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def refusal(cls, context):
        if not context.scene.lamp_design.lamps:
            return "No lamp to convert: add one or apply a preset"
        return None

    def execute(self, context):
        try:
            report = conversion.convert_to_freeform(context.scene)
        except SceneError as e:
            return self.cancelled(f"Not converted: {e}")
        built = "built the lamp, then " if report.built else ""
        text = f"Converted: {built}made {len(report.objects)} free-form parts"
        hidden = f"Hid the {len(report.hidden)} parametric parts they stand in for"
        if report.earlier_parts:
            reports.details(self, [hidden, "Take the earlier parts' roles away if they are an earlier copy"])
            reports.say(self, "WARNING", f"{text}; the {report.earlier_parts} parts the scene had already are traced "
                                         "too")
            return {"FINISHED"}
        return reports.finished(self, f"{text}; {hidden[:1].lower()}{hidden[1:]}")


class LAMP_OT_freeform_export(bpy.types.Operator, ExportHelper):
    bl_idname = "lamp.freeform_export"
    bl_label = "Export Free-form Design"
    bl_description = ("Write the design with its free-form parts as a lamp-scene/2 JSON and a .glb beside it, "
                      "for python -m core_tracer render")
    bl_options = {"REGISTER"}

    filename_ext = ".json"
    filter_glob: StringProperty(default="*.json", options={"HIDDEN"})
    replace: BoolProperty(name="Replace Existing", default=False,
                          description="Replace the JSON and .glb if they exist already")

    @classmethod
    def poll(cls, context):
        if context.scene is None or not properties.role_objects(context.scene):
            cls.poll_message_set("No object has a lamp role")
            return False
        return True

    def execute(self, context):
        try:
            report = export.export_pair(context.scene, self.filepath, overwrite=self.replace)
        except fileio.TargetExistsError as e:
            return reports.cancelled(self, f"Not exported: {e.filename} exists already; tick Replace Existing")
        except (SceneError, OSError) as e:
            return reports.cancelled(self, f"Not exported: {_error_text(e)}")
        return reports.finished(self, f"Exported {report.parts} parts ({report.triangles} triangles) to "
                                      f"{report.json_path} and {report.glb_path}")


classes = (LAMP_OT_role_assign, LAMP_OT_role_clear, LAMP_OT_freeform_convert, LAMP_OT_freeform_export)

register, unregister = bpy.utils.register_classes_factory(classes)

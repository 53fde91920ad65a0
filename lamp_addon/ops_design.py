"""Operators that edit the design: add and remove lamps, build the lamp as objects."""

from __future__ import annotations

import bpy

from ..core_tracer import spec
from ..core_tracer.scene import SceneError


class LAMP_OT_lamp_add(bpy.types.Operator):
    bl_idname = "lamp.lamp_add"
    bl_label = "Add Lamp"
    bl_description = f"Add a lamp with default values to the design (at most {spec.MAX_LAMPS})"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        if context.scene is None:
            return False
        if len(context.scene.lamp_design.lamps) >= spec.MAX_LAMPS:
            cls.poll_message_set(f"A design has at most {spec.MAX_LAMPS} lamps")
            return False
        return True

    def execute(self, context):
        design = context.scene.lamp_design
        lamp = design.lamps.add()
        center = free_lamp_center(design, lamp.lens.radius)
        if center is not None:
            lamp.center = center
        design.active_lamps_index = len(design.lamps) - 1
        return {"FINISHED"}


def free_lamp_center(design, radius: float, step: float = 5.0) -> tuple[float, float] | None:
    """The free place nearest the body centre for a new lens of ``radius`` (mm), or None if there is none."""
    bx, bz = design.body.center
    w, h = design.body.size
    others = [(tuple(lamp.center), lamp.lens.radius) for lamp in design.lamps[:-1]]
    nx, nz = int((w / 2 - radius) // step), int((h / 2 - radius) // step)
    candidates = sorted(((i * step, j * step) for i in range(-nx, nx + 1) for j in range(-nz, nz + 1)),
                        key=lambda c: (c[0] ** 2 + c[1] ** 2, c))
    for dx, dz in candidates:
        x, z = bx + dx, bz + dz
        if all((x - ox) ** 2 + (z - oz) ** 2 >= (radius + r) ** 2 for (ox, oz), r in others):
            return (x, z)
    return None


class LAMP_OT_lamp_remove(bpy.types.Operator):
    bl_idname = "lamp.lamp_remove"
    bl_label = "Remove Lamp"
    bl_description = "Remove the selected lamp from the design"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        if context.scene is None:
            return False
        design = context.scene.lamp_design
        if not 0 <= design.active_lamps_index < len(design.lamps):
            cls.poll_message_set("No lamp is selected")
            return False
        if len(design.lamps) <= 1:
            cls.poll_message_set("A design needs at least one lamp")
            return False
        return True

    def execute(self, context):
        design = context.scene.lamp_design
        design.lamps.remove(design.active_lamps_index)
        design.active_lamps_index = min(design.active_lamps_index, len(design.lamps) - 1)
        return {"FINISHED"}


class LAMP_OT_build(bpy.types.Operator):
    bl_idname = "lamp.build"
    bl_label = "Build Lamp"
    bl_description = ("Build the design as objects in the \"Lamp Design\" collection, replacing the "
                      "previous build")
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        if context.scene is None:
            return False
        if context.mode != "OBJECT":
            cls.poll_message_set("Switch to Object Mode first")
            return False
        if not context.scene.lamp_design.lamps:
            cls.poll_message_set("Add a lamp first")
            return False
        return True

    def execute(self, context):
        from . import builder, properties

        try:
            scene = properties.design_to_scene(context.scene)
        except SceneError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        report = builder.build_lamp(context.scene, scene)
        level = "WARNING" if report.worst_deviation > report.tolerance else "INFO"
        self.report({level}, f"Built {len(report.objects)} objects; largest deviation from the model "
                             f"{report.worst_deviation:.3f} mm (tolerance {report.tolerance:g} mm)")
        return {"FINISHED"}


classes = (
    LAMP_OT_lamp_add,
    LAMP_OT_lamp_remove,
    LAMP_OT_build,
)


def register() -> None:
    for cls in classes:
        bpy.utils.register_class(cls)


def unregister() -> None:
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)

"""Operators that edit the design: add and remove lamps, build the lamp as objects.

Add Lamp keeps a valid design valid: the new lamp is a copy of the active one (the spec's default
lamp in an empty design), placed right of the others with a small margin, and the body grows to
hold it. When the result would not be a valid design (a body wider than the spec allows), poll and
execute refuse, naming the field and its allowed range.
"""

from __future__ import annotations

import copy

import bpy

from ..core_tracer.scene import spec
from ..core_tracer.scene.validate import SceneError, parse_scene
from . import design_properties, render_camera

MARGIN_MM = 5.0  # between a new lens and its neighbour, and at least between it and the body's edge


class LAMP_OT_lamp_add(bpy.types.Operator):
    bl_idname = "lamp.lamp_add"
    bl_label = "Add Lamp"
    bl_description = (f"Add a copy of the active lamp right of the others (at most {spec.MAX_LAMPS} lamps; the "
                      "first one with default values); the body grows to hold it")
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        if not design_properties.poll_design(cls, context):
            return False
        if len(context.scene.lamp_design.lamps) >= spec.MAX_LAMPS:
            cls.poll_message_set(f"A design has at most {spec.MAX_LAMPS} lamps")
            return False
        refusal = _add_refusal(context.scene)
        if refusal is not None:
            cls.poll_message_set(refusal)
            return False
        return True

    def execute(self, context):
        design = context.scene.lamp_design
        try:
            doc = design_with_new_lamp(design_properties.design_document(context.scene), design.active_lamps_index)
        except SceneError as e:
            self.report({"ERROR"}, f"Cannot add a lamp: {e}")
            return {"CANCELLED"}
        design_properties.set_lamp(design.lamps.add(), doc["lamps"][-1])
        design.body.center = doc["body"]["center"]
        design.body.size = doc["body"]["size"]
        design.active_lamps_index = len(design.lamps) - 1
        render_camera.keep_framed(context.scene)
        return {"FINISHED"}


_refusal_memo: dict = {"key": None, "refusal": None}  # the last design poll checked, and its answer


def _add_refusal(bl_scene) -> str | None:
    """Why a lamp cannot be added to the scene's design, or None. Checking a design takes
    milliseconds and poll runs at every redraw of the panel, so the answer is kept until the
    design changes."""
    key = (design_properties.design_document(bl_scene), bl_scene.lamp_design.active_lamps_index)
    if _refusal_memo["key"] != key:
        try:
            design_with_new_lamp(*key)
            refusal = None
        except SceneError as e:
            refusal = f"Cannot add a lamp: {e}"
        _refusal_memo.update(key=key, refusal=refusal)
    return _refusal_memo["refusal"]


def design_with_new_lamp(doc: dict, active_index: int) -> dict:
    """A copy of the design document ``doc`` with a lamp added by ``place_new_lamp``: a copy of
    the active lamp (so its lens radius, and a reflector and bulb that fit that lens), or the
    spec's default lamp in an empty design. Raises ``SceneError`` (field and allowed range) when
    the result is not a valid design, checked as ``parse_scene`` does, camera aside (a new lamp
    does not change what the camera may be)."""
    doc = copy.deepcopy(doc)
    lamps = doc["lamps"]
    if 0 <= active_index < len(lamps):
        lamps.append(copy.deepcopy(lamps[active_index]))
    else:
        lamps.append(parse_scene({"schema": spec.SCHEMA, "lamps": [{}]})["lamps"][0])
    place_new_lamp(doc)
    parse_scene({key: value for key, value in doc.items() if key != "camera"})
    return doc


def place_new_lamp(doc: dict, margin: float = MARGIN_MM) -> None:
    """Place the last lamp of the design document ``doc`` and make the body hold it (in place).

    The new lens goes ``margin`` to the right of the rightmost lens, at its own height ``center[1]``
    (the first lamp at the body's centre). The body keeps its other edges and grows on each side the
    new lens needs, leaving beside it the free border the body has left of its leftmost lens (at
    least ``margin``), so the body's centre moves as it grows."""
    *others, new = doc["lamps"]
    radius = new["lens"]["radius"]
    body = doc["body"]
    (bx, bz), (width, height) = body["center"], body["size"]
    left, right, bottom, top = bx - width / 2, bx + width / 2, bz - height / 2, bz + height / 2
    if others:
        x = max(o["center"][0] + o["lens"]["radius"] for o in others) + margin + radius
        z = new["center"][1]
        border = max(margin, min(o["center"][0] - o["lens"]["radius"] for o in others) - left)
    else:
        x, z, border = bx, bz, margin
    new["center"] = [x, z]
    left, right = min(left, x - radius - border), max(right, x + radius + border)
    bottom, top = min(bottom, z - radius - margin), max(top, z + radius + margin)
    body["center"] = [(left + right) / 2, (bottom + top) / 2]
    body["size"] = [right - left, top - bottom]


class LAMP_OT_lamp_remove(bpy.types.Operator):
    bl_idname = "lamp.lamp_remove"
    bl_label = "Remove Lamp"
    bl_description = "Remove the selected lamp from the design"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        if not design_properties.poll_design(cls, context):
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
        render_camera.keep_framed(context.scene)
        return {"FINISHED"}


class LAMP_OT_build(bpy.types.Operator):
    bl_idname = "lamp.build"
    bl_label = "Build Lamp"
    bl_description = ("Build the design as objects in the \"Lamp Design\" collection, replacing the "
                      "previous build")
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        if not design_properties.poll_design(cls, context):
            return False
        if context.mode != "OBJECT":
            cls.poll_message_set("Switch to Object Mode first")
            return False
        if not context.scene.lamp_design.lamps:
            cls.poll_message_set("Add a lamp first")
            return False
        return True

    def execute(self, context):
        from . import design_builder

        try:
            scene = design_properties.design_to_scene(context.scene)
        except SceneError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        report = design_builder.build_lamp(context.scene, scene)
        camera_news = render_camera.camera_after_build(context.scene)
        level = "WARNING" if report.worst_deviation > report.tolerance else "INFO"
        self.report({level}, f"Built {len(report.objects)} objects; largest deviation from the model "
                             f"{report.worst_deviation:.3f} mm (tolerance {report.tolerance:g} mm)"
                             + (f"; {camera_news}" if camera_news else ""))
        return {"FINISHED"}


classes = (
    LAMP_OT_lamp_add,
    LAMP_OT_lamp_remove,
    LAMP_OT_build,
)


register, unregister = bpy.utils.register_classes_factory(classes)

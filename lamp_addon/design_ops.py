"""Operators that edit the design: add and remove lamps, build the lamp as objects.

Add Lamp keeps a valid design valid: the new lamp is a copy of the active one (the spec's default
lamp in an empty design, in the preferred forms: the lens colour picker), placed right of the
others with a small margin, and the body grows to hold it. Only adding itself is refused (four
lamps already, a body wider than the spec allows), by poll and execute alike, naming the field and
its allowed range; an error the design has anyway is the panel's to show and does not block it.
"""

from __future__ import annotations

import copy

import bpy

from ..core_tracer.scene import spec
from ..core_tracer.scene.validate import SceneError, new_lamp, parse_scene
from . import design_properties

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
        refusal = _add_refusal(context.scene)
        if refusal is not None:
            cls.poll_message_set(refusal)
            return False
        return True

    def execute(self, context):
        design = context.scene.lamp_design
        refusal = _add_refusal(context.scene)
        if refusal is not None:
            self.report({"ERROR"}, refusal)
            return {"CANCELLED"}
        doc = design_properties.design_document(context.scene)
        try:
            doc = design_with_new_lamp(doc, design.active_lamps_index)
        except SceneError:  # the design has an error of its own, which the panel shows: add the lamp anyway
            doc = _with_new_lamp_unchecked(doc, design.active_lamps_index)
        design_properties.set_lamp(design.lamps.add(), doc["lamps"][-1])
        design.body.center = doc["body"]["center"]
        design.body.size = doc["body"]["size"]
        design.active_lamps_index = len(design.lamps) - 1
        return {"FINISHED"}


_refusal_memo: dict = {"key": None, "refusal": None}  # the last design poll checked, and its answer


def _add_refusal(bl_scene) -> str | None:
    """Why a lamp cannot be added to the scene's design, or None: only reasons of adding itself
    (four lamps already, no room for a body that holds the new lamp); an error the design has
    anyway is the panel's to show, not a reason to grey out Add Lamp. Checking a design takes
    milliseconds and poll runs at every redraw of the panel, so the answer is kept until the
    design changes."""
    doc = design_properties.design_document(bl_scene)
    if len(doc["lamps"]) >= spec.MAX_LAMPS:
        return f"A design has at most {spec.MAX_LAMPS} lamps"
    key = (doc, bl_scene.lamp_design.active_lamps_index)
    if _refusal_memo["key"] != key:
        _refusal_memo.update(key=key, refusal=_refusal_of(*key))
    return _refusal_memo["refusal"]


def _refusal_of(doc: dict, active_index: int) -> str | None:
    try:
        parse_scene({key: value for key, value in doc.items() if key != "camera"})
    except SceneError:
        # An error of the design itself, which the panel shows, is no reason to refuse; only the
        # new lamp's own place is.
        body = _with_new_lamp_unchecked(doc, active_index)["body"]
        limit = spec.BODY.fields["size"].hi
        if max(body["size"]) > limit:
            return (f"Cannot add a lamp: the body would need {max(body['size']):g} mm; body.size allows up "
                    f"to {limit:g} mm (make the lenses smaller or remove a lamp)")
        return None
    try:
        design_with_new_lamp(doc, active_index)
    except SceneError as e:
        return f"Cannot add a lamp: {e}"
    return None


def _with_new_lamp_unchecked(doc: dict, active_index: int) -> dict:
    """``design_with_new_lamp`` without the check: a copy of the active lamp placed beside the others."""
    doc = copy.deepcopy(doc)
    lamps = doc["lamps"]
    lamps.append(copy.deepcopy(lamps[active_index]) if 0 <= active_index < len(lamps) else new_lamp())
    place_new_lamp(doc)
    return doc


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
        lamps.append(new_lamp())
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
        level = "WARNING" if report.worst_deviation > report.tolerance else "INFO"
        self.report({level}, f"Built {len(report.objects)} objects; largest deviation from the model "
                             f"{report.worst_deviation:.3f} mm (tolerance {report.tolerance:g} mm)")
        return {"FINISHED"}


classes = (
    LAMP_OT_lamp_add,
    LAMP_OT_lamp_remove,
    LAMP_OT_build,
)


register, unregister = bpy.utils.register_classes_factory(classes)

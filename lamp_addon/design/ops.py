"""Operators that edit the design: add and remove lamps, build the lamp as objects.

Add Lamp keeps a valid design valid (``convert.layout``): the new lamp is a copy of the active one
(the spec's default lamp in an empty design, in the preferred forms: the lens colour picker), placed
right of the others with a small margin, and the body grows to hold it. Only adding itself is refused (four
lamps already, a body wider than the spec allows), by poll and execute alike, naming the field and
its allowed range; an error the design has anyway is the panel's to show and does not block it.
"""

from __future__ import annotations

import bpy

from ...core_tracer.scene import spec
from ...core_tracer.scene.reading import SceneError
from .. import reports
from ..convert.layout import (
    design_with_new_lamp,
    image_size_for_body,
    refusal_of_new_lamp,
    with_new_lamp_unchecked,
)
from . import builder, lamp_camera, properties, validity, view_link
from . import setup as render_setup
from .operator import DesignOperator


class LAMP_OT_lamp_add(DesignOperator, bpy.types.Operator):
    bl_idname = "lamp.lamp_add"
    bl_label = "Add Lamp"
    bl_description = (f"Add a copy of the active lamp right of the others (at most {spec.MAX_LAMPS} lamps; the "
                      "first one with default values); the body grows to hold it")
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def refusal(cls, context):
        return _add_refusal(context.scene)

    def execute(self, context):
        design = context.scene.lamp_design
        refusal = self.refusal(context)
        if refusal is not None:
            return self.cancelled(refusal)
        doc = properties.design_document(context.scene)
        try:
            doc = design_with_new_lamp(doc, design.active_lamps_index)
        except SceneError:  # the design has an error of its own, which the panel shows: add the lamp anyway
            doc = with_new_lamp_unchecked(doc, design.active_lamps_index)
        properties.set_lamp(design.lamps.add(), doc["lamps"][-1])
        design.body.center = doc["body"]["center"]
        design.body.size = doc["body"]["size"]
        design.active_lamps_index = len(design.lamps) - 1
        follow_body_aspect(context.scene)
        lamp_camera.keep_framed(context.scene)
        if len(design.lamps) == 1 and design.auto_build and not render_setup.is_set_up(context.scene):
            # Auto Build makes the lamp in a moment: its first build in this file, so set the scene up now.
            news = render_setup.set_up(context.scene)
            return reports.finished(self, "Added the first lamp" + render_setup.news_text(news),
                                    render_setup.news_details(news))
        return {"FINISHED"}


IMAGE_KEY = "lamp_image_from_body"  # design: the image size Add Lamp gave it from the body, [w, h]


def follow_body_aspect(bl_scene) -> bool:
    """Give a new design's image the body's aspect with a margin (``image_size_for_body``), and keep
    it so as lamps are added or removed, for as long as the image has the size given (a size the
    designer sets, or a preset's, is theirs). Returns whether the size changed."""
    design = bl_scene.lamp_design
    image = (design.image.width, design.image.height)
    given = design.get(IMAGE_KEY)
    default = (spec.IMAGE.fields["width"].default, spec.IMAGE.fields["height"].default)
    new_design = len(design.lamps) == 1 and image == default
    if not new_design and (given is None or tuple(given) != image):
        return False
    size = image_size_for_body(design.body.size)
    design[IMAGE_KEY] = list(size)
    if size == image:
        return False
    design.image.width, design.image.height = size
    return True


_refusal_memo: dict = {"key": None, "refusal": None}  # the last design poll checked, and its answer


def _add_refusal(bl_scene) -> str | None:
    """Why a lamp cannot be added to the scene's design, or None: only reasons of adding itself
    (four lamps already, no room for a body that holds the new lamp); an error the design has
    anyway is the panel's to show, not a reason to grey out Add Lamp. Checking a design takes
    milliseconds and poll runs at every redraw of the panel, so the answer is kept until the
    design changes."""
    doc = properties.design_document(bl_scene)
    if len(doc["lamps"]) >= spec.MAX_LAMPS:
        return f"A design has at most {spec.MAX_LAMPS} lamps"
    key = (doc, bl_scene.lamp_design.active_lamps_index)
    if _refusal_memo["key"] != key:
        _refusal_memo.update(key=key, refusal=refusal_of_new_lamp(*key))
    return _refusal_memo["refusal"]


class LAMP_OT_lamp_remove(DesignOperator, bpy.types.Operator):
    bl_idname = "lamp.lamp_remove"
    bl_label = "Remove Lamp"
    bl_description = "Remove the selected lamp from the design"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def refusal(cls, context):
        design = context.scene.lamp_design
        if not 0 <= design.active_lamps_index < len(design.lamps):
            return "No lamp is selected"
        if len(design.lamps) <= 1:
            return "A design needs at least one lamp"
        return None

    def execute(self, context):
        design = context.scene.lamp_design
        design.lamps.remove(design.active_lamps_index)
        design.active_lamps_index = min(design.active_lamps_index, len(design.lamps) - 1)
        properties.notify_edited(context.scene)  # removing from the list calls no update callback
        follow_body_aspect(context.scene)
        lamp_camera.keep_framed(context.scene)
        return {"FINISHED"}


class LAMP_OT_build(DesignOperator, bpy.types.Operator):
    bl_idname = "lamp.build"
    bl_label = "Build Lamp"
    bl_description = ("Build the design as objects under the \"Lamp Design\" root object, updating the previous "
                      "build in place: your names, placement, modifiers and material edits are kept")
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def refusal(cls, context):
        if context.mode != "OBJECT":
            return "Switch to Object Mode first"
        if not context.scene.lamp_design.lamps:
            return "Add a lamp first"
        return None

    def execute(self, context):
        try:
            scene = properties.design_to_scene(context.scene)
        except SceneError as e:
            return self.cancelled(e)
        report = builder.build_lamp(context.scene, scene)
        validity.remember(context.scene)
        view_link.sync_view(context.scene)
        news = render_setup.set_up(context.scene)
        if report.not_driven:  # the designer's own edits, each named in the Info editor
            reports.details(self, [f"Not following the design (your edit kept): {what}" for what in report.not_driven])
            reports.say(self, "WARNING", f"{len(report.not_driven)} of your edits kept, not following the design "
                                         "(Info editor)")
        deviation = (f"Largest deviation of the lamp objects from the model {report.worst_deviation:.3f} mm "
                     f"(tolerance {report.tolerance:g} mm)")
        if report.worst_deviation > report.tolerance:
            reports.details(self, [deviation, *render_setup.news_details(news)])
            reports.say(self, "WARNING", f"Built {len(report.objects)} objects, {report.worst_deviation:.3f} mm from "
                                         f"the model: over the {report.tolerance:g} mm tolerance"
                                         f"{render_setup.news_text(news)}")
            return {"FINISHED"}
        return reports.finished(self, f"Built {len(report.objects)} objects{render_setup.news_text(news)}",
                                [deviation, *render_setup.news_details(news)])


classes = (
    LAMP_OT_lamp_add,
    LAMP_OT_lamp_remove,
    LAMP_OT_build,
)


register, unregister = bpy.utils.register_classes_factory(classes)

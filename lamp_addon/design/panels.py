"""The "Lamp" tab of the 3D Viewport sidebar: every field of the design, the lamp list and the actions.

Fields are drawn by walking ``core_tracer.spec`` sections, so a field added to the spec shows up
without touching this file; an either/or rule of a section (the lens colour) is drawn as a row of
its forms and the fields of the form in use. Lengths carry their unit in the property name
("Radius (mm)"). The top of the panel says whether the design is valid; the field its first error
names is highlighted where it is drawn, with the message under it (``design.validity``).

Other modules add buttons to the actions area at register time (``actions.add_action(idname, text,
icon)``, taken away with ``remove_action``); the panel draws ``actions.ACTION_OPERATORS`` in order.
"""

from __future__ import annotations

import bpy

from ...core_tracer.scene import functions, light_models
from ...core_tracer.scene import spec as S
from ..actions import ACTION_OPERATORS
from . import properties, validity
from . import setup as render_setup


# (operator idname, button text, icon) drawn in the actions area, in order.
def leaf_keys(section: S.Section) -> list[str]:
    """The keys of ``section`` drawn as plain properties: leaves that are not constants and belong
    to no either/or rule (those are drawn by ``draw_rule``)."""
    return [key for key, spec in section.fields.items()
            if not isinstance(spec, (S.Section, S.ListOf)) and not properties.is_constant(spec)
            and section.rule_of(key) is None]


def draw_section(layout, group, section: S.Section, kinds: tuple[type, ...] | None = None) -> None:
    """One ``prop`` per leaf field of ``section`` (only of the given spec ``kinds`` if set), then
    each either/or rule of the section."""
    status = validity.status(group.id_data)  # once per section: reading the design costs ~0.5 ms
    model = group.id_data.lamp_design.light_model

    def value_of(k):
        return getattr(group, properties.property_id(k))

    for key in leaf_keys(section):
        if not section.shown(key, value_of):
            continue  # a field of another choice (a round lens's width)
        if not light_models.used(section, key, model, value_of):
            continue  # a field the design's light model does not use (a bulb's RGB intensity in lm)
        if kinds is None or isinstance(section.fields[key], kinds):
            validity.draw_field(layout, group, properties.property_id(key), status)
    if kinds is None:
        for rule in section.one_of:
            if any(light_models.used(section, key, model, value_of) for key in rule.keys):
                draw_rule(layout, group, rule, status)


def draw_rule(layout, group, rule: S.OneOf, status: validity.Status) -> None:
    """An either/or rule: its forms as a row of buttons, then the fields of the form in use."""
    box = layout.box()
    mode = properties.mode_property(rule)
    box.row().prop(group, mode, expand=True)
    for key in rule.alternative(getattr(group, mode)).keys:
        validity.draw_field(box, group, key, status)


def draw_cuts(layout, group) -> None:
    """The cuts: their type as a row of buttons, then only the fields that type uses."""
    status = validity.status(group.id_data)
    kind = properties.property_id("type")
    layout.row().prop(group, kind, expand=True)
    for key in S.CUT_TYPE_FIELDS[getattr(group, kind)]:
        validity.draw_field(layout, group, properties.property_id(key), status)


def active_lamp(context):
    design = context.scene.lamp_design
    if 0 <= design.active_lamps_index < len(design.lamps):
        return design.lamps[design.active_lamps_index]
    return None


class LAMP_UL_lamps(bpy.types.UIList):
    """The design's lamps, at most ``MAX_LAMPS``, named as their parts are; the bulb switch on each row."""

    def draw_item(self, context, layout, data, item, icon, active_data, active_propname, index=0, flt_flag=0):
        row = layout.row(align=True)
        # The name its parts are built with: "Stop", "Turn 2", or "Lamp 3" for a custom lamp.
        label = functions.lamp_label([{"function": lamp.function} for lamp in data.lamps], index)
        row.label(text=label, icon="LIGHT_POINT")
        row.prop(item.bulb, "on", text="", emboss=False, icon="OUTLINER_OB_LIGHT" if item.bulb.on else "LIGHT")


class LampTab:
    """Where the design's panels are: the 3D Viewport's sidebar, tab "Lamp"."""

    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Lamp"

    @staticmethod
    def _split(layout):
        layout.use_property_split = True
        layout.use_property_decorate = False
        return layout


class LAMP_PT_design(LampTab, bpy.types.Panel):
    bl_label = "Lamp Design"

    def draw(self, context):
        validity.draw_status(self.layout, context.scene)
        col = self.layout.column(align=True)
        for idname, text, icon in ACTION_OPERATORS:
            col.operator(idname, text=text, icon=icon)


class DesignSection(LampTab):
    """A sub-panel of the Lamp Design panel (its place among the others is its ``bl_order``)."""

    bl_parent_id = "LAMP_PT_design"


class ClosedSection(DesignSection):
    """A sub-panel of the Lamp Design panel that starts closed."""

    bl_options = {"DEFAULT_CLOSED"}


def property_column(layout, settings, *names: str):
    """An aligned column of ``settings``' properties ``names``, labels on the left as Blender's own
    panels have them; returned for more."""
    col = layout.column(align=True)
    col.use_property_split = True
    col.use_property_decorate = False
    for name in names:
        col.prop(settings, name)
    return col


class LAMP_PT_info(ClosedSection, bpy.types.Panel):
    bl_label = "Design"
    bl_order = 0

    def draw(self, context):
        draw_section(self._split(self.layout), context.scene.lamp_design, S.SCENE, (S.Text, S.Tags))


class LAMP_PT_body(DesignSection, bpy.types.Panel):
    bl_label = "Body"
    bl_order = 1

    def draw(self, context):
        draw_section(self._split(self.layout), context.scene.lamp_design.body, S.BODY)


class LAMP_PT_light(DesignSection, bpy.types.Panel):
    bl_label = "Light"
    bl_order = 2

    def draw(self, context):
        layout = self._split(self.layout)
        design = context.scene.lamp_design
        layout.row().prop(design, "light_model", expand=True)  # which fields follow: the paper's or lm, lx
        kept = render_setup.kept_exposure_text(context.scene)
        if kept:
            layout.label(text=kept, icon="INFO")
        draw_section(layout, design.light, S.LIGHT)
        draw_section(layout, design, S.SCENE, (S.Num,))  # the background colour
        layout.separator()
        draw_section(layout.column(heading="Surroundings"), design.environment, S.ENVIRONMENT)


class LAMP_PT_camera(ClosedSection, bpy.types.Panel):
    bl_label = "Camera & Image"
    bl_order = 3

    def draw(self, context):
        layout = self._split(self.layout)
        design = context.scene.lamp_design
        draw_section(layout.column(), design.camera, S.CAMERA)
        layout.separator()
        draw_section(layout.column(), design.image, S.IMAGE)


class LAMP_PT_glare(DesignSection, bpy.types.Panel):
    """The eye's glare around bright pixels, switched on in the header as Blender's own effects are."""

    bl_label = "Glare"
    bl_parent_id = "LAMP_PT_camera"
    bl_options = {"DEFAULT_CLOSED"}
    bl_order = 1

    def draw_header(self, context):
        self.layout.prop(context.scene.lamp_design.glare, "on", text="")

    def draw(self, context):
        layout = self._split(self.layout)
        glare = context.scene.lamp_design.glare
        layout.active = glare.on
        status = validity.status(context.scene)
        for key in leaf_keys(S.GLARE):
            if key != "on":
                validity.draw_field(layout, glare, properties.property_id(key), status)


class LAMP_PT_lamps(DesignSection, bpy.types.Panel):
    bl_label = "Lamps"
    bl_order = 4

    def draw(self, context):
        layout = self.layout
        design = context.scene.lamp_design
        row = layout.row()
        row.template_list("LAMP_UL_lamps", "", design, "lamps", design, "active_lamps_index",
                          rows=2, maxrows=S.MAX_LAMPS)
        col = row.column(align=True)
        col.operator("lamp.lamp_add", icon="ADD", text="")
        col.operator("lamp.lamp_remove", icon="REMOVE", text="")
        lamp = active_lamp(context)
        if lamp is not None:
            draw_section(self._split(layout.column()), lamp, S.LAMP)
        elif not design.lamps:  # a new scene: say how to start rather than show an empty list
            layout.label(text="Add a lamp with + or apply a preset below", icon="INFO")


class _LampPartPanel(LampTab):
    """A sub-panel of the active lamp showing one section of ``spec.LAMP``."""

    bl_parent_id = "LAMP_PT_lamps"
    part = ""

    @classmethod
    def poll(cls, context):
        lamp = active_lamp(context)
        return lamp is not None and section_in_use(lamp, cls.part) and cls._has_a_field_shown(lamp)

    @classmethod
    def _has_a_field_shown(cls, lamp) -> bool:
        """Whether the design's light model uses a field of the section: no empty sub-panel (the light
        guide's, all photometric, in the paper mode)."""
        if cls.part == "cuts":
            return True
        group = getattr(lamp, cls.part)
        section = S.LAMP.fields[cls.part]
        model = lamp.id_data.lamp_design.light_model
        return any(light_models.used(section, key, model, lambda k: getattr(group, properties.property_id(k)))
                   for key in leaf_keys(section))

    def draw(self, context):
        group = getattr(active_lamp(context), self.part)
        if self.part == "cuts":
            draw_cuts(self._split(self.layout), group)
        else:
            draw_section(self._split(self.layout), group, S.LAMP.fields[self.part])


def section_in_use(lamp, part: str) -> bool:
    """Whether the lamp's ``part`` section shapes it: the reflector's and the prism plate's only for
    the lamp's collection (docs/model.md, the prism plate), the bulb's and socket's or the LEDs' only
    for its light source; every other section always (a section none of whose fields the light model
    uses, the light guide's in the paper mode, is hidden by ``_has_a_field_shown``)."""
    if part in S.COLLECTIONS:
        return lamp.collection == part
    if part == "led":  # the LEDs in place of bulb and socket (the lamp list's switch stays)
        return lamp.source == "led"
    if part in ("bulb", "socket"):
        return lamp.source == "bulb"
    return True


def _make_part_panel(key: str, order: int) -> type:
    return type(f"LAMP_PT_{key}", (_LampPartPanel, bpy.types.Panel),
                {"bl_label": properties.display_name(key), "part": key, "bl_order": order})


_part_panels = tuple(_make_part_panel(key, order) for order, (key, spec) in enumerate(S.LAMP.fields.items())
                     if isinstance(spec, S.Section))

classes = (
    LAMP_UL_lamps,
    LAMP_PT_design,
    LAMP_PT_info,
    LAMP_PT_body,
    LAMP_PT_light,
    LAMP_PT_camera,
    LAMP_PT_glare,
    LAMP_PT_lamps,
    *_part_panels,
)


register, unregister = bpy.utils.register_classes_factory(classes)

# SPDX-License-Identifier: GPL-3.0-or-later
"""The "Study" section of the Lamp sidebar tab: one or two parameters of the design, varied (issue 5).

The settings live on the scene (``Scene.lamp_study``): for each axis a parameter (every numeric field
that ``core_tracer.study`` can vary, lamp fields for all lamps or for one), and its values as a range
with a number of steps or as a list written as on the command line (``1.45, 1.5`` or, for colours and
other vectors, ``0.9/0.1/0.1, 0.9/0.5/0.05``); the size of each variant and the number of worker
processes. ``study_settings.study_from_settings`` turns them into a ``core_tracer.study.Study`` of the current design;
the operators (``study_ops``) render it and show the contact sheet.
"""

from __future__ import annotations

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty, PointerProperty, StringProperty

from ..core_tracer.scene import spec as S
from ..core_tracer.study import definition as st
from . import design_properties, study_settings
from .study_settings import ALL_LAMPS, is_lamp_parameter, is_single_number

LENS_COLOUR = "lens.transmitted_color"


def _parameter_label(path: str) -> str:
    if path == LENS_COLOUR:
        return "Lens Colour (transmitted)"
    spec = S.lookup(path)
    *parents, key = path.split(".")
    unit = spec.unit if isinstance(spec, S.Num) else ""
    prefix = " ".join(design_properties.display_name(p) for p in parents)
    label = design_properties.display_name(key, unit)
    return f"{prefix}: {label}" if prefix else label


def _parameter_items() -> tuple[tuple[str, str, str], ...]:
    items = []
    for path in st.study_parameters():
        spec = S.lookup(path)
        vector = isinstance(spec, S.Num) and spec.size > 1
        how = "a list of values written a/b/c" if vector else "a range or a list"
        items.append((path, _parameter_label(path), f"{spec.doc}. Allowed: {spec.range_text()}; {how}"))
    return tuple(items)


PARAMETER_ITEMS = _parameter_items()
LAMP_ITEMS = ((ALL_LAMPS, "All Lamps", "Change the parameter of every lamp"),
              *((str(i), f"Lamp {i + 1}", f"Change the parameter of lamp {i + 1} only") for i in range(S.MAX_LAMPS)))
MODE_ITEMS = (("RANGE", "Range", "From a first to a last value in a number of equal steps"),
              ("LIST", "List", "Values separated by commas; vectors and colours as a/b/c"))


def _suggest_range(self, context) -> None:
    """A new parameter gets a range around its default, inside its allowed range."""
    spec = S.lookup(self.parameter)
    if isinstance(spec, S.Num) and spec.size == 1:
        lo, hi = design_properties.blender_range(spec)
        d = float(spec.default)
        span = abs(d) * 0.25 or 1.0
        self.start = max(d - span, lo) if lo is not None else d - span
        self.stop = min(d + span, hi) if hi is not None else d + span
        self.mode = "RANGE"
    else:
        self.mode = "LIST"
        if isinstance(spec, S.Flag):
            self.values = "on, off"
        elif self.parameter == LENS_COLOUR:
            self.values = "0.9/0.05/0.05, 0.9/0.4/0.05, 0.9/0.9/0.9"


def _axis_group(name: str, parameter: str, start: float, stop: float) -> type:
    annotations = {
        "parameter": EnumProperty(name="Parameter", items=PARAMETER_ITEMS, default=parameter,
                                  description="The field of the design this axis varies", update=_suggest_range),
        "lamp": EnumProperty(name="Lamp", items=LAMP_ITEMS, default=ALL_LAMPS,
                             description="Which lamp a lamp parameter changes"),
        "mode": EnumProperty(name="Values", items=MODE_ITEMS, default="RANGE"),
        "start": FloatProperty(name="From", default=start, precision=4,
                               description="First value of the range"),
        "stop": FloatProperty(name="To", default=stop, precision=4, description="Last value of the range"),
        "steps": IntProperty(name="Steps", default=4, min=1, max=st.MAX_VARIANTS,
                             description="Number of values from the first to the last, both included"),
        "values": StringProperty(name="Values", default="",
                                 description="Values separated by commas, e.g. 1.45, 1.5; colours and other "
                                             "vectors as 0.9/0.1/0.1, 0.9/0.5/0.05"),
    }
    return type(name, (bpy.types.PropertyGroup,), {"__annotations__": annotations})


LAMP_PG_study_axis_1 = _axis_group("LAMP_PG_study_axis_1", "lens.ior", 1.45, 1.6)
LAMP_PG_study_axis_2 = _axis_group("LAMP_PG_study_axis_2", "cuts.height", 0.5, 2.0)


class LAMP_PG_study(bpy.types.PropertyGroup):
    axis_1: PointerProperty(type=LAMP_PG_study_axis_1, name="Columns")
    use_axis_2: BoolProperty(name="Second Parameter", default=True,
                             description="Vary a second parameter down the rows of the sheet")
    axis_2: PointerProperty(type=LAMP_PG_study_axis_2, name="Rows")
    width: IntProperty(name="Width", default=128, min=8, max=st.MAX_SIZE, subtype="PIXEL",
                       description="Width of each variant image")
    height: IntProperty(name="Height", default=128, min=8, max=st.MAX_SIZE, subtype="PIXEL",
                        description="Height of each variant image")
    workers: IntProperty(name="Workers", default=0, min=0, max=256,
                         description="Worker processes rendering the variants (0: one per core)")
    variant: IntProperty(name="Variant", default=1, min=1, max=st.MAX_VARIANTS,
                         description="A variant of the last study (numbered along the rows of the sheet)")

    @classmethod
    def register(cls):
        bpy.types.Scene.lamp_study = PointerProperty(type=cls, name="Lamp Study",
                                                     description="Settings of the design study")

    @classmethod
    def unregister(cls):
        del bpy.types.Scene.lamp_study


# ---------------------------------------------------------------------------------------------
# The panel


def _draw_axis(layout, axis, title: str) -> None:
    box = layout.box()
    box.label(text=title)
    col = box.column()
    col.use_property_split = True
    col.use_property_decorate = False
    col.prop(axis, "parameter", text="Parameter")
    if is_lamp_parameter(axis.parameter):
        col.prop(axis, "lamp")
    if is_single_number(axis.parameter):
        col.row().prop(axis, "mode", expand=True)
    if axis.mode == "RANGE" and is_single_number(axis.parameter):
        sub = col.column(align=True)
        sub.prop(axis, "start")
        sub.prop(axis, "stop")
        sub.prop(axis, "steps")
    else:
        col.prop(axis, "values", text="Values")


class LAMP_PT_study(bpy.types.Panel):
    bl_label = "Study"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Lamp"
    bl_parent_id = "LAMP_PT_design"
    bl_options = {"DEFAULT_CLOSED"}
    bl_order = 20

    def draw(self, context):
        layout = self.layout
        settings = context.scene.lamp_study
        _draw_axis(layout, settings.axis_1, "Columns")
        layout.prop(settings, "use_axis_2")
        if settings.use_axis_2:
            _draw_axis(layout, settings.axis_2, "Rows")
        col = layout.column(align=True)
        col.use_property_split = True
        col.use_property_decorate = False
        col.prop(settings, "width")
        col.prop(settings, "height")
        col.prop(settings, "workers")
        layout.operator("lamp.study_run", icon="IMGDISPLAY")

        study = study_settings.last_study()
        if study is None:
            return
        box = layout.box()
        box.label(text=f"Last study: {len(study)} variants", icon="IMAGE_DATA")
        box.operator("lamp.study_save_sheet", icon="FILE_IMAGE")
        row = box.row(align=True)
        row.prop(settings, "variant")
        index = settings.variant - 1
        if index < len(study):
            box.label(text=study.variants[index].label(study))
            row = box.row(align=True)
            row.operator("lamp.study_apply_variant", icon="CHECKMARK")
            row.operator("lamp.study_keep_variant", icon="ADD")
        else:
            box.label(text=f"The study has {len(study)} variants", icon="ERROR")


classes = (LAMP_PG_study_axis_1, LAMP_PG_study_axis_2, LAMP_PG_study, LAMP_PT_study)


register, unregister = bpy.utils.register_classes_factory(classes)

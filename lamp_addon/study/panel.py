# SPDX-License-Identifier: GPL-3.0-or-later
"""The "Study" section of the Lamp sidebar tab: the study settings (``study.settings``), the button
that renders them and the last study's sheet and variants (``study.ops``)."""

from __future__ import annotations

import bpy

from ...core_tracer.scene import spec as S
from ..design.panels import ClosedSection, property_column
from . import settings as study_settings

# ---------------------------------------------------------------------------------------------
# The panel


def _draw_axis(layout, axis, title: str) -> None:
    box = layout.box()
    box.label(text=title)
    col = box.column()
    col.use_property_split = True
    col.use_property_decorate = False
    col.prop(axis, "parameter", text="Parameter")
    if study_settings.is_lamp_parameter(axis.parameter):
        col.prop(axis, "lamp")
    if study_settings.is_single_number(axis.parameter):
        col.row().prop(axis, "mode", expand=True)
    if axis.mode == "RANGE" and study_settings.is_single_number(axis.parameter):
        sub = col.column(align=True)
        sub.prop(axis, "start")
        sub.prop(axis, "stop")
        sub.prop(axis, "steps")
    else:
        col.prop(axis, "values", text="Values")
        spec = study_settings.parameter_spec(axis.parameter)
        if isinstance(spec, S.Choice):  # the names the list may hold
            col.label(text=spec.range_text().capitalize())


class LAMP_PT_study(ClosedSection, bpy.types.Panel):
    bl_label = "Study"
    bl_order = 20

    def draw(self, context):
        layout = self.layout
        settings = context.scene.lamp_study
        _draw_axis(layout, settings.axis_1, "Columns")
        layout.prop(settings, "use_axis_2")
        if settings.use_axis_2:
            _draw_axis(layout, settings.axis_2, "Rows")
        col = property_column(layout, settings, "width", "height", "fit_lamp", "scheduler")
        if study_settings.uses_cluster(settings):
            col.label(text="Variants render as Dask tasks", icon="NETWORK_DRIVE")
        else:
            col.prop(settings, "workers")
        if context.scene.lamp_design.light_model == "photometric":
            property_column(layout, settings, "measures", "sort_by", "filter")
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


classes = (LAMP_PT_study,)


register, unregister = bpy.utils.register_classes_factory(classes)

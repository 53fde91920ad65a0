# SPDX-License-Identifier: GPL-3.0-or-later
"""The "Measures" section of the Lamp sidebar tab: Measure Design, the summary line and the table of
the last measures (function, test point, required, simulated, margin, pass), Open Report."""

from __future__ import annotations

import bpy

from ..design.panels import ClosedSection
from . import ops
from . import settings as measures_settings

ROWS_SHOWN = 40  # rows of the table drawn at most (the four-lamp design has about 150)


class LAMP_PT_measures(ClosedSection, bpy.types.Panel):
    bl_label = "Measures"
    bl_order = 22

    def draw(self, context):
        layout = self.layout
        if ops.not_photometric(context.scene):
            layout.label(text="Measures need the Photometric light model (Design: Light Model)", icon="INFO")
            return
        settings = context.scene.lamp_measures
        row = layout.row(align=True)
        row.operator("lamp.measures_run", icon="DRIVER_DISTANCE")
        row.prop(settings, "beam_files", toggle=True)
        measured = measures_settings.last_measures(context.scene)
        if measured is None:
            return
        from ...core_tracer.measures import table

        box = layout.box()
        for part in table.summary(measured).split(" · "):
            box.label(text=part, icon="ERROR" if ": fails" in part or "outside" in part else "CHECKMARK")
        box.operator("lamp.measures_open_report", icon="IMAGE_DATA")
        box.prop(settings, "show_all")
        lines = table.lines(measured)
        shown = lines if settings.show_all else [line for line in lines if line.passed is not True
                                                 or line.point.startswith("colour")]
        col = box.column(align=True)  # a row's labels share its width equally: the columns line up
        row = col.row()
        for heading in ("Function", "Test point / measure", "Required", "Simulated", "Margin", "Pass"):
            row.label(text=heading)
        for line in shown[:ROWS_SHOWN]:
            row = col.row()
            for text in (line.function, line.point, line.required, line.simulated, line.margin):
                row.label(text=text)
            if line.passed is None:  # a figure without a limit
                row.label(text="—")
            else:
                row.label(text="pass" if line.passed else "FAIL", icon="CHECKMARK" if line.passed else "CANCEL")
        if len(shown) > ROWS_SHOWN:
            box.label(text=f"{len(shown) - ROWS_SHOWN} more rows in measures.json and the report")
        box.label(text=f"Folder: {settings.folder}")


classes = (LAMP_PT_measures,)


register, unregister = bpy.utils.register_classes_factory(classes)

# SPDX-License-Identifier: GPL-3.0-or-later
"""The "Optimise" section of the Lamp sidebar tab: the optimisation file, where trials render, the
button that searches, and the best designs found, each applicable to the design with one click."""

from __future__ import annotations

import bpy

from ..design.panels import ClosedSection, property_column
from . import settings as optimise_settings


class LAMP_PT_optimise(ClosedSection, bpy.types.Panel):
    bl_label = "Optimise"
    bl_order = 21

    def draw(self, context):
        layout = self.layout
        settings = context.scene.lamp_optimise
        property_column(layout, settings, "file", "scheduler", "trials")
        layout.operator("lamp.optimise_run", icon="PLAY")
        outcome = optimise_settings.last()
        if outcome is None:
            return
        box = layout.box()
        box.label(text=outcome.summary or outcome.name, icon="SORTTIME")
        if not outcome.best:
            box.label(text="No trial met every constraint", icon="ERROR")
            return
        for k, (number, design, values) in enumerate(outcome.best[:8], start=1):
            shown = ", ".join(f"{v:.4g}" for v in values)
            setting = ", ".join(f"{name.split('.')[-1]} {v:.4g}" if isinstance(v, float) else f"{name} {v}"
                                for name, v in design.items())
            box.label(text=f"{k}. trial {number}: {shown} ({setting})")
        row = box.row(align=True)
        row.prop(settings, "choice")
        row.operator("lamp.optimise_apply", icon="CHECKMARK")


classes = (LAMP_PT_optimise,)


register, unregister = bpy.utils.register_classes_factory(classes)

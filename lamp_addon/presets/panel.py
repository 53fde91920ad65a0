# SPDX-License-Identifier: GPL-3.0-or-later
"""The preset browser: a "Presets" sub-panel of the Lamp tab, and the registration of its parts.

Drawing only reads the last listing (``presets.library``); listing and thumbnails happen in timers,
operators and a worker thread, so opening the panel stays instant whatever the libraries hold.
"""

from __future__ import annotations

import textwrap

import bpy

from ..design.panels import DesignSection
from . import library

MAX_WARNINGS_SHOWN = 30


def _haystack(item) -> str:
    return " ".join((item.name, item.author, item.tags, item.library, item.description)).casefold()


class LAMP_UL_presets(bpy.types.UIList):
    """Presets with their thumbnail, filtered by the search field above the list."""

    def draw_item(self, context, layout, data, item, icon, active_data, active_propname, index=0, flt_flag=0):
        thumbs = library.thumbnails()
        icon_id = thumbs.icon_id(item.file) if thumbs is not None else 0
        row = layout.row(align=True)
        if icon_id:
            row.label(text=item.name, icon_value=icon_id)
        else:
            row.label(text=item.name, icon="PRESET")
        sub = row.row()
        sub.alignment = "RIGHT"
        sub.label(text=item.library, icon="UNLOCKED" if item.writable else "LOCKED")

    def filter_items(self, context, data, propname):
        items = getattr(data, propname)
        words = context.window_manager.lamp_preset_search.casefold().split()
        if not words:
            return [], []
        flags = [self.bitflag_filter_item if all(w in _haystack(item) for w in words) else 0 for item in items]
        return flags, []


class LAMP_PT_presets(DesignSection, bpy.types.Panel):
    bl_label = "Presets"
    bl_order = 100

    def draw(self, context):
        layout = self.layout
        wm = context.window_manager
        listing = library.listing()
        layout.prop(wm, "lamp_preset_search", text="", icon="VIEWZOOM")
        if not listing.loaded or listing.stale:
            row = layout.row()
            row.label(text="Listing presets..." if not listing.loaded else "Libraries changed")
            row.operator("lamp.preset_refresh", text="Refresh", icon="FILE_REFRESH")
            if not listing.loaded:
                return

        row = layout.row()
        row.template_list("LAMP_UL_presets", "", wm, "lamp_presets", wm, "lamp_presets_index", rows=5)
        col = row.column(align=True)
        col.operator("lamp.preset_save", icon="ADD", text="")
        col.operator("lamp.preset_delete", icon="REMOVE", text="")
        col.operator("lamp.preset_rename", icon="GREASEPENCIL", text="")
        col.separator()
        col.operator("lamp.preset_import", icon="IMPORT", text="")
        col.operator("lamp.preset_export", icon="EXPORT", text="")
        col.separator()
        col.operator("lamp.preset_refresh", icon="FILE_REFRESH", text="")

        self._draw_selected(context, layout)
        self._draw_problems(wm, layout, listing)

    @staticmethod
    def _draw_selected(context, layout) -> None:
        wm = context.window_manager
        if not 0 <= wm.lamp_presets_index < len(wm.lamp_presets):
            return
        item = wm.lamp_presets[wm.lamp_presets_index]
        box = layout.box()
        thumbs = library.thumbnails()
        icon_id = thumbs.icon_id(item.file) if thumbs is not None else 0
        if icon_id:
            box.template_icon(icon_value=icon_id, scale=6.0)
        elif thumbs is not None and thumbs.missing_reason(item.file):
            box.label(text=thumbs.missing_reason(item.file)[:200], icon="ERROR")
        else:
            box.label(text="Thumbnail being made...", icon="TIME")
        col = box.column(align=True)
        col.label(text=item.name, icon="PRESET")
        if item.author:
            col.label(text=f"By {item.author}")
        if item.tags:
            col.label(text=f"Tags: {item.tags}")
        col.label(text=f"Library: {item.library}")
        for line in textwrap.wrap(item.description, 48)[:6]:
            col.label(text=line)
        box.operator("lamp.preset_apply", icon="CHECKMARK").file = item.file

    @staticmethod
    def _draw_problems(wm, layout, listing) -> None:
        problems = [*listing.notes, *(str(w) for w in listing.warnings)]
        if not problems:
            return
        box = layout.box()
        box.prop(wm, "lamp_preset_show_warnings", icon="ERROR", emboss=False,
                 text=f"{len(listing.warnings)} files are not valid presets" if listing.warnings
                 else "Library problems")
        if wm.lamp_preset_show_warnings:
            col = box.column(align=True)
            for text in problems[:MAX_WARNINGS_SHOWN]:
                col.label(text=text[:200])
            if len(problems) > MAX_WARNINGS_SHOWN:
                col.label(text=f"... and {len(problems) - MAX_WARNINGS_SHOWN} more (python -m core_tracer "
                               "presets validate FOLDER lists them all)")


classes = (
    LAMP_UL_presets,
    LAMP_PT_presets,
)

register, unregister = bpy.utils.register_classes_factory(classes)

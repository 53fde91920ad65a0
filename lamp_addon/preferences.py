# SPDX-License-Identifier: GPL-3.0-or-later
"""The add-on's preferences: extra preset library folders (a team share, a project folder).

The preferences belong to the extension's root module (``bl_ext.<repository>.lamp_styling``), which is
what Blender looks up, so ``bl_idname`` is derived from ``__package__`` and never spelled out.
"""

from __future__ import annotations

import bpy
from bpy.props import BoolProperty, CollectionProperty, IntProperty, StringProperty

from . import reports

ADDON_PACKAGE = __package__.rpartition(".")[0]  # "bl_ext.<repository>.lamp_styling"


# Called with no arguments when the library folders change; the preset library adds its listener
# when it registers (it sits above this module, which never imports it).
library_listeners: list = []


def _libraries_changed(self, context) -> None:
    for listener in library_listeners:
        listener()


class LAMP_PG_library_folder(bpy.types.PropertyGroup):
    """A folder of lamp-scene/1 presets shown in the preset browser."""

    name: StringProperty(name="Name", description="How the library is shown in the preset browser",
                         update=_libraries_changed)
    directory: StringProperty(name="Folder", subtype="DIR_PATH", update=_libraries_changed,
                              description="Folder holding the *.json presets (only the folder itself, "
                                          "not its sub-folders)")
    read_only: BoolProperty(name="Read-Only", default=False, update=_libraries_changed,
                            description="Never save, rename or delete presets in this folder, even if the "
                                        "file system allows it (a team's reference library)")


class LAMP_UL_library_folders(bpy.types.UIList):
    def draw_item(self, context, layout, data, item, icon, active_data, active_propname, index=0, flt_flag=0):
        row = layout.row(align=True)
        row.prop(item, "name", text="", emboss=False, icon="ASSET_MANAGER")
        row.prop(item, "directory", text="")
        row.prop(item, "read_only", text="", icon="LOCKED" if item.read_only else "UNLOCKED")


class LAMP_OT_library_folder_add(bpy.types.Operator):
    bl_idname = "lamp.library_folder_add"
    bl_label = "Add Preset Library"
    bl_description = "Add a folder of lamp presets to the preset browser"
    bl_options = {"REGISTER", "INTERNAL"}

    directory: StringProperty(name="Folder", subtype="DIR_PATH", options={"SKIP_SAVE"})

    def invoke(self, context, event):
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}

    def execute(self, context):
        prefs = get(context)
        if prefs is None:
            return reports.cancelled(self, "The Lamp Styling add-on is not enabled")
        folder = bpy.path.abspath(self.directory).rstrip("/\\") if self.directory else ""
        item = prefs.library_folders.add()
        item.directory = folder
        item.name = bpy.path.basename(folder) or "Library"
        prefs.active_library_folder_index = len(prefs.library_folders) - 1
        context.preferences.is_dirty = True
        return {"FINISHED"}


class LAMP_OT_library_folder_remove(bpy.types.Operator):
    bl_idname = "lamp.library_folder_remove"
    bl_label = "Remove Preset Library"
    bl_description = "Stop showing the selected folder in the preset browser (its files are kept)"
    bl_options = {"REGISTER", "INTERNAL"}

    @classmethod
    def poll(cls, context):
        prefs = get(context)
        if prefs is None or not 0 <= prefs.active_library_folder_index < len(prefs.library_folders):
            cls.poll_message_set("No library folder is selected")
            return False
        return True

    def execute(self, context):
        prefs = get(context)
        prefs.library_folders.remove(prefs.active_library_folder_index)
        prefs.active_library_folder_index = max(0, min(prefs.active_library_folder_index,
                                                       len(prefs.library_folders) - 1))
        context.preferences.is_dirty = True
        _libraries_changed(prefs, context)
        return {"FINISHED"}


class LAMP_AP_preferences(bpy.types.AddonPreferences):
    bl_idname = ADDON_PACKAGE

    library_folders: CollectionProperty(type=LAMP_PG_library_folder, name="Preset Libraries")
    active_library_folder_index: IntProperty(name="Active Preset Library", min=0)

    def draw(self, context):
        layout = self.layout
        layout.label(text="Preset libraries besides the built-in presets and your own:")
        row = layout.row()
        row.template_list("LAMP_UL_library_folders", "", self, "library_folders", self,
                          "active_library_folder_index", rows=3)
        col = row.column(align=True)
        col.operator("lamp.library_folder_add", icon="ADD", text="")
        col.operator("lamp.library_folder_remove", icon="REMOVE", text="")
        layout.label(text="A team shares presets by adding the same folder (e.g. a network share) here.",
                     icon="INFO")


def get(context=None) -> LAMP_AP_preferences | None:
    """The add-on's preferences, or None when the add-on is not enabled."""
    addon = (context or bpy.context).preferences.addons.get(ADDON_PACKAGE)
    return addon.preferences if addon is not None else None


classes = (
    LAMP_PG_library_folder,
    LAMP_UL_library_folders,
    LAMP_OT_library_folder_add,
    LAMP_OT_library_folder_remove,
    LAMP_AP_preferences,
)

register, unregister = bpy.utils.register_classes_factory(classes)

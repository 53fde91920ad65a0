# SPDX-License-Identifier: GPL-3.0-or-later
"""Operators of the preset browser: apply, save, rename, delete, import, export, and the drop handler.

A preset is applied only after it has been read again and validated in full, and then all at once
(``design.properties.scene_to_design``), so a bad preset never changes the design half-way. Presets are only
ever opened from the listed libraries or from a file the designer picked; names never become paths
outside a library (``core_tracer.presets``).

A saved or exported preset records the view the designer sees: the Blender scene camera and the render
size when the scene has a camera, else the design's own camera and image. Applying a preset shows its
view through the add-on's own "Lamp Camera" (created when the scene has no camera); a camera of the
designer's own is never moved.
"""

from __future__ import annotations

import os

import bpy
from bpy.props import BoolProperty, EnumProperty, StringProperty
from bpy_extras.io_utils import ExportHelper, ImportHelper

from ...core_tracer import fileio
from ...core_tracer.library import presets as P
from ...core_tracer.scene.reading import SceneError, scene_to_json
from .. import reports
from ..design import properties as design_properties
from ..freeform import loading as freeform_loading
from ..freeform.properties import role_objects
from . import library as preset_library
from .apply import apply_preset_whole, design_as_seen


def selected_entry(context) -> P.PresetEntry | None:
    """The preset selected in the browser, if it is still listed."""
    wm = context.window_manager
    items = getattr(wm, "lamp_presets", None)
    if items is None or not 0 <= wm.lamp_presets_index < len(items):
        return None
    return preset_library.listing().entry(items[wm.lamp_presets_index].file)


def _split_tags(text: str) -> list[str]:
    return [t.strip() for t in text.split(design_properties.TAG_SEPARATOR) if t.strip()]


def _error_text(e: Exception) -> str:
    """One printable line: a file's name or content may hold line breaks or escape sequences."""
    if isinstance(e, OSError) and e.strerror:
        return P.printable(f"{e.filename}: {e.strerror}" if e.filename else e.strerror, 1000)
    return P.printable(str(e), 1000)


def _failed(operator: bpy.types.Operator, message: str, error: Exception | None = None) -> set[str]:
    """Report why ``operator`` did nothing (``message: error``) and cancel it."""
    return reports.cancelled(operator, message if error is None else f"{message}: {_error_text(error)}")


def _parts_left_out(bl_scene) -> str:
    """What a preset of the scene's design leaves out: its free-form parts (a preset is the JSON only)."""
    count = len(role_objects(bl_scene))
    if not count:
        return ""
    return (f" (the parametric design only: the {count} free-form parts are not in it; Export Free-form "
            "Design writes them with the design)")


def _exists(operator: bpy.types.Operator, path: str) -> set[str]:
    return _failed(operator, f"{path} exists already; tick \"Replace Existing\" to overwrite it")


def _not_applied(operator: bpy.types.Operator, message: str, e: Exception) -> set[str]:
    """The one-line report of an apply that failed (a failure other than the preset's own named by its kind)."""
    return _failed(operator, message, e if isinstance(e, (SceneError, OSError)) else
                   RuntimeError(f"{type(e).__name__}: {e}"))


# Dynamic enum items must stay referenced from Python while Blender shows them.
_library_items: list[tuple[str, str, str]] = []


def _writable_library_items(self, context):
    _library_items[:] = [(lib.folder, lib.name, f"Save into {lib.folder}")
                         for lib in preset_library.writable_libraries()]
    if not _library_items:
        _library_items.append(("", "No Writable Library", "Add a preset folder in the add-on preferences"))
    return _library_items


def _default_library() -> P.Library | None:
    libs = preset_library.writable_libraries()
    mine = [lib for lib in libs if lib.name == preset_library.USER_LIBRARY_NAME]
    return (mine or libs or [None])[0]


class LAMP_OT_preset_refresh(bpy.types.Operator):
    bl_idname = "lamp.preset_refresh"
    bl_label = "Refresh Presets"
    bl_description = "List the preset libraries again and make the missing thumbnails"
    bl_options = {"REGISTER"}

    def execute(self, context):
        listing = preset_library.sync(context)
        if listing.warnings:
            reports.say(self, "WARNING", f"{len(listing.warnings)} files are not valid presets; see the list")
        return {"FINISHED"}


class LAMP_OT_preset_apply(bpy.types.Operator):
    bl_idname = "lamp.preset_apply"
    bl_label = "Apply Preset"
    bl_description = "Replace the scene's lamp design with the selected preset (one undo step)"
    bl_options = {"REGISTER", "UNDO"}

    file: StringProperty(name="Preset File", description="A preset of the listed libraries (default: the "
                         "selected one)", options={"HIDDEN", "SKIP_SAVE"})

    @classmethod
    def poll(cls, context):
        if context.scene is None:
            return False
        if selected_entry(context) is None:
            cls.poll_message_set("Select a preset first")
            return False
        return True

    def execute(self, context):
        entry = preset_library.listing().entry(self.file) if self.file else selected_entry(context)
        if entry is None:
            return _failed(self, "Not a preset of the listed libraries; refresh the preset list")
        try:
            # Read again: the file may have changed since it was listed.
            applied = apply_preset_whole(context.scene, P.load_preset(entry.file), entry.file)
        except Exception as e:  # noqa: BLE001 - put back whole; the report says what failed
            return _not_applied(self, "Preset not applied, the design is unchanged", e)
        return reports.finished(self, f"Applied \"{entry.name}\"{applied.short}",
                                [f"Applied \"{entry.name}\" from {entry.library.name}", *applied.details])


class LAMP_OT_preset_save(bpy.types.Operator):
    bl_idname = "lamp.preset_save"
    bl_label = "Save Design as Preset"
    bl_description = "Save the scene's lamp design as a preset in a writable library"
    bl_options = {"REGISTER"}  # writes a file; the .blend data is not changed

    name: StringProperty(name="Name", description="Name of the preset; its file name follows from it")
    author: StringProperty(name="Author")
    description: StringProperty(name="Description")
    tags: StringProperty(name="Tags", description="Keywords, separated by commas")
    library: EnumProperty(name="Library", items=_writable_library_items,
                          description="The library to save into")
    overwrite: BoolProperty(name="Replace Existing", default=False, options={"SKIP_SAVE"},
                            description="Replace the preset of the same file name in that library")

    @classmethod
    def poll(cls, context):
        if context.scene is None:
            return False
        if not preset_library.writable_libraries():
            cls.poll_message_set("No writable preset library: list the presets, or add a folder in the preferences")
            return False
        return True

    def _target(self) -> tuple[P.Library | None, str]:
        lib = preset_library.library_by_folder(self.library)
        if lib is None or not self.name.strip():
            return lib, ""
        return lib, P.preset_file(lib, P.slug(self.name) + P.SUFFIX)

    def invoke(self, context, event):
        design = context.scene.lamp_design
        self.name, self.author, self.description, self.tags = design.design_name, design.author, design.description, \
            design.tags
        lib = _default_library()
        if lib is not None:
            self.library = lib.folder
        return context.window_manager.invoke_props_dialog(self, width=420)

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        for key in ("name", "author", "description", "tags", "library"):
            layout.prop(self, key)
        _, path = self._target()
        if path and os.path.lexists(path):
            box = layout.box()
            box.label(text=f"{os.path.basename(path)} exists in this library", icon="ERROR")
            box.prop(self, "overwrite")

    def execute(self, context):
        lib, path = self._target()
        if lib is None:
            return _failed(self, "Choose a writable library to save into")
        if not path:
            return _failed(self, "Give the preset a name")
        try:
            scene = design_as_seen(context.scene)
            scene["author"], scene["description"], scene["tags"] = self.author, self.description, \
                _split_tags(self.tags)
            entry = P.save_preset(lib, self.name.strip(), scene, overwrite=self.overwrite)
        except P.PresetExistsError:
            return _exists(self, path)
        except (SceneError, OSError) as e:
            return _failed(self, "Preset not saved", e)
        preset_library.sync(context, select=entry.file)
        return reports.finished(self, f"Saved \"{entry.name}\" to {entry.file}{_parts_left_out(context.scene)}")


class _WritableSelected:
    @classmethod
    def poll(cls, context):
        entry = selected_entry(context)
        if entry is None:
            cls.poll_message_set("Select a preset first")
            return False
        if not entry.library.writable:
            cls.poll_message_set(f"The library \"{entry.library.name}\" is read-only")
            return False
        return True


class LAMP_OT_preset_delete(_WritableSelected, bpy.types.Operator):
    bl_idname = "lamp.preset_delete"
    bl_label = "Delete Preset"
    bl_description = "Delete the selected preset file from its library"
    bl_options = {"REGISTER"}

    def invoke(self, context, event):
        entry = selected_entry(context)
        return context.window_manager.invoke_confirm(
            self, event, title="Delete Preset", confirm_text="Delete", icon="WARNING",
            message=f"Delete \"{entry.name}\" ({os.path.basename(entry.file)}) from {entry.library.name}?")

    def execute(self, context):
        entry = selected_entry(context)
        try:
            P.delete_preset(entry)
        except (SceneError, OSError) as e:
            return _failed(self, "Preset not deleted", e)
        preset_library.sync(context)
        return reports.finished(self, f"Deleted \"{entry.name}\"")


class LAMP_OT_preset_rename(_WritableSelected, bpy.types.Operator):
    bl_idname = "lamp.preset_rename"
    bl_label = "Rename Preset"
    bl_description = "Give the selected preset a new name (and the matching file name)"
    bl_options = {"REGISTER"}

    new_name: StringProperty(name="New Name")
    overwrite: BoolProperty(name="Replace Existing", default=False, options={"SKIP_SAVE"},
                            description="Replace a preset that already has the new file name")

    def invoke(self, context, event):
        self.new_name = selected_entry(context).name
        return context.window_manager.invoke_props_dialog(self, width=360)

    def execute(self, context):
        entry = selected_entry(context)
        if not self.new_name.strip():
            return _failed(self, "Give the preset a name")
        try:
            renamed = P.rename_preset(entry, self.new_name.strip(), overwrite=self.overwrite)
        except P.PresetExistsError as e:
            return _exists(self, e.path)
        except (SceneError, OSError) as e:
            return _failed(self, "Preset not renamed", e)
        preset_library.sync(context, select=renamed.file)
        return {"FINISHED"}


class LAMP_OT_preset_import(bpy.types.Operator, ImportHelper):
    bl_idname = "lamp.preset_import"
    bl_label = "Import Lamp Preset"
    bl_description = "Open a lamp-scene/1 preset file: apply it to the design and add it to your presets"
    bl_options = {"REGISTER", "UNDO"}

    filename_ext = ".json"
    filter_glob: StringProperty(default="*.json", options={"HIDDEN"})
    apply: BoolProperty(name="Apply to Design", default=True, description="Replace the scene's lamp design")
    add_to_library: BoolProperty(name="Add to My Presets", default=True,
                                 description="Keep a copy in your own preset library")
    overwrite: BoolProperty(name="Replace Existing", default=False, options={"SKIP_SAVE"},
                            description="Replace a preset of the same name in your library")

    def invoke(self, context, event):
        if self.properties.is_property_set("filepath"):  # dropped on the viewport: no file browser
            return context.window_manager.invoke_props_dialog(self, title=os.path.basename(self.filepath),
                                                              confirm_text="Import")
        return ImportHelper.invoke(self, context, event)

    def execute(self, context):
        if not self.apply and not self.add_to_library:
            return _failed(self, "Nothing to do: tick Apply to Design or Add to My Presets")
        try:
            scene = P.load_preset(self.filepath)
            if "freeform" in scene:  # its meshes are part of it: a missing or bad .glb refuses it
                freeform_loading.read_parts(self.filepath, scene)
        except SceneError as e:
            return _failed(self, "Not imported", e)
        if "freeform" in scene and self.add_to_library:
            # The library keeps JSON files; its .glb would have to travel with it under its own name.
            return _failed(self, "A free-form design is not added to a library here: untick Add to My "
                                 "Presets, or copy its .json and .glb into a library folder")
        lib = _default_library() if self.add_to_library else None
        overwrite = self.overwrite
        if self.add_to_library:
            if lib is None:
                return _failed(self, "No writable preset library to add the preset to; untick Add to My "
                                     "Presets")
            target = P.preset_file(lib, P.slug(scene["name"]) + P.SUFFIX)
            if os.path.lexists(target) and not overwrite:
                try:
                    same = P.digest(P.load_preset(target)) == P.digest(scene)
                except SceneError:
                    same = False
                if not same:
                    return _failed(self, f"{target} exists already with another design; tick \"Replace "
                                         "Existing\" or rename the preset first")
                overwrite = True  # the very same design: saving again changes nothing
        view, more = "", []
        if self.apply:
            try:
                applied = apply_preset_whole(context.scene, scene, self.filepath)
                view, more = applied.short, applied.details
            except Exception as e:  # noqa: BLE001 - put back whole; the report says what failed
                return _not_applied(self, "Not imported, the design is unchanged", e)
        if lib is not None:
            try:
                entry = P.save_preset(lib, scene["name"], scene, overwrite=overwrite)
            except (SceneError, OSError) as e:
                reports.say(self, "WARNING", f"Applied, but not added to {lib.name}: {_error_text(e)}")
                return {"FINISHED"}
            preset_library.sync(context, select=entry.file)
        return reports.finished(self, f"Imported \"{scene['name']}\"{view}", more)


class LAMP_OT_preset_export(bpy.types.Operator, ExportHelper):
    bl_idname = "lamp.preset_export"
    bl_label = "Export Lamp Preset"
    bl_description = "Write the scene's lamp design to a lamp-scene/1 preset file"
    bl_options = {"REGISTER"}

    filename_ext = ".json"
    filter_glob: StringProperty(default="*.json", options={"HIDDEN"})

    def invoke(self, context, event):
        if not self.filepath:
            self.filepath = P.slug(context.scene.lamp_design.design_name) + self.filename_ext
        return ExportHelper.invoke(self, context, event)

    def execute(self, context):
        try:
            scene = design_as_seen(context.scene)
            fileio.atomic_write_text(self.filepath, scene_to_json(scene))
        except (SceneError, OSError) as e:
            return _failed(self, "Not exported", e)
        left_out = _parts_left_out(context.scene)
        return reports.finished(self, f"Exported \"{scene['name']}\" to {self.filepath}{left_out}")


class LAMP_FH_preset(bpy.types.FileHandler):
    """Drop a lamp preset (.json) on the 3D Viewport to import it."""

    bl_idname = "LAMP_FH_preset"
    bl_label = "Lamp design preset"
    bl_import_operator = "lamp.preset_import"
    bl_file_extensions = ".json"

    @classmethod
    def poll_drop(cls, context):
        return context.area is not None and context.area.type == "VIEW_3D"


classes = (
    LAMP_OT_preset_refresh,
    LAMP_OT_preset_apply,
    LAMP_OT_preset_save,
    LAMP_OT_preset_delete,
    LAMP_OT_preset_rename,
    LAMP_OT_preset_import,
    LAMP_OT_preset_export,
    LAMP_FH_preset,
)

register, unregister = bpy.utils.register_classes_factory(classes)

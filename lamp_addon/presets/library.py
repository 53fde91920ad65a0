# SPDX-License-Identifier: GPL-3.0-or-later
"""The preset libraries as Blender sees them, and their thumbnails made in the background.

The libraries are the built-in presets (read-only, inside the extension), the designer's own
folder (the extension's per-user storage) and the extra folders of the add-on preferences. The
listing itself is ``core_tracer.presets``: bpy-free, bounded against hostile files.

Thumbnails are rendered by the tracer on one worker thread that never touches ``bpy``; a timer on
the main thread loads finished PNGs into a ``bpy.utils.previews`` collection and redraws the
sidebar, so opening the panel never waits for a render.
"""

from __future__ import annotations

import os
import queue
import tempfile
import threading
from dataclasses import dataclass, field

import bpy
import bpy.utils.previews
from bpy.app.handlers import persistent
from bpy.props import BoolProperty, CollectionProperty, IntProperty, StringProperty

from ...core_tracer.library import presets as P
from .. import image_view, preferences
from ..jobs import POLL_SECONDS  # the thumbnail timer polls as often as the modal jobs

USER_LIBRARY_NAME = "My Presets"


@dataclass
class Listing:
    """The last listing of every library."""

    libraries: list[P.Library] = field(default_factory=list)
    entries: list[P.PresetEntry] = field(default_factory=list)
    warnings: list[P.PresetWarning] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)  # about libraries as a whole (e.g. no user folder)
    loaded: bool = False
    stale: bool = True

    def entry(self, file: str) -> P.PresetEntry | None:
        for e in self.entries:
            if e.file == file:
                return e
        return None


_listing = Listing()
_thumbnails: Thumbnails | None = None


# ---------------------------------------------------------------------------------------------
# Libraries


def _user_path(path: str) -> tuple[str | None, str]:
    """A folder of the extension's per-user storage, or None and why not."""
    try:
        return bpy.utils.extension_path_user(preferences.ADDON_PACKAGE, path=path, create=True), ""
    except ValueError:
        return None, ("Lamp Styling is not installed as an extension, so it has no per-user folder; "
                      "install it from its zip or add a preset folder in the preferences")
    except OSError as e:
        return None, f"Cannot create the per-user folder ({e.strerror or e})"


def user_library() -> tuple[P.Library | None, str]:
    folder, why = _user_path("presets")
    return (P.Library(USER_LIBRARY_NAME, folder, writable=True) if folder else None), why


def thumbnail_cache() -> str:
    """Where thumbnails of read-only libraries go: the extension's user storage, else the temp folder."""
    folder, _ = _user_path("thumbnails")
    if folder is None:
        folder = os.path.join(tempfile.gettempdir(), "lamp_styling-thumbnails")
    return folder


def libraries(context=None) -> tuple[list[P.Library], list[str]]:
    """Every library in browser order, and notes about the ones that cannot be used."""
    libs = [P.builtin_library()]
    notes: list[str] = []
    user, why = user_library()
    if user is not None:
        libs.append(user)
    else:
        notes.append(why)
    prefs = preferences.get(context)
    for item in prefs.library_folders if prefs is not None else ():
        if not item.directory:
            continue
        folder = os.path.normpath(bpy.path.abspath(item.directory))
        if any(os.path.normpath(lib.folder) == folder for lib in libs):
            continue  # the same folder twice would list every preset twice
        if not os.path.isdir(folder):
            notes.append(f"{item.name or folder}: the folder {folder} does not exist")
            continue
        writable = not item.read_only and os.access(folder, os.W_OK)
        libs.append(P.Library(item.name or os.path.basename(folder), folder, writable))
    return libs, notes


def writable_libraries() -> list[P.Library]:
    return [lib for lib in _listing.libraries if lib.writable]


def library_by_folder(folder: str) -> P.Library | None:
    for lib in _listing.libraries:
        if lib.folder == folder:
            return lib
    return None


def listing() -> Listing:
    return _listing


def mark_stale() -> None:
    """The libraries changed (preferences, another file): list them again soon, outside any draw."""
    _listing.stale = True
    if not bpy.app.timers.is_registered(_sync_timer):
        bpy.app.timers.register(_sync_timer, first_interval=0.1)


def _sync_timer() -> None:
    if _thumbnails is not None:  # still registered
        sync(bpy.context)


@persistent
def _file_loaded(_dummy) -> None:
    mark_stale()


class LAMP_PG_preset_item(bpy.types.PropertyGroup):
    """One listed preset, as the browser's list shows it (the file is the key into the listing)."""

    author: StringProperty(name="Author")
    tags: StringProperty(name="Tags")
    library: StringProperty(name="Library")
    description: StringProperty(name="Description")
    file: StringProperty(name="File", subtype="FILE_PATH")
    writable: BoolProperty(name="Writable")


def sync(context=None, select: str | None = None) -> Listing:
    """List the libraries and mirror the presets into ``WindowManager.lamp_presets`` for the browser.

    Keeps the selection on the same file (or moves it to ``select``). Not for ``draw`` code, which
    may not write to Blender data.
    """
    context = context or bpy.context
    wm = context.window_manager
    items = wm.lamp_presets
    current = select
    if current is None and 0 <= wm.lamp_presets_index < len(items):
        current = items[wm.lamp_presets_index].file
    listing = refresh(context)
    items.clear()
    index = 0
    for i, entry in enumerate(listing.entries):
        item = items.add()
        item.name = entry.name
        item.author = entry.author
        item.tags = ", ".join(entry.tags)
        item.library = entry.library.name
        item.description = entry.description
        item.file = entry.file
        item.writable = entry.library.writable
        if entry.file == current:
            index = i
    wm.lamp_presets_index = index
    return listing


def refresh(context=None) -> Listing:
    """List every library again (a few ms per preset) and queue the missing thumbnails."""
    libs, notes = libraries(context)
    entries, warnings = P.list_presets(libs)
    _listing.libraries, _listing.entries, _listing.warnings, _listing.notes = libs, entries, warnings, notes
    _listing.loaded, _listing.stale = True, False
    if _thumbnails is not None:
        _thumbnails.request(entries)
    return _listing


# ---------------------------------------------------------------------------------------------
# Thumbnails


class Thumbnails:
    """Thumbnail PNGs made on a worker thread, shown through a previews collection."""

    def __init__(self) -> None:
        self.previews = bpy.utils.previews.new()
        self.cache = thumbnail_cache()
        self.paths: dict[str, str] = {}  # preset file -> its thumbnail path (which carries the preset's hash)
        self.errors: dict[str, str] = {}  # thumbnail path -> why it could not be made
        self._jobs: queue.Queue = queue.Queue()
        self._done: queue.Queue = queue.Queue()
        self._queued: set[str] = set()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.view = None  # the view transform thumbnails are shown through, found on first request

    def path(self, entry: P.PresetEntry) -> str:
        return P.thumbnail_path(entry, self.cache)

    def request(self, entries: list[P.PresetEntry]) -> None:
        """Show the thumbnails that exist; queue the others for the worker (where it can write them)."""
        can_write = image_view.openimageio_available()
        if can_write and self.view is None:
            self.view = image_view.thumbnail_view()  # here, on the main thread: the worker never touches bpy
        for entry in entries:
            path = self.path(entry)
            self.paths[entry.file] = path
            if path in self.previews or path in self._queued or path in self.errors:
                continue
            if os.path.isfile(path):
                self._show(path)
            elif not can_write:
                self.errors[path] = f"No thumbnail: {image_view.NO_OPENIMAGEIO}"
            else:
                self._queued.add(path)
                self._jobs.put((entry, path))
        if self._queued:
            self._start()

    def missing_reason(self, file: str) -> str:
        """Why the preset ``file`` has no thumbnail and will get none ("" while it is being made)."""
        return self.errors.get(self.paths.get(file, ""), "")

    def icon_id(self, file: str) -> int:
        preview = self.previews.get(self.paths.get(file, ""))
        return preview.icon_id if preview is not None else 0

    def busy(self) -> bool:
        return bool(self._queued)

    def poll(self) -> int:
        """Main thread: load the thumbnails finished since the last call; returns how many."""
        count = 0
        while True:
            try:
                path, error = self._done.get_nowait()
            except queue.Empty:
                return count
            self._queued.discard(path)
            if error:
                self.errors[path] = error
            else:
                self._show(path)
                count += 1

    def wait(self, timeout: float = 60.0) -> None:
        """Block until every queued thumbnail is made, then load them (for scripts and tests)."""
        if self._thread is not None and self._thread.is_alive():
            done = threading.Event()
            self._jobs.put((None, done))
            done.wait(timeout)
        self.poll()

    def close(self) -> None:
        self._stop.set()
        self._jobs.put(None)
        if self._thread is not None:
            self._thread.join(timeout=5.0)
        bpy.utils.previews.remove(self.previews)

    def _show(self, path: str) -> None:
        if path in self.previews:
            return
        self.previews.load(path, path, "IMAGE")

    def _start(self) -> None:
        if self._thread is None or not self._thread.is_alive():
            self._thread = threading.Thread(target=self._work, name="lamp-preset-thumbnails", daemon=True)
            self._thread.start()
        if not bpy.app.timers.is_registered(_poll_timer):
            bpy.app.timers.register(_poll_timer, first_interval=POLL_SECONDS)

    def _work(self) -> None:
        # No bpy here: the tracer and OpenImageIO only.
        while not self._stop.is_set():
            job = self._jobs.get()
            if job is None:
                return
            entry, path = job
            if entry is None:  # a marker from wait()
                path.set()
                continue
            try:
                P.make_thumbnail(entry, path, view=self.view)
                self._done.put((path, ""))
            except Exception as e:  # noqa: BLE001 - a thumbnail that fails is reported, never fatal
                self._done.put((path, f"{type(e).__name__}: {e}"))


def thumbnails() -> Thumbnails | None:
    return _thumbnails


def _poll_timer() -> float | None:
    if _thumbnails is None:
        return None
    if _thumbnails.poll():
        _redraw_sidebars()
    return POLL_SECONDS if _thumbnails.busy() else None


def _redraw_sidebars() -> None:
    wm = bpy.context.window_manager
    for window in wm.windows if wm is not None else ():
        for area in window.screen.areas:
            if area.type == "VIEW_3D":
                area.tag_redraw()


classes = (LAMP_PG_preset_item,)

_WM_PROPERTIES = {
    "lamp_presets": lambda: CollectionProperty(type=LAMP_PG_preset_item, name="Lamp Presets"),
    "lamp_presets_index": lambda: IntProperty(name="Selected Preset", min=0),
    "lamp_preset_search": lambda: StringProperty(
        name="Search", description="Show the presets whose name, author, tags, library or description "
                                   "contain every word", options={"TEXTEDIT_UPDATE"}),
    "lamp_preset_show_warnings": lambda: BoolProperty(name="Show Problems", default=False),
}


_register_classes, _unregister_classes = bpy.utils.register_classes_factory(classes)


def register() -> None:
    global _thumbnails, _listing
    _register_classes()
    for key, make in _WM_PROPERTIES.items():
        setattr(bpy.types.WindowManager, key, make())
    _listing = Listing()
    _thumbnails = Thumbnails()
    bpy.app.handlers.load_post.append(_file_loaded)
    preferences.library_listeners.append(mark_stale)
    bpy.app.timers.register(_sync_timer, first_interval=0.5)  # list once the UI runs, never in register


def unregister() -> None:
    global _thumbnails
    if mark_stale in preferences.library_listeners:
        preferences.library_listeners.remove(mark_stale)
    for timer in (_poll_timer, _sync_timer):
        if bpy.app.timers.is_registered(timer):
            bpy.app.timers.unregister(timer)
    if _file_loaded in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.remove(_file_loaded)
    if _thumbnails is not None:
        _thumbnails.close()
        _thumbnails = None
    for key in reversed(_WM_PROPERTIES):
        delattr(bpy.types.WindowManager, key)
    _unregister_classes()

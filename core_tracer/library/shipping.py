"""A library prepared for shipping: its ``thumbnails/`` folder checked against its presets as they
are now (``check_shipped_thumbnails``) and brought up to date on purpose
(``make_shipped_thumbnails``; ``python -m core_tracer presets thumbnails`` for the built-in
presets). Using a library, and the thumbnails made on demand, is ``presets``'s."""

from __future__ import annotations

import os
from dataclasses import dataclass

from ..images import display
from ..scene.safe_text import printable
from . import presets as P


@dataclass(frozen=True)
class ShippedThumbnails:
    """How a library's ``thumbnails/`` folder stands against its presets."""

    folder: str
    missing: tuple[P.PresetEntry, ...]  # presets without a thumbnail of their current content
    stale: tuple[str, ...]  # PNG files of no current preset (an old hash, a removed preset)
    warnings: tuple[P.PresetWarning, ...]  # library files that are not valid presets

    @property
    def ok(self) -> bool:
        return not (self.missing or self.stale or self.warnings)

    def problems(self) -> list[str]:
        """One line per problem, each saying what to do."""
        lines = [f"{printable(e.file)}: has no thumbnail {P.thumbnail_name(e)} in {printable(self.folder)}"
                 for e in self.missing]
        lines += [f"{printable(os.path.join(self.folder, name))}: belongs to no current preset"
                  for name in self.stale]
        lines += [str(w) for w in self.warnings]
        return lines


def check_shipped_thumbnails(library: P.Library) -> ShippedThumbnails:
    """Compare a library's shipped ``thumbnails/`` folder with its presets as they are now."""
    entries, warnings = P.list_library(library)
    folder = P.own_subfolder(library, P.SHIPPED_THUMBNAIL_FOLDER)
    if folder is None:
        raise P.PresetError(printable(os.path.join(library.folder, P.SHIPPED_THUMBNAIL_FOLDER)),
                            "is a link that leads out of the library; a library's thumbnails are its own")
    missing = tuple(e for e in entries if P.shipped_thumbnail(e) is None)
    wanted = {P.thumbnail_name(e) for e in entries}
    try:
        names = sorted(os.listdir(folder))
    except (FileNotFoundError, NotADirectoryError):
        names = []
    stale = tuple(n for n in names if n.lower().endswith(".png") and n not in wanted and not n.startswith("."))
    return ShippedThumbnails(folder, missing, stale, tuple(warnings))


def make_shipped_thumbnails(library: P.Library,
                            size: int = P.THUMBNAIL_SIZE) -> tuple[list[str], list[str], list[P.PresetWarning]]:
    """Make the missing thumbnails of ``thumbnails/`` and remove the stale ones, on purpose.

    Writes into the library's folder whatever its ``writable`` flag says: this is how a library is
    prepared for shipping. Returns the thumbnails made, the files removed and the warnings about
    files that are not valid presets (which get no thumbnail)."""
    state = check_shipped_thumbnails(library)
    view = display.view_transform(display.DEFAULT_VIEW)
    if view.note and state.missing:  # shipped thumbnails must look as their name says
        raise P.PresetError(printable(state.folder), f"cannot make shipped thumbnails: {view.note}")
    os.makedirs(state.folder, exist_ok=True)
    made = []
    for entry in state.missing:
        path = P.make_thumbnail(entry, os.path.join(state.folder, P.thumbnail_name(entry)), size, view=view)
        os.chmod(path, 0o644)  # shipped to everyone who installs the library, whatever this umask is
        made.append(path)
    removed = []
    for name in state.stale:
        path = os.path.join(state.folder, name)
        if os.path.isfile(path) or os.path.islink(path):
            os.unlink(path)
            removed.append(path)
    return made, removed, list(state.warnings)

"""Rendered cells kept by content: ``<folder>/<key[:2]>/<key>.npy``, one file per cell key.

A re-run, a study resumed after a crash or extended by one axis value, and the trials an
optimisation repeats find their images here and render only what is new. Files are written
atomically (a ``.part`` file renamed into place) as each cell arrives, so a crash loses at most
the cells under way, and a damaged file is rendered again.

The folder is kept below ``MAX_BYTES`` (``prune``, after each run): the cells used least recently go
first (reading a cell marks it used).
"""

from __future__ import annotations

import os
import sys

import numpy as np

from ..raytrace.world_cache import ENV_FOLDER
from ..scene.safe_text import printable

SUBFOLDER = "cells"
MAX_BYTES = 4 * 2**30  # the cache's size after a prune: a 64-variant study of 2048 px is 3.2 GB


def default_folder() -> str:
    """``$LAMP_STYLING_CACHE/cells``, else ``$XDG_CACHE_HOME`` or ``~/.cache``, then ``lamp-styling/cells``."""
    root = os.environ.get(ENV_FOLDER)
    if not root:
        base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
        root = os.path.join(base, "lamp-styling")
    return os.path.join(root, SUBFOLDER)


class CellCache:
    def __init__(self, folder: str | os.PathLike | None = None):
        self.folder = os.fspath(folder) if folder is not None else default_folder()

    def path(self, key: str) -> str:
        return os.path.join(self.folder, key[:2], f"{key}.npy")

    def get(self, key: str, size: tuple[int, int] | None = None) -> np.ndarray | None:
        """The image kept under ``key``: float32 (H, W, 3), (H, W) = ``size`` when given, finite; None
        when there is none. A damaged cell is dropped with one line on stderr, and rendered again."""
        shape = (size[1], size[0], 3) if size is not None else (None, None, 3)
        return self._read(key, dtype=np.float32, shape=shape)

    def _read(self, key: str, **checks) -> np.ndarray | None:
        from .. import arrays, budget

        path = self.path(key)
        try:
            array = arrays.read_npy_file(path, max_bytes=budget.MEMORY_BUDGET, **checks)
        except IsADirectoryError:  # a folder in the cell's place: dropped like a damaged cell
            why = "is a folder"
        except OSError:  # missing, or the folder itself unusable: rendered again, and keeping it says why
            return None
        except arrays.BadArray as e:  # cut short or tampered: render it again
            why = str(e)
        else:
            self._used(key)
            return array
        dropped = "dropped" if self._drop(path) else "left in place (cannot remove it)"
        print(f"cache: cell {key[:12]} in {printable(self.folder, 80)} {why}; {dropped}, rendering it again",
              file=sys.stderr)
        return None

    def ready(self, option: str = "--cache") -> None:
        """Before any work: the folder exists (made now if need be) and may be written, else a one-line
        ``SceneError`` naming ``option`` and the cause (issue 33: it was "cannot reach the scheduler")."""
        from ..fileio import check_writable
        from ..scene.reading import SceneError

        try:
            os.makedirs(self.folder, exist_ok=True)
            check_writable(os.path.join(self.folder, "probe"))
        except (OSError, ValueError) as e:
            cause = e.strerror if isinstance(e, OSError) and e.strerror else str(e)
            raise SceneError(option, f"{printable(self.folder, 80)!r} cannot hold the cache ({cause}); allowed a "
                                     "folder you may write to") from None

    @staticmethod
    def _drop(path: str) -> bool:
        try:
            if os.path.isdir(path) and not os.path.islink(path):
                os.rmdir(path)
            else:
                os.unlink(path)
        except OSError:
            return False
        return True

    def _used(self, key: str) -> None:
        try:
            os.utime(self.path(key))
        except OSError:
            pass

    def put(self, key: str, image: np.ndarray) -> None:
        self.put_array(key, np.asarray(image, dtype=np.float32))

    def get_array(self, key: str) -> np.ndarray | None:
        """Any array kept under ``key`` (a trial's lamp mask, say), finite, or None (a damaged one dropped)."""
        return self._read(key)

    def put_array(self, key: str, array: np.ndarray) -> None:
        """Keep ``array`` under ``key``; one holding NaN or inf is not kept (the writers refuse it)."""
        if array.dtype.kind in "fc" and not np.isfinite(array).all():
            return
        path = self.path(key)
        os.makedirs(os.path.dirname(path), exist_ok=True)
        partial = f"{path}.{os.getpid()}.part.npy"
        try:
            np.save(partial, array)
            os.replace(partial, path)
        except BaseException:
            if os.path.exists(partial):
                os.unlink(partial)
            raise

    def prune(self, max_bytes: int = MAX_BYTES) -> int:
        """Remove the least recently used cells until the folder holds at most ``max_bytes``; the
        bytes removed."""
        files = []
        for root, _, names in os.walk(self.folder):
            for name in names:
                if name.endswith(".npy") and ".part." not in name:
                    path = os.path.join(root, name)
                    try:
                        st = os.stat(path)
                    except OSError:
                        continue
                    files.append((st.st_mtime, st.st_size, path))
        total = sum(size for _, size, _ in files)
        removed = 0
        for _, size, path in sorted(files):
            if total - removed <= max_bytes:
                break
            try:
                os.unlink(path)
            except OSError:
                continue
            removed += size
        return removed

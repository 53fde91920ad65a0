"""Enable Lamp Styling from this source tree in a running Blender (or the bpy module), without a zip.

Used by ``tools/compare_preset.py`` and by the tests' ``addon`` fixture: a temporary development
extension repository holds a link to the source tree (a copy of what the zip would hold where links
are not allowed), and the add-on is enabled from it as ``bl_ext.<repo>.lamp_styling``. Call it only
after ``import bpy``; set ``BLENDER_USER_RESOURCES`` before that to keep Blender's configuration out of
the user's home.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from collections.abc import Iterator

EXTENSION_ID = "lamp_styling"
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def _raise(e: BaseException) -> None:
    raise e


@contextlib.contextmanager
def enabled_from_source(bpy, repo_module: str, *, reuse_enabled: bool = True,
                        strict: bool = False) -> Iterator[str]:
    """Yield the package name of the enabled extension: an already enabled Lamp Styling when
    ``reuse_enabled``, else this source tree through the development repository ``repo_module``.

    On exit the repository is removed, which disables its add-ons. ``strict`` (the tests) disables
    the add-on explicitly instead and raises what its ``unregister`` raised; the repository then
    stays registered until the process ends (removing it would disable the add-on a second time).
    """
    import addon_utils

    prefs = bpy.context.preferences
    if reuse_enabled:
        enabled = [a.module for a in prefs.addons if a.module.rsplit(".", 1)[-1] == EXTENSION_ID]
        if enabled:
            yield enabled[0]
            return
    folder = tempfile.mkdtemp(prefix="lamp-dev-repo-")
    try:
        try:
            os.symlink(ROOT, os.path.join(folder, EXTENSION_ID), target_is_directory=True)
        except OSError:  # no symlinks (Windows without the privilege): copy what the zip would hold
            shutil.copytree(ROOT, os.path.join(folder, EXTENSION_ID),
                            ignore=shutil.ignore_patterns(".*", "__pycache__", "tests", "tools", "out", "dist"))
        repo = prefs.extensions.repos.new(name=repo_module, module=repo_module, custom_directory=folder,
                                          source="USER")
        package = f"bl_ext.{repo_module}.{EXTENSION_ID}"
        addon_utils.enable(package, default_set=True, handle_error=_raise)
        try:
            yield package
        finally:
            if strict:
                addon_utils.disable(package, default_set=True, handle_error=_raise)
            else:
                prefs.extensions.repos.remove(repo)
    finally:
        shutil.rmtree(folder, ignore_errors=True)


@contextlib.contextmanager
def blender_with_addon(repo_module: str) -> Iterator[tuple]:
    """For the tools that draw or build with the add-on: ``bpy`` imported with Blender's configuration in a
    temporary folder (``BLENDER_USER_RESOURCES``, unless set), Lamp Styling enabled from this tree
    (``enabled_from_source``); yields ``(bpy, lamp_addon, core_tracer)`` as the extension has them."""
    import sys

    os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix=f"{repo_module}-"))
    import bpy

    with enabled_from_source(bpy, repo_module) as package:
        yield bpy, sys.modules[f"{package}.lamp_addon"], sys.modules[f"{package}.core_tracer"]

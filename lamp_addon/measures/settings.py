# SPDX-License-Identifier: GPL-3.0-or-later
"""``Scene.lamp_measures``: where the last measures of this file are, and how the panel shows them.

The result itself is the ``measures.json`` of that folder (``core_tracer.measures``), read again
when the file changes; nothing else of the measures is stored in the .blend.
"""

from __future__ import annotations

import json
import os

import bpy
from bpy.props import BoolProperty, StringProperty

from ..scene_settings import SceneSettings

_read: dict[str, tuple[float, dict]] = {}  # measures.json path -> (its mtime, its contents)


class LAMP_PG_measures(SceneSettings, bpy.types.PropertyGroup):
    scene_attribute = "lamp_measures"
    scene_name = "Lamp Measures"
    scene_description = "The design's measures (intensity grids, colour, homogeneity)"

    folder: StringProperty(name="Folder", subtype="DIR_PATH", options=set(),
                           description="The folder of the last measures (measures.json, measures.png)")
    beam_files: BoolProperty(name="Beam Files", default=False,
                             description="Also write each function's beam as IES and EULUMDAT files (a (C, γ) sweep: "
                                         "about a third longer)")
    show_all: BoolProperty(name="Show Every Row", default=False,
                           description="Every test point of the table, not only the failed ones and the figures")


def output_folder(blend_path: str, temporary: str) -> str:
    """Where the measures go: ``<name>_measures`` next to a saved .blend, else ``temporary``."""
    if not blend_path:
        return temporary
    stem = os.path.splitext(os.path.basename(blend_path))[0]
    return os.path.join(os.path.dirname(os.path.abspath(blend_path)), f"{stem}_measures")


def last_measures(scene) -> dict | None:
    """The contents of the last measures.json of ``scene``, or None when there is none (or it is unreadable)."""
    folder = scene.lamp_measures.folder
    if not folder:
        return None
    path = os.path.join(bpy.path.abspath(folder), "measures.json")
    try:
        mtime = os.path.getmtime(path)
        cached = _read.get(path)
        if cached is None or cached[0] != mtime:
            with open(path, encoding="utf-8") as f:
                _read[path] = (mtime, json.load(f))
        return _read[path][1]
    except (OSError, ValueError):
        return None


classes = (LAMP_PG_measures,)


register, unregister = bpy.utils.register_classes_factory(classes)

# SPDX-License-Identifier: GPL-3.0-or-later
"""The settings every scene holds for one part of the add-on (the study, the optimisation, the
measures, the Light Panel): a property group attached to ``bpy.types.Scene`` when it registers and
detached when it unregisters."""

from __future__ import annotations

import bpy
from bpy.props import PointerProperty


class SceneSettings:
    """Mix in before ``bpy.types.PropertyGroup``; every scene holds one as ``scene_attribute``
    (e.g. ``lamp_study``), named and described in Blender's data API by ``scene_name`` and
    ``scene_description``."""

    scene_attribute = ""
    scene_name = ""
    scene_description = ""

    @classmethod
    def register(cls):
        setattr(bpy.types.Scene, cls.scene_attribute,
                PointerProperty(type=cls, name=cls.scene_name, description=cls.scene_description))

    @classmethod
    def unregister(cls):
        delattr(bpy.types.Scene, cls.scene_attribute)

# SPDX-License-Identifier: GPL-3.0-or-later
"""The Blender side of Lamp Styling: everything that touches ``bpy``.

Each module owns its classes and its ``register``/``unregister``. They are registered in the
order of ``modules`` (properties before the operators and panels that use them) and unregistered
in reverse. To add a module, import it here and append it to ``modules``.
"""

from . import (
    camera,
    compare,
    engine,
    ops_design,
    ops_render,
    panels,
    preset_browser,
    properties,
    study_ops,
    study_panel,
)

modules = (
    properties,
    ops_design,
    panels,
    camera, engine, ops_render, compare,
    preset_browser,
    study_panel, study_ops,
)


def register() -> None:
    for module in modules:
        module.register()


def unregister() -> None:
    for module in reversed(modules):
        module.unregister()

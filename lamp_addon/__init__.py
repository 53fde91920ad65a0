# SPDX-License-Identifier: GPL-3.0-or-later
"""The Blender side of Lamp Styling: everything that touches ``bpy``.

Modules are grouped by feature: ``design_*`` (the design's properties, panel, operators and the
object builder), ``render_*`` (the Lamp Tracer engine, its camera and render operator),
``compare_*`` (tracer and Cycles side by side), ``preset_*`` and ``preferences`` (libraries),
``study_*`` (contact sheets), ``freeform_*`` (lamp roles on the designer's own meshes, their
rendering, Convert to Free-form and export). ``convert`` is the bpy-free layer they share.

Each module owns its classes and its ``register``/``unregister``. They are registered in the
order of ``modules()`` (properties before the operators and panels that use them) and
unregistered in reverse. The imports happen in ``modules()`` so that ``lamp_addon.convert``
can be imported without Blender.
"""


def modules() -> tuple:
    """Every module that registers, in registration order."""
    from . import (
        compare_ops,
        design_autobuild,
        design_ops,
        design_panels,
        design_properties,
        display_ops,
        freeform_geometry,
        freeform_ops,
        freeform_panel,
        freeform_properties,
        preferences,
        preset_library,
        preset_ops,
        preset_panel,
        render_camera,
        render_engine,
        render_ops,
        study_ops,
        study_panel,
        study_settings,
    )

    return (
        design_properties,
        design_ops,
        design_autobuild,
        design_panels,
        freeform_properties, freeform_geometry, freeform_ops, freeform_panel,
        render_camera, render_engine, render_ops, compare_ops, display_ops,
        preferences, preset_library, preset_ops, preset_panel,
        study_settings, study_panel, study_ops,
    )


def register() -> None:
    for module in modules():
        module.register()


def unregister() -> None:
    for module in reversed(modules()):
        module.unregister()

"""The buttons of the Lamp tab's actions area (Build, Frame, Render, Compare, ...).

A module whose operators show there registers them with ``register_actions_factory`` (or
``add_action``); the design panel draws ``ACTION_OPERATORS`` in order. The buttons of the add-on
stand in the order of ``ORDER`` whichever sub-package registers first; others follow in the order
they were added. This module sits below both the panels and the operators, so an operator module
never depends on a panel module.
"""

from __future__ import annotations

import bpy

ACTION_OPERATORS: list[tuple[str, str, str]] = [("lamp.build", "Build Lamp", "MESH_CYLINDER")]
ORDER = ("lamp.build", "lamp.frame_design", "lamp.hide_others", "lamp.render_tracer", "lamp.compare_cycles",
         "lamp.exposure_from_design", "lamp.lamp_view")


def add_action(idname: str, text: str, icon: str = "NONE") -> None:
    """Show operator ``idname`` as a button in the actions area (call from a module's ``register``)."""
    remove_action(idname)
    rank = ORDER.index(idname) if idname in ORDER else len(ORDER)
    at = next((i for i, (other, _, _) in enumerate(ACTION_OPERATORS)
               if rank < (ORDER.index(other) if other in ORDER else len(ORDER))), len(ACTION_OPERATORS))
    ACTION_OPERATORS.insert(at, (idname, text, icon))


def remove_action(idname: str) -> None:
    ACTION_OPERATORS[:] = [entry for entry in ACTION_OPERATORS if entry[0] != idname]


def register_actions_factory(classes: tuple[type, ...], actions: tuple[tuple[str, str, str], ...]):
    """``register``/``unregister`` of a module whose operators show as buttons in the actions area:
    ``bpy.utils.register_classes_factory(classes)`` plus ``add_action`` of each (idname, text, icon)
    of ``actions`` (in order), taken away again in reverse."""
    register_classes, unregister_classes = bpy.utils.register_classes_factory(classes)

    def register() -> None:
        register_classes()
        for action in actions:
            add_action(*action)

    def unregister() -> None:
        for idname, _text, _icon in reversed(actions):
            remove_action(idname)
        unregister_classes()

    return register, unregister

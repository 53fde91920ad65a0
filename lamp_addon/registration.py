"""Registering a package's modules, as ``bpy.utils.register_classes_factory`` registers classes.

Each sub-package of the add-on lists the modules that register in its ``modules()`` (properties
before the operators and panels that use them) and takes ``register``/``unregister`` from
``modules_factory``: every module's ``register`` in that order, every ``unregister`` in reverse, so
registering is symmetric and can be repeated. Errors are not caught: Blender reports them.
Unlike ``bpy.utils.register_submodule_factory`` the modules stay imported after ``unregister``,
so state that tests and handlers hold keeps its identity across a re-register.
"""

from __future__ import annotations

from collections.abc import Callable
from types import ModuleType


def modules_factory(modules: Callable[[], tuple[ModuleType, ...]]) -> tuple[Callable[[], None], Callable[[], None]]:
    """``register``/``unregister`` calling those of each module of ``modules()``, in order and in reverse."""

    def register() -> None:
        for module in modules():
            module.register()

    def unregister() -> None:
        for module in reversed(modules()):
            module.unregister()

    return register, unregister

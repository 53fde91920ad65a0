# SPDX-License-Identifier: GPL-3.0-or-later
"""Optimisation from Blender: ``settings`` (``Scene.lamp_optimise``), ``panel`` (the Optimise section
of the Lamp tab) and ``ops`` (running the search, applying the best trial to the design).
"""

from ..registration import modules_factory


def modules() -> tuple:
    """The modules that register, in order: the settings before the panel and operators."""
    from . import ops, panel, settings

    return (settings, panel, ops)


register, unregister = modules_factory(modules)

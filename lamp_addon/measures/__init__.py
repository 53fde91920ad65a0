"""Measures of the design: ``settings`` (``Scene.lamp_measures``), ``ops`` (running the ``measure``
command as a modal job, opening its page) and ``panel`` (the Measures section of the Lamp tab).
"""

from ..registration import modules_factory


def modules() -> tuple:
    """The modules that register, in order: the settings before the operators and the panel."""
    from . import ops, panel, settings

    return (settings, ops, panel)


register, unregister = modules_factory(modules)

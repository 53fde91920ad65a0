"""Measures of the design: ``settings`` (``Scene.lamp_measures``), ``ops`` (running the ``measure``
command as a modal job, opening its page), ``panel`` (the Measures section of the Lamp tab) and
``light_panel`` (the Light Panel: lighting states switched and dimmed without rendering).
"""

from ..registration import modules_factory


def modules() -> tuple:
    """The modules that register, in order: the settings before the operators and the panel."""
    from . import light_panel, ops, panel, settings

    return (settings, ops, panel, light_panel)


register, unregister = modules_factory(modules)

"""Design studies: ``settings`` (``Scene.lamp_study``), ``panel`` (the Study section of the Lamp tab)
and ``ops`` (running a study and using its contact sheet).
"""

from ..registration import modules_factory


def modules() -> tuple:
    """The modules that register, in order: the settings before the panel and operators."""
    from . import ops, panel, settings

    return (settings, panel, ops)


register, unregister = modules_factory(modules)

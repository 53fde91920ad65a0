"""Design studies: ``settings`` (``Scene.lamp_study``), ``panel`` (the Study section of the Lamp tab),
``ops`` (running a study and using its contact sheet) and ``meshes`` (a free-form design's mesh file).
"""

from ..registration import modules_factory


def modules() -> tuple:
    """The modules that register, in order: the settings before the panel and operators."""
    from . import meshes, ops, panel, settings

    return (settings, meshes, panel, ops)


register, unregister = modules_factory(modules)

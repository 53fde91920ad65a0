"""The preset libraries: ``library`` (the libraries as Blender sees them and their thumbnails),
``apply`` (what applying a preset does to the scene, all or nothing, with ``state``), ``ops`` (apply,
save, rename, delete, import, export, drop) and ``panel`` (the preset browser).
"""

from ..registration import modules_factory


def modules() -> tuple:
    """The modules that register, in order."""
    from . import library, ops, panel

    return (library, ops, panel)


register, unregister = modules_factory(modules)

"""Rendering with the paper's tracer: the Lamp Tracer engine behind F12 and the viewport's Rendered
shading, the scene camera both renderers use, Render with Lamp Tracer and Exposure from Design.

- ``camera``: the scene camera and Frame Lamp; ``setup``: what a file needs to show the lamp.
- ``engine``: the ``RenderEngine``; ``viewport`` and ``preview``: its viewport session and the
  preview's stages.
- ``ops``: Render with Lamp Tracer (a modal job); ``exposure``: Exposure from Design.
"""

from ..registration import modules_factory


def modules() -> tuple:
    """The modules that register, in order."""
    from . import camera, engine, exposure, ops

    return (camera, engine, ops, exposure)


register, unregister = modules_factory(modules)

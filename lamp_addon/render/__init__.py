"""Rendering with the paper's tracer: the Lamp Tracer engine behind F12 and the viewport's Rendered
shading, Render with Lamp Tracer and Exposure from Design.

- The scene camera both renderers use is the design's (``design.camera``, ``design.lamp_camera``,
  ``design.view_link``, ``design.setup``); here ``camera_sync``'s handlers keep it live, and
  ``camera_ops`` and ``camera_panel`` are Frame Lamp, Copy Scene Camera to Design and the Scene
  Camera area.
- ``engine``: the ``RenderEngine``; ``viewport`` and ``preview``: its viewport session and the
  preview's stages.
- ``ops``: Render with Lamp Tracer (a modal job); ``exposure``: Exposure from Design.
"""

from ..registration import modules_factory


def modules() -> tuple:
    """The modules that register, in order."""
    from . import camera_ops, camera_panel, camera_sync, engine, exposure, ops

    return (camera_ops, camera_panel, camera_sync, engine, ops, exposure)


register, unregister = modules_factory(modules)

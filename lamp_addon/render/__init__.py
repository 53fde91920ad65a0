"""Rendering with the paper's tracer: the Lamp Tracer engine behind F12 and the viewport's Rendered
shading, the scene camera both renderers use, Render with Lamp Tracer and Exposure from Design.

- ``camera``: the scene camera, read and written in the design's space; ``lamp_camera``: the add-on's
  own camera, made and framed; ``view_link``: the design's view and the Lamp Camera kept equal,
  live through ``camera_sync``'s handlers; ``camera_ops`` and ``camera_panel``: Frame Lamp, Copy
  Scene Camera to Design and the Scene Camera area; ``setup``: what a file needs to show the lamp.
- ``engine``: the ``RenderEngine``; ``viewport`` and ``preview``: its viewport session and the
  preview's stages.
- ``ops``: Render with Lamp Tracer (a modal job); ``exposure``: Exposure from Design; ``view_frame``:
  the 3D View framed on the lamp, Hide Other Objects.
"""

from ..registration import modules_factory


def modules() -> tuple:
    """The modules that register, in order."""
    from . import camera_ops, camera_panel, camera_sync, engine, exposure, ops, view_frame

    return (camera_ops, camera_panel, camera_sync, engine, ops, exposure, view_frame)


register, unregister = modules_factory(modules)

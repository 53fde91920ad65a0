"""The design: its properties on the scene, the Lamp tab's panels, the operators that edit it, and
the builder that makes the lamp's objects from it.

- ``properties``: ``Scene.lamp_design``, generated from the core spec; ``validity``: whether it is
  valid and which property to change; ``operator``: the base of the operators that work on it.
- ``ops``: add and remove lamps, Build Lamp; ``autobuild``: the objects follow the design's edits.
- ``parts`` (what a lamp is made of), ``materials`` (its Cycles materials), ``builder`` (the parts
  as Blender objects under the root, ``root``).
- ``panels``: the Lamp tab of the 3D Viewport sidebar.
- How the design is seen: ``camera`` (the scene camera read and written in the design's space),
  ``lamp_camera`` (the add-on's own camera, made and framed), ``view_link`` (the design's view and
  the Lamp Camera kept equal), ``setup`` (what a file needs to show the lamp), ``view_frame`` (the
  3D View framed on the lamp, Hide Other Objects).
"""

from ..registration import modules_factory


def modules() -> tuple:
    """The modules that register, in order: the properties before what uses them."""
    from . import autobuild, ops, panels, properties, view_frame

    return (properties, ops, autobuild, panels, view_frame)


register, unregister = modules_factory(modules)

"""Free-form parts: lamp roles on the designer's own mesh objects, rendered by the free-form tracer.

- ``properties``: ``Object.lamp_role`` and its values; ``materials``: their Cycles materials.
- ``meshes``: the parts as meshes in the design's frame; ``parametric``: the built parametric lamps
  as meshes with their roles; ``geometry``: the parts' geometry, made once per change.
- ``scene``: the ``lamp-scene/2`` document; ``render``: which tracer renders, with which meshes;
  ``status``: what the panel says above its list.
- ``conversion`` and ``solids``: Convert to Free-form; ``export``: the JSON and ``.glb`` for
  headless use; ``loading``: a free-form preset's parts brought into Blender; ``written``: the
  parts written for the worker processes of a study or a measure.
- ``ops``: the operators; ``panel``: the Free-form Parts sub-panel.
"""

from ..registration import modules_factory


def modules() -> tuple:
    """The modules that register, in order: the properties before what uses them."""
    from . import geometry, ops, panel, properties, written

    return (properties, geometry, written, ops, panel)


register, unregister = modules_factory(modules)

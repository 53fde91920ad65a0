# SPDX-License-Identifier: GPL-3.0-or-later
"""The Blender side of Lamp Styling: everything that touches ``bpy``, in rooms by what the designer does.

- ``design``: the design's properties, the Lamp tab's panels, the operators that edit it and the
  builder that makes the lamp's objects (Auto Build keeps them up to date).
- ``render``: the Lamp Tracer engine (F12 and the viewport's Rendered shading), the scene camera
  both renderers use, Render with Lamp Tracer and Exposure from Design.
- ``compare``: the tracer and Cycles side by side, from the panel and headless.
- ``presets``: the preset libraries, their browser and operators.
- ``study``: design studies and their contact sheets.
- ``optimise``: optimisations (Optuna) and applying what they found.
- ``measures``: the design's measures (regulation grids, colour, homogeneity) and their report.
- ``freeform``: lamp roles on the designer's own meshes, their rendering, Convert to Free-form and
  export.
- ``convert``: the bpy-free layer they share (units, camera mathematics, Cycles numbers, meshes).

Shared by several rooms: ``preferences`` (the add-on's preferences, found through ``__package__``),
``actions`` (the buttons of the actions area), ``jobs`` (modal jobs), ``reports``, ``image_view``,
``registration``.

Each sub-package lists the modules that register in its ``modules()``; this package registers the
sub-packages in the order of ``modules()`` (the design's properties before everything that uses
them) and unregisters them in reverse. The imports happen in ``modules()`` so that
``lamp_addon.convert`` can be imported without Blender.
"""

from .registration import modules_factory


def modules() -> tuple:
    """Every sub-package (or module) that registers, in registration order."""
    from . import compare, design, freeform, measures, optimise, preferences, presets, render, study

    return (design, freeform, render, compare, preferences, presets, study, optimise, measures)


register, unregister = modules_factory(modules)

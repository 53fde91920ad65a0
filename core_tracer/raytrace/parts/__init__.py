"""The parts of a lamp, one module per part type (docs/model.md §3), each a ``base.Part``: the surface
it is, the media it can be reached from, and ``intersect``. The tracer finds a ray's next surface
by walking ``PARTS``, each part given the rays of its media, so a new part type is a new module
and one entry in ``PARTS``; no loop changes.

Order matters in one way: each part is given the nearest hit of the parts before it as a limit,
and the cut walk stops there, so the side wall, which bounds the cuts, comes first; only the housing of
a prism-plate lamp precedes it (the same cylinder behind the plate: the tie keeps the housing).
The prism plate's faces come before the cuts: a ray inside the plate or behind it then gives the cut
walk a limit short of the cuts, and the walk does nothing for it (the plate and the cuts never touch:
the plate's gap is > 0). The cheap closed-form parts of the air (reflector, bulb, socket) come before
the walk too: an air ray bound for the bulb or the reflector then never walks the cells. Ties keep the
earlier part (the cuts touch none of those). The body box (``body_box``) is not in the table: only
eye rays, in the world frame, meet it.
"""

from __future__ import annotations

from . import (
    bulb,
    cut_surface,
    guide_led,
    housing,
    light_guide,
    outer_face,
    plate_front,
    prism_rings,
    reflector,
    side_wall,
    socket,
)
from .base import Part

# ``cut_surface`` hands each ray to its lamp's cut type: ``cuts`` (fish-eye), ``sawtooth`` or ``flutes``.
PARTS: tuple[Part, ...] = (housing, side_wall, plate_front, prism_rings, reflector, bulb, socket, light_guide,
                           guide_led, cut_surface, outer_face)


def parts_for(lamps) -> tuple[Part, ...]:
    """``PARTS`` for these lamps: without the prism plate's parts when no lamp has a plate, nor the
    light guide's when no lamp has a guide (every ray would only find ``inf`` there, at the cost of
    their gathers)."""
    unused = () if lamps.ring_count.any() else (housing, plate_front, prism_rings)
    unused += () if lamps.guide is not None else (light_guide, guide_led)
    return tuple(part for part in PARTS if part not in unused)

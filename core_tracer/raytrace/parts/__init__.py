"""The parts of a lamp, one module per part type (docs/model.md §3), each a ``base.Part``: the surface
it is, the media it can be reached from, and ``intersect``. The tracer finds a ray's next surface
by walking ``PARTS``, each part given the rays of its media, so a new part type is a new module
and one entry in ``PARTS``; no loop changes.

Order matters in one way: each part is given the nearest hit of the parts before it as a limit,
and the cut walk stops there, so the side wall, which bounds the cuts, comes first; only the housing of
a prism-plate lamp precedes it (the same cylinder behind the plate: the tie keeps the housing).
The prism plate's faces come before the cuts: a ray inside the plate or behind it then gives the cut
walk a limit short of the cuts, and the walk does nothing for it (the plate and the cuts never touch:
the plate's gap is > 0). The cheap closed-form parts of the air (reflector, bulb, socket, LED dies) come before
the walk too: an air ray bound for the bulb or the reflector then never walks the cells. Ties keep the
earlier part (the cuts touch none of those). The body box (``body_box``) is not in the table: only
eye rays, in the world frame, meet it.
"""

from __future__ import annotations

from . import (
    bulb,
    cut_surface,
    housing,
    led_die,
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
PARTS: tuple[Part, ...] = (housing, side_wall, plate_front, prism_rings, reflector, bulb, socket, led_die,
                           light_guide, cut_surface, outer_face)


def parts_for(lamps) -> tuple[Part, ...]:
    """``PARTS`` for these lamps: without the prism plate's parts when no lamp has a plate, without
    the LED dies when no lamp has LEDs, without the bulb and socket when every lamp has LEDs, without
    the light guide when no lamp has one (every ray would only find ``inf`` there, at the cost of
    their gathers)."""
    left_out: set = set()
    if not lamps.ring_count.any():
        left_out |= {housing, plate_front, prism_rings}
    if not lamps.any_leds:
        left_out.add(led_die)
    if not lamps.has_bulb.any():
        left_out |= {bulb, socket}
    if lamps.guide is None:
        left_out.add(light_guide)
    return tuple(part for part in PARTS if part not in left_out)

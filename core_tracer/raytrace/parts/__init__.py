"""The parts of a lamp, one module per part type (MODEL.md §3), each a ``base.Part``: the surface
it is, the media it can be reached from, and ``intersect``. The tracer finds a ray's next surface
by walking ``PARTS``, each part given the rays of its media, so a new part type is a new module
and one entry in ``PARTS``; no loop changes.

Order matters in one way: each part is given the nearest hit of the parts before it as a limit,
and the cut walk stops there, so the side wall, which bounds the cuts, comes first, and the cheap
closed-form parts of the air (reflector, bulb, socket) come before the walk: an air ray bound for
the bulb or the reflector then never walks the cells. Ties keep the earlier part (the cuts touch
none of those three). The body box (``body_box``) is not in the table: only eye rays, in the world frame,
meet it.
"""

from __future__ import annotations

from . import bulb, cuts, outer_face, reflector, side_wall, socket
from .base import Part

PARTS: tuple[Part, ...] = (side_wall, reflector, bulb, socket, cuts, outer_face)

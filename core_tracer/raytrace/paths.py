"""The twelve elementary light paths of the paper (§3.2.2, Fig. 8, Table 1).

Every ray segment inside a lamp belongs to one class, fixed by the medium it travels in, the
surface it leaves and the surface it reaches (``CLASS_OF``). What happens at its end follows from
the same medium and surface: absorption for the segments inside the lens (② ⑥ ⑧, and ⑦ from
inside), reflector scattering at ③ ④, terminal luminance at ⑦ ⑩ ⑪ ⑫.
"""

from __future__ import annotations

import numpy as np

# Path classes (the paper's circled numbers).
OUTSIDE_TO_LENS = 1  # ① outside -> lens outer face
LENS_OUTER_TO_CUT = 2  # ② lens outer face -> cut face, inside the lens
CUT_TO_REFLECTOR = 3  # ③ cut face -> reflector (air)
REFLECTOR_TO_REFLECTOR = 4  # ④
REFLECTOR_TO_CUT = 5  # ⑤ reflector -> cut face (air)
CUT_TO_LENS_OUTER = 6  # ⑥ cut face -> outer face, inside the lens
TO_SIDE_WALL = 7  # ⑦ -> lens side wall (ends)
CUT_TO_CUT_IN_LENS = 8  # ⑧
CUT_TO_CUT_IN_AIR = 9  # ⑨ between lenslets, in the air
LENS_OUTER_TO_OUTSIDE = 10  # ⑩ leaves the lamp (ends, background)
TO_BULB = 11  # ⑪ (ends)
TO_SOCKET = 12  # ⑫ (ends)

# Table 1: for each incident class, the classes its reflected and its transmitted ray can be.
TABLE_1: dict[int, tuple[frozenset[int], frozenset[int]]] = {
    1: (frozenset({10}), frozenset({2, 7})),
    2: (frozenset({6, 7, 8}), frozenset({3, 9, 11, 12})),
    3: (frozenset({4, 5, 11, 12}), frozenset()),
    4: (frozenset({4, 5, 11, 12}), frozenset()),
    5: (frozenset({3, 9, 11, 12}), frozenset({6, 7, 8})),
    6: (frozenset({2, 7}), frozenset({10})),
    7: (frozenset(), frozenset()),
    8: (frozenset({6, 7, 8}), frozenset({3, 9, 11, 12})),
    9: (frozenset({3, 9, 11, 12}), frozenset({6, 7, 8})),
    10: (frozenset(), frozenset()),
    11: (frozenset(), frozenset()),
    12: (frozenset(), frozenset()),
}

# Table 1 lists ⑦ only after rays inside the lens. With the cuts clipped by the side wall, the
# wall also shows a thin band to the air between the clipped cut surface and the reflector rim
# (plus any reflector gap); air rays that reach it end there as ⑦ too. These are the only
# transitions the tracer adds to Table 1 (see README, "Where the model is completed").
AIR_SIDE_WALL: dict[int, tuple[frozenset[int], frozenset[int]]] = {
    2: (frozenset(), frozenset({7})),
    3: (frozenset({7}), frozenset()),
    4: (frozenset({7}), frozenset()),
    5: (frozenset({7}), frozenset()),
    8: (frozenset(), frozenset({7})),
    9: (frozenset({7}), frozenset()),
}

ENDS = frozenset({7, 10, 11, 12})

REFLECTED, TRANSMITTED = 0, 1


def allowed(parent: int, branch: int, child: int) -> bool:
    """Whether a transition is one of Table 1's (or the documented air side-wall band)."""
    extra = AIR_SIDE_WALL.get(parent, (frozenset(), frozenset()))
    return child in TABLE_1[parent][branch] or child in extra[branch]


# Surfaces a segment can start from or reach, used to classify it.
OUTER, CUT, REFLECTOR, WALL, BULB, SOCKET, NOTHING = range(7)
IN_LENS, IN_AIR = 0, 1


def _build_lookup() -> np.ndarray:
    """CLASS_OF[medium, source surface, hit surface] -> path class (0 = impossible)."""
    table = np.zeros((2, 7, 7), dtype=np.int8)
    table[IN_LENS, OUTER, CUT] = LENS_OUTER_TO_CUT
    table[IN_LENS, OUTER, WALL] = TO_SIDE_WALL
    table[IN_LENS, CUT, OUTER] = CUT_TO_LENS_OUTER
    table[IN_LENS, CUT, CUT] = CUT_TO_CUT_IN_LENS
    table[IN_LENS, CUT, WALL] = TO_SIDE_WALL
    for src in (CUT, REFLECTOR):
        table[IN_AIR, src, BULB] = TO_BULB
        table[IN_AIR, src, SOCKET] = TO_SOCKET
        table[IN_AIR, src, WALL] = TO_SIDE_WALL
    table[IN_AIR, CUT, REFLECTOR] = CUT_TO_REFLECTOR
    table[IN_AIR, REFLECTOR, REFLECTOR] = REFLECTOR_TO_REFLECTOR
    table[IN_AIR, CUT, CUT] = CUT_TO_CUT_IN_AIR
    table[IN_AIR, REFLECTOR, CUT] = REFLECTOR_TO_CUT
    return table


CLASS_OF = _build_lookup()

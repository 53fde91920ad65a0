"""The twelve elementary light paths of the paper (§3.2.2, Fig. 8, Table 1), and the prism plate's
seven more (⑬-⑲, ``PLATE_TABLE``, docs/model.md: the prism plate).

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
# transitions the tracer adds to Table 1 (see docs/model.md, "Where the model is completed").
AIR_SIDE_WALL: dict[int, tuple[frozenset[int], frozenset[int]]] = {
    2: (frozenset(), frozenset({7})),
    3: (frozenset({7}), frozenset()),
    4: (frozenset({7}), frozenset()),
    5: (frozenset({7}), frozenset()),
    8: (frozenset(), frozenset({7})),
    9: (frozenset({7}), frozenset()),
}

# The prism plate's classes (docs/model.md, "Where the model is completed": the prism plate), numbered on
# from the paper's twelve. A prism-plate lamp has no reflector (③ ④ ⑤ never occur); between the
# lens and the bulb stands a transparent plate, flat toward the lens (its front face) and carrying
# the prism rings toward the bulb, inside a housing that ends paths like the socket. Rays reach the
# bulb (⑪) and the socket (⑫) from the air behind the plate, and the lens side wall (⑦) from the
# air between lens and plate.
CUT_TO_PLATE = 13  # ⑬ cut face -> plate front face, in the air between lens and plate
PLATE_TO_CUT = 14  # ⑭ plate front face -> cut face, in that air
PLATE_FRONT_TO_RINGS = 15  # ⑮ inside the plate
RINGS_TO_PLATE_FRONT = 16  # ⑯ inside the plate
RINGS_TO_RINGS_IN_PLATE = 17  # ⑰ from one ring face to another, inside the plate
RINGS_TO_RINGS_IN_AIR = 18  # ⑱ between the rings, in the air behind the plate
TO_HOUSING = 19  # ⑲ -> the housing behind the plate (ends)

# Table 1 continued for the plate: for each incident class, the classes its reflected and its
# transmitted ray can be. For the paper's classes only the children the plate adds are listed
# (a ray leaving a cut face into the air can now meet the plate: ⑬).
#
# | #  | segment                                | reflected ray can be | transmitted ray can be |
# |----|----------------------------------------|----------------------|------------------------|
# | ②  | (the paper's)                          |                      | + ⑬                    |
# | ⑧  | (the paper's)                          |                      | + ⑬                    |
# | ⑨  | (the paper's)                          | + ⑬                  |                        |
# | ⑬  | cut face -> plate front (air)          | ⑦ ⑭                  | ⑮ ⑲                    |
# | ⑭  | plate front -> cut face (air)          | ⑦ ⑨ ⑬                | ⑥ ⑦ ⑧                  |
# | ⑮  | plate front -> rings, in the plate     | ⑯ ⑰ ⑲                | ⑪ ⑫ ⑱ ⑲                |
# | ⑯  | rings -> plate front, in the plate     | ⑮ ⑲                  | ⑦ ⑭                    |
# | ⑰  | rings -> rings, in the plate           | ⑯ ⑰ ⑲                | ⑪ ⑫ ⑱ ⑲                |
# | ⑱  | rings -> rings, in the air behind      | ⑪ ⑫ ⑱ ⑲              | ⑯ ⑰ ⑲                  |
# | ⑲  | -> housing                             | ends                 |                        |
PLATE_TABLE: dict[int, tuple[frozenset[int], frozenset[int]]] = {
    2: (frozenset(), frozenset({13})),
    8: (frozenset(), frozenset({13})),
    9: (frozenset({13}), frozenset()),
    13: (frozenset({7, 14}), frozenset({15, 19})),
    14: (frozenset({7, 9, 13}), frozenset({6, 7, 8})),
    15: (frozenset({16, 17, 19}), frozenset({11, 12, 18, 19})),
    16: (frozenset({15, 19}), frozenset({7, 14})),
    17: (frozenset({16, 17, 19}), frozenset({11, 12, 18, 19})),
    18: (frozenset({11, 12, 18, 19}), frozenset({16, 17, 19})),
    19: (frozenset(), frozenset()),
}

# The light guide's classes (docs/model.md §8.7a), numbered on from the plate's. A guide lamp has no
# prism plate: its rod is the lamp's second dielectric (IN_GUIDE is the plate's medium). Its LEDs are
# the lamp's own dies (``LED``): a ray leaving the rod that reaches them is ⑪, as the bulb.
AIR_TO_GUIDE = 20  # ⑳ from any surface of the lamp's air to the guide's surface
IN_GUIDE_SEGMENT = 21  # ㉑ from the guide's surface to itself, inside the rod
GUIDE_TO_LAMP = 22  # ㉒ from the guide's surface to the lamp's other parts (or its LEDs: ⑪), in the air
LAST_CLASS = GUIDE_TO_LAMP  # classes that only meshes have are numbered after it (``freeform.render``)


def _guide_table() -> dict[int, tuple[frozenset[int], frozenset[int]]]:
    """Table 1 continued for the guide: every branch that goes on in the lamp's air can meet the rod
    (⑳); the rod's surface reflects into the medium the ray came from and transmits into the other;
    ㉒ reaches the lamp's other parts as the air classes that reach them do."""
    air = {3, 4, 5, 9, 11, 12, 13, 14, 18}
    table: dict[int, tuple[frozenset[int], frozenset[int]]] = {}
    for source in (TABLE_1, PLATE_TABLE):
        for parent, branches in source.items():
            table[parent] = tuple(frozenset({AIR_TO_GUIDE}) if children & air else frozenset()
                                  for children in branches)
    into_air = frozenset({AIR_TO_GUIDE, TO_BULB, GUIDE_TO_LAMP})
    table[AIR_TO_GUIDE] = (into_air, frozenset({IN_GUIDE_SEGMENT}))
    table[IN_GUIDE_SEGMENT] = (frozenset({IN_GUIDE_SEGMENT}), into_air)
    # ㉒ reaches a cut (as ⑤ does), the reflector (as ④), or ends on the wall, bulb or socket
    table[GUIDE_TO_LAMP] = (frozenset({3, 4, 5, 7, 9, 11, 12, 13, AIR_TO_GUIDE}), frozenset({6, 7, 8}))
    return table


GUIDE_TABLE = _guide_table()

ENDS = frozenset({7, 10, 11, 12, 19})

REFLECTED, TRANSMITTED = 0, 1

_NONE = (frozenset(), frozenset())


def allowed(parent: int, branch: int, child: int) -> bool:
    """Whether a transition is one of Table 1's, the documented air side-wall band's, or the
    prism plate's continuation of Table 1."""
    return any(child in table.get(parent, _NONE)[branch]
               for table in (TABLE_1, AIR_SIDE_WALL, PLATE_TABLE, GUIDE_TABLE))


# Surfaces a segment can start from or reach, used to classify it (the plate's after the paper's).
OUTER, CUT, REFLECTOR, WALL, BULB, SOCKET, NOTHING, PLATE_FRONT, RINGS, HOUSING, LED, GUIDE = range(12)
SURFACES = GUIDE + 1  # how many there are: a free-form body is numbered after them (``freeform.geometry.BODY``)
# LED: a lamp's LED dies, the light source in place of the bulb: reaching them is ⑪ as the bulb
IN_LENS, IN_AIR, IN_PLATE = 0, 1, 2
IN_GUIDE = IN_PLATE  # a lamp has a prism plate or a light guide, never both: the guide's rod is its second dielectric


def _build_lookup() -> np.ndarray:
    """CLASS_OF[medium, source surface, hit surface] -> path class (0 = impossible)."""
    table = np.zeros((3, SURFACES, SURFACES), dtype=np.int8)
    table[IN_LENS, OUTER, CUT] = LENS_OUTER_TO_CUT
    table[IN_LENS, OUTER, WALL] = TO_SIDE_WALL
    table[IN_LENS, CUT, OUTER] = CUT_TO_LENS_OUTER
    table[IN_LENS, CUT, CUT] = CUT_TO_CUT_IN_LENS
    table[IN_LENS, CUT, WALL] = TO_SIDE_WALL
    for src in (CUT, REFLECTOR, RINGS):
        table[IN_AIR, src, LED] = TO_BULB
    for src in (CUT, REFLECTOR):
        table[IN_AIR, src, BULB] = TO_BULB
        table[IN_AIR, src, SOCKET] = TO_SOCKET
        table[IN_AIR, src, WALL] = TO_SIDE_WALL
    table[IN_AIR, CUT, REFLECTOR] = CUT_TO_REFLECTOR
    table[IN_AIR, REFLECTOR, REFLECTOR] = REFLECTOR_TO_REFLECTOR
    table[IN_AIR, CUT, CUT] = CUT_TO_CUT_IN_AIR
    table[IN_AIR, REFLECTOR, CUT] = REFLECTOR_TO_CUT
    # the prism plate (PLATE_TABLE)
    table[IN_AIR, CUT, PLATE_FRONT] = CUT_TO_PLATE
    table[IN_AIR, PLATE_FRONT, CUT] = PLATE_TO_CUT
    table[IN_AIR, PLATE_FRONT, WALL] = TO_SIDE_WALL
    table[IN_PLATE, PLATE_FRONT, RINGS] = PLATE_FRONT_TO_RINGS
    table[IN_PLATE, RINGS, PLATE_FRONT] = RINGS_TO_PLATE_FRONT
    table[IN_PLATE, RINGS, RINGS] = RINGS_TO_RINGS_IN_PLATE
    table[IN_AIR, RINGS, RINGS] = RINGS_TO_RINGS_IN_AIR
    table[IN_AIR, RINGS, BULB] = TO_BULB
    table[IN_AIR, RINGS, SOCKET] = TO_SOCKET
    for medium, src in ((IN_PLATE, PLATE_FRONT), (IN_PLATE, RINGS), (IN_AIR, RINGS)):
        table[medium, src, HOUSING] = TO_HOUSING
    # the light guide
    table[IN_AIR, :, GUIDE] = AIR_TO_GUIDE
    table[IN_GUIDE, GUIDE, GUIDE] = IN_GUIDE_SEGMENT
    table[IN_AIR, GUIDE, LED] = TO_BULB
    for surface in (CUT, REFLECTOR, WALL, BULB, SOCKET, PLATE_FRONT, HOUSING):
        table[IN_AIR, GUIDE, surface] = GUIDE_TO_LAMP
    return table


CLASS_OF = _build_lookup()

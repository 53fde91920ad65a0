"""The parts table the tracer walks: every surface Table 1 lets a segment reach from a medium is
a part reachable from that medium, and nothing else is; the side wall bounds the cut walk."""

from __future__ import annotations

import numpy as np
from helpers import scene_with

from core_tracer.raytrace import paths
from core_tracer.raytrace.lamp_table import LampTable
from core_tracer.raytrace.parts import PARTS, cut_surface, cuts, side_wall
from core_tracer.raytrace.parts.base import Segments


def test_each_medium_reaches_exactly_the_surfaces_of_table_1():
    for medium in (paths.IN_LENS, paths.IN_AIR, paths.IN_PLATE):
        reachable = {int(s) for s in np.nonzero(paths.CLASS_OF[medium].any(axis=0))[0]}
        assert {part.SURFACE for part in PARTS if medium in part.MEDIA} == reachable, medium


def test_every_part_is_one_surface_and_the_side_wall_comes_before_the_cuts():
    assert len({part.SURFACE for part in PARTS}) == len(PARTS)
    assert PARTS.index(side_wall) < PARTS.index(cut_surface)


def test_a_part_reports_no_hit_beyond_its_limit_for_the_cut_walk():
    # A ray from inside the lens at its axis heading for the cuts, stopped just short of them.
    lamps = LampTable.from_scene(scene_with())
    o = np.array([[0.0, 0.0, 0.0]])
    d = np.array([[0.0, 1.0, 0.0]])
    rays = Segments(o, d, np.array([0]), np.array([paths.OUTER], np.int8), np.array([paths.IN_LENS], np.int8))
    t_free, normal = cuts.intersect(rays, lamps, np.array([np.inf]))
    assert t_free[0] == lamps.plane_b[0] and normal[0, 1] == 1.0  # the apex; out of the lens is +y
    t_short, _ = cuts.intersect(rays, lamps, np.array([0.5 * t_free[0]]))
    assert np.isinf(t_short[0])

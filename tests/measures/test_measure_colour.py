"""The colour of a lamp's light (core_tracer.measures.colour): chromaticity against colour-science,
and points inside, on and outside each region of UN R48 §2.29 and SAE J578."""

from __future__ import annotations

import numpy as np
import pytest

from core_tracer.measures import colour as C
from core_tracer.photometry import cie, materials, sources
from core_tracer.photometry.bands import VISIBLE_NM


@pytest.mark.slow
@pytest.mark.parametrize("filter_name", ["red", "amber", "smoke"])
def test_illuminant_a_through_a_filter_is_colour_sciences(colour, filter_name):
    """Illuminant A times a filter's transmittance curve (the project's logistic cut-on at its
    reference thickness): xy within 1e-4 of colour-science's sd_to_XYZ with the CIE 1931 2° CMFs."""
    light = sources.incandescent().times(materials.FILTERS[filter_name].spectrum())
    ours = C.spectrum_xy(light)
    grid = np.arange(VISIBLE_NM[0], VISIBLE_NM[1] + 1.0)
    sd = colour.SpectralDistribution(light.at(grid), grid)
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().trim(colour.SpectralShape(380, 780, 1))
    reference = colour.XYZ_to_xy(colour.sd_to_XYZ(sd, cmfs, method="Integration"))
    np.testing.assert_allclose(ours, reference, atol=1e-4)


def test_j578_vertices_are_r48_corners():
    """SAE J578 (since DEC2006) and UN R48 share their red, amber and white corners."""
    for name, corners in C.SAE_J578_REGIONS.items():
        assert sorted(corners) == sorted(C.REGIONS["UN R48 §2.29"][name])


@pytest.mark.parametrize("regulation", list(C.REGIONS))
@pytest.mark.parametrize("colour_name", ["red", "amber", "white"])
def test_inside_on_and_outside(regulation, colour_name):
    corners = np.asarray(C.REGIONS[regulation][colour_name])
    assert C.inside(corners.mean(axis=0), corners)
    x, y = corners[:, 0], corners[:, 1]
    counter_clockwise = np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y) > 0  # the shoelace's sign
    for a, b in zip(corners, np.roll(corners, -1, axis=0), strict=True):
        mid = (a + b) / 2
        assert C.inside(mid, corners), (mid, "on an edge")
        assert C.inside(a, corners), (a, "a corner")
        edge = (b - a) / np.linalg.norm(b - a)
        outward = np.array([edge[1], -edge[0]]) * (1.0 if counter_clockwise else -1.0)
        assert C.inside(mid - 0.002 * outward, corners), (mid, "just inside")
        assert not C.inside(mid + 0.002 * outward, corners), (mid, "just outside")
        assert C.distance_outside(mid + 0.002 * outward, corners) == pytest.approx(0.002)


def test_known_colours():
    """The red lens's light is red, not amber; illuminant A is white; an amber-coated bulb is amber."""
    red = C.spectrum_xy(sources.incandescent().times(materials.FILTERS["red"].spectrum()))
    assert C.check(red, "red") == {"UN R48 §2.29": True, "SAE J578": True}
    assert C.check(red, "amber") == {"UN R48 §2.29": False, "SAE J578": False}
    white = C.spectrum_xy(sources.incandescent())
    assert C.check(white, "white") == {"UN R48 §2.29": True, "SAE J578": True}
    assert all(C.check(C.spectrum_xy(sources.amber_coated()), "amber").values())
    assert np.allclose(C.xy_of(cie.spectrum_xyz(sources.incandescent())), white)
    with pytest.raises(ValueError, match="signal colour"):
        C.check(white, "green")

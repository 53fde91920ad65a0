"""R48 colour regions: corners and edges inside, neighbours outside, the non-convex white region."""

from __future__ import annotations

import numpy as np
import pytest

from core_tracer.photometry import regulation


@pytest.mark.parametrize("region", regulation.R48_REGIONS)
def test_corners_and_centroid_are_inside(region):
    corners = np.asarray(regulation.R48_REGIONS[region])
    assert np.all(regulation.in_region(corners, region))
    assert regulation.in_region(corners.mean(axis=0), region)


def test_boundaries_of_red_and_amber():
    assert regulation.in_region([0.66, 0.334], "red") and not regulation.in_region([0.66, 0.3351], "red")
    assert not regulation.in_region([0.70, 0.27], "red")  # below the purple boundary y = 0.980 - x
    assert regulation.in_region([0.58, 0.41], "amber")
    assert not regulation.in_region([0.58, 0.40], "amber")  # beyond the white boundary y = 0.790 - 0.670 x
    assert not regulation.in_region([0.60, 0.385], "amber")  # below the red boundary y = 0.390
    assert not regulation.in_region([0.55, 0.435], "amber")  # beyond the green boundary y = x - 0.120


def test_white_region_is_not_convex():
    # the notch between W3-W4-W5: (0.48, 0.36) lies inside the hull, outside the region
    assert not regulation.in_region([0.48, 0.36], "white")
    assert regulation.in_region([0.3127, 0.3290], "white")  # D65
    assert regulation.in_region([0.4476, 0.4074], "white")  # illuminant A


def test_unknown_region():
    with pytest.raises(ValueError, match="red, amber, white"):
        regulation.in_region([0.5, 0.4], "green")

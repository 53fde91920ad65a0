"""Directions of the light a lamp sends out, as a goniometer and the lighting regulations name them.

The lamp's front faces −y (docs/model.md §2). A direction of the emitted light is given by two
angles in degrees, the regulations' H and V (UN R148 and FMVSS 108 give their test points so):
V is the elevation above the horizontal plane (up positive), H the azimuth in that plane from the
lamp's axis −y, positive toward +x:

    d(H, V) = (cos V sin H, −cos V cos H, sin V).

H-V is (0, 0), the axis. This is an (H, V) goniometer whose vertical axis is fixed (type A in
CIE 121's terms: the lamp turns about a vertical axis, then about the tilted horizontal one).
"""

from __future__ import annotations

import math

import numpy as np


def direction(h_deg: float, v_deg: float) -> np.ndarray:
    """The unit vector (3,) of light leaving the lamp at (H, V) degrees."""
    h, v = math.radians(h_deg), math.radians(v_deg)
    return np.array([math.cos(v) * math.sin(h), -math.cos(v) * math.cos(h), math.sin(v)])


def directions(h_deg: np.ndarray, v_deg: np.ndarray) -> np.ndarray:
    """Unit vectors (..., 3) of the (H, V) pairs given as arrays of the same shape."""
    h, v = np.radians(np.asarray(h_deg, dtype=np.float64)), np.radians(np.asarray(v_deg, dtype=np.float64))
    return np.stack([np.cos(v) * np.sin(h), -np.cos(v) * np.cos(h), np.sin(v)], axis=-1)


def angles_of(d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(H, V) in degrees of unit vectors ``d`` (..., 3): the inverse of ``directions``."""
    d = np.asarray(d, dtype=np.float64)
    v = np.degrees(np.arcsin(np.clip(d[..., 2], -1.0, 1.0)))
    h = np.degrees(np.arctan2(d[..., 0], -d[..., 1]))
    return h, v


def cone_solid_angle(half_angle_deg: float) -> float:
    """Solid angle in sr of a cone of the given half angle: 2π (1 − cos α)."""
    return 2.0 * math.pi * (1.0 - math.cos(math.radians(half_angle_deg)))

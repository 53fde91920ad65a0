"""The prism plate's ring profile (docs/model.md, "Where the model is completed": the prism plate).

The plate's back face (toward the bulb) carries concentric rings of pitch p about the lamp axis:
ring k spans the radii [k p, (k + 1) p] (the last one is cut by the lens radius). Each ring is a
conical facet falling from height s_k p above the ring bottoms (plane y = y_base) at its inner
radius to 0 at its outer radius, followed by a vertical (cylindrical) draft face at the next
ring's inner radius. The slope s_k is the classic Fresnel-lens design: the ray from the focus
(on the axis, f behind the ring bottoms) to the facet's point at the ring's mid-radius is
refracted into the direction -y, parallel to the axis, and then crosses the flat front face
unbent. Snell's law in vector form, n1 u - n2 v parallel to the normal, gives the facet normal
N = u - n v for the unit incident direction u and v = (0, -1) in the (radius, y) plane, so

    s_k = u_r / (n + u_y),

where u is taken to the facet's own mid-radius point (at height s_k p / 2): a fixed point,
found by iteration from s = 0 (a contraction: the point moves by s p / 2, a fraction of the
distance to the focus). The tracer and the Blender meshes both take the slopes from here.
"""

from __future__ import annotations

import math

import numpy as np

# The design ray may meet its facet at most this far from the facet's normal: beyond it the facet
# reflects most of the light (Fresnel) and no refraction can bend the ray parallel at all past
# 90 - asin(1/n) degrees from the axis.
MAX_FACET_INCIDENCE_DEG = 85.0
_ITERATIONS = 60  # the fixed point converges to rounding in far fewer; a fixed count is deterministic


def ring_count(radius: float, pitch: float) -> int:
    """Number of rings on a plate of ``radius``: the last one may be cut by the rim."""
    return max(1, math.ceil(radius / pitch - 1e-9))


def ring_slopes(radius: float, pitch: float, focal_length: float, ior: float) -> np.ndarray:
    """The facet slope s_k (height per mm of radius, > 0) of every ring (module docstring)."""
    mid = (np.arange(ring_count(radius, pitch)) + 0.5) * pitch
    s = np.zeros_like(mid)
    for _ in range(_ITERATIONS):
        u_r, u_y = _design_ray(mid, s, pitch, focal_length)
        s = u_r / (ior + u_y)
    return s


def _design_ray(mid: np.ndarray, s: np.ndarray, pitch: float, focal_length: float) -> tuple[np.ndarray, np.ndarray]:
    """Unit direction (radius, y) from the focus to each facet's mid-radius point."""
    dy = 0.5 * s * pitch - focal_length  # facet point y minus focus y (negative: toward the lens)
    length = np.hypot(mid, dy)
    return mid / length, dy / length


def facet_incidence_deg(radius: float, pitch: float, focal_length: float, ior: float) -> np.ndarray:
    """Angle (degrees) between each ring's design ray and its facet's normal."""
    s = ring_slopes(radius, pitch, focal_length, ior)
    u_r, u_y = _design_ray((np.arange(len(s)) + 0.5) * pitch, s, pitch, focal_length)
    n_r, n_y = u_r, u_y + ior  # N = u - n v, pointing out of the plate toward the bulb when entering
    cos_i = -(u_r * n_r + u_y * n_y) / np.hypot(n_r, n_y)
    return np.degrees(np.arccos(np.clip(cos_i, -1.0, 1.0)))


def shortest_focal_length(radius: float, pitch: float, ior: float, focal_hi: float) -> float | None:
    """The shortest focal length (to 2^-30 of the span) for which every ring's design ray meets
    its facet within ``MAX_FACET_INCIDENCE_DEG``; None when not even ``focal_hi`` does."""

    def fits(f: float) -> bool:
        return bool(facet_incidence_deg(radius, pitch, f, ior).max() <= MAX_FACET_INCIDENCE_DEG)

    if not fits(focal_hi):
        return None
    lo, hi = 0.0, focal_hi
    for _ in range(30):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if fits(mid) else (mid, hi)
    return hi

"""Meshes of a lamp's light guide (docs/model.md §8.7a), in the lamp's local frame in mm, bpy-free.

The rod: its cross-section (a polygon of the circle within ``CHORD_TOLERANCE_MM``, or the rectangle)
swept along the axis (straight, or an arc: ``arc_points``), at every s where the prisms' profile
bends: each ring of the sweep is the
section cut by the prisms' height v <= g(s) (points above it lowered onto it, which for a convex
section is exactly the cut), so the V grooves are exact between the rings; both end faces closed.
The guide's LEDs are the lamp's own dies (``design.parts.led_part``).
"""

from __future__ import annotations

import numpy as np

from ....core_tracer.raytrace.guide_table import GuideTable
from .builder import FLAT, MeshBuilder, MeshData, chord_tolerance, circle_segments


def _frame(lamp: dict) -> tuple[GuideTable, np.ndarray, np.ndarray, np.ndarray]:
    guide = GuideTable.from_scene({"lamps": [lamp]})
    return guide, guide.start[0], guide.axis[0], guide.across[0]


def section_polygon(guide: GuideTable) -> np.ndarray:
    """The rod's cross-section (N, 2) [u, v], counter-clockwise seen from +s."""
    hu, hv = float(guide.half_u[0]), float(guide.half_v[0])
    if guide.round[0]:
        n = circle_segments(hu, chord_tolerance())
        a = 2.0 * np.pi * np.arange(n) / n
        # a vertex on the back line v = r, where the prisms cut: the grooves' bottom is a chord there
        return np.stack([hu * np.sin(a), hu * np.cos(a)], axis=1)
    return np.array([[hu, hv], [-hu, hv], [-hu, -hv], [hu, -hv]])


def prism_height(s: np.ndarray, guide: GuideTable) -> np.ndarray:
    """g(s): the highest v of the rod at s (its back, lowered in the grooves)."""
    top = float(guide.half_v[0])
    count = int(guide.prisms[0])
    if count == 0:
        return np.full(np.shape(s), np.inf)
    pitch, first, slope = float(guide.pitch[0]), float(guide.first_prism[0]), float(guide.slope[0])
    k = np.clip(np.floor((np.asarray(s) - first) / pitch + 0.5), 0, count - 1)
    return np.minimum(top, top - float(guide.prism_depth[0]) + slope * np.abs(np.asarray(s) - first - k * pitch))


def sweep_stations(guide: GuideTable, section: np.ndarray) -> np.ndarray:
    """The s of every ring: the ends, each prism's apex and edges, and where a groove facet passes a
    section vertex's height (there a vertex starts or stops being lowered)."""
    length = float(guide.length[0])
    stations = [0.0, length]
    count = int(guide.prisms[0])
    if count:
        pitch, first, slope = float(guide.pitch[0]), float(guide.first_prism[0]), float(guide.slope[0])
        bottom = float(guide.half_v[0] - guide.prism_depth[0])
        heights = np.unique(section[:, 1][section[:, 1] > bottom])
        for k in range(count):
            apex = first + k * pitch
            stations.append(apex)
            for h in heights:
                reach = (h - bottom) / slope
                stations.extend((apex - reach, apex + reach))
    if guide.arc[0]:  # the arc's walls as chords within the tolerance (a full circle's segments, pro rata)
        outer = float(guide.radius[0] + guide.half_u[0])
        step = 2.0 * np.pi * float(guide.radius[0]) / circle_segments(outer, chord_tolerance())
        stations.extend(np.linspace(0.0, length, int(np.ceil(length / step)) + 1))
    return np.unique(np.clip(np.array(stations), 0.0, length))


def arc_points(guide: GuideTable, s: float, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Points of an arc guide's ring at s (lamp frame): within a prism's groove on the planar facets'
    own terms (at τ = s − s_k from the radial plane of its apex, on the cylinder ρ = R − u), elsewhere
    on the radial plane at φ = s / R − Φ/2 (so the end faces are radial)."""
    radius, sweep = float(guide.radius[0]), float(guide.sweep[0])
    centre, a, c = guide.arc_centre[0], guide.axis[0], guide.across[0]
    rho = radius - u
    phi, tau = s / radius - 0.5 * sweep, np.zeros_like(u)
    count = int(guide.prisms[0])
    if count and 0.0 < s < float(guide.length[0]):
        pitch, first = float(guide.pitch[0]), float(guide.first_prism[0])
        k = min(max(int(np.floor((s - first) / pitch + 0.5)), 0), count - 1)
        reach = float(guide.prism_depth[0] / guide.slope[0])
        if abs(s - first - k * pitch) <= reach + 1e-9:
            phi, tau = (first + k * pitch) / radius - 0.5 * sweep, np.full_like(u, s - first - k * pitch)
    t_k = np.cos(phi) * a + np.sin(phi) * c
    r_k = np.sin(phi) * a - np.cos(phi) * c
    along_r = np.sqrt(rho * rho - tau * tau)
    points = centre + along_r[:, None] * r_k + tau[:, None] * t_k
    points[:, 1] = centre[1] + v
    return points


def guide_mesh(lamp: dict) -> MeshData:
    """The rod (normals out of it)."""
    guide, start, axis, across = _frame(lamp)
    section = section_polygon(guide)
    stations = sweep_stations(guide, section)
    mb = MeshBuilder()
    y_axis = np.array([0.0, 1.0, 0.0])
    rings = []
    for s in stations:
        v = np.minimum(section[:, 1], prism_height(np.array([s]), guide)[0])
        if guide.arc[0]:
            points = arc_points(guide, float(s), section[:, 0], v)
        else:
            points = start + s * axis + section[:, :1] * across + v[:, None] * y_axis
        rings.append([mb.vertex(*p) for p in points])
    n = len(section)
    for a, b in zip(rings[:-1], rings[1:], strict=True):
        for j in range(n):
            j1 = (j + 1) % n
            mb.face([a[j], b[j], b[j1], a[j1]], 0 if guide.round[0] else FLAT)
    mb.face(rings[0], FLAT)  # the end faces, turned as the sides are
    mb.face(list(reversed(rings[-1])), FLAT)
    data = mb.result()
    if signed_volume(data) < 0:  # the section's turn in the guide's frame: make the normals point out
        data.faces = [tuple(reversed(face)) for face in data.faces]
    return data


def signed_volume(data: MeshData) -> float:
    """The volume the faces enclose, positive when their normals point out (the divergence theorem
    over a fan of each face)."""
    total = 0.0
    for face in data.faces:
        p0 = data.verts[face[0]]
        for i in range(1, len(face) - 1):
            total += float(np.dot(p0, np.cross(data.verts[face[i]], data.verts[face[i + 1]])))
    return total / 6.0

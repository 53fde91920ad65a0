"""Meshes of a prism-plate lamp (docs/model.md, the prism plate), in the lamp's local frame in mm, bpy-free.

The plate: the flat front face, and the ring face revolved from the profile the tracer uses
(``core_tracer.scene.prism_profile``): per ring the conical facet from its top at the inner radius to
its foot at the outer radius, then the vertical draft up to the next ring's top. The facets and drafts
are straight in profile, so the only chord error is around the axis: ``segments`` (from
``builder.circle_segments(R)``) keeps it within ``CHORD_TOLERANCE_MM`` at the rim, measured anyway.
The plate has no rim face of its own: the housing's cylinder r = R closes it, as in the tracer,
where a ray inside the plate that reaches r = R ends on the housing.

The housing: the cylinder r = R from the plate's front face to its back, and the back disk; normals
toward the lamp interior.
"""

from __future__ import annotations

import math

import numpy as np

from ....core_tracer.scene.derived import lamp_geometry
from ....core_tracer.scene.prism_profile import ring_slopes
from .builder import FLAT, MeshBuilder, MeshData, fan_triangles, triangle_deviation


def ring_profile(lamp: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The ring face's profile from the axis to the rim: radii, heights y, and for each segment
    between consecutive points the ring it belongs to (>= 0, a facet) or -1 - ring (a draft)."""
    plate, R = lamp["prism_plate"], lamp["lens"]["radius"]
    p = plate["pitch"]
    s = ring_slopes(R, p, plate["focal_length"], plate["ior"])
    base = lamp_geometry(lamp)["plate_base"]
    r, y, kind = [0.0], [base + s[0] * p], []
    for k in range(len(s)):
        r_out = min((k + 1) * p, R)
        r.append(r_out)
        y.append(base + s[k] * ((k + 1) * p - r_out))  # the foot, or the height where the rim cuts it
        kind.append(k)
        if k + 1 < len(s):  # the draft up to the next ring's top
            r.append(r_out)
            y.append(base + s[k + 1] * p)
            kind.append(-2 - k)
    return np.array(r), np.array(y), np.array(kind)


def ring_distance(lamp: dict):
    """Distance of points to the analytic ring face: to each facet's cone and each draft's cylinder,
    each only within its own extent (a point off both ends of a piece is not near it)."""
    plate, R = lamp["prism_plate"], lamp["lens"]["radius"]
    p = plate["pitch"]
    s = ring_slopes(R, p, plate["focal_length"], plate["ior"])
    base = lamp_geometry(lamp)["plate_base"]
    tol = 1e-6

    def distance(points: np.ndarray) -> np.ndarray:
        rho = np.hypot(points[:, 0], points[:, 2])
        y = points[:, 1]
        k0 = np.clip(np.floor(rho / p).astype(int), 0, len(s) - 1)
        best = np.full(len(rho), np.inf)
        for k in (k0 - 1, k0, k0 + 1):
            kk = np.clip(k, 0, len(s) - 1)
            sk = s[kk]
            # facet: the line y = base + s (r_foot - rho), within its radii
            d_facet = np.abs(y - base - sk * ((kk + 1) * p - rho)) / np.sqrt(1.0 + sk * sk)
            within = (rho >= kk * p - 0.1) & (rho <= np.minimum((kk + 1) * p, R) + 0.1)
            best = np.where(within & (k == kk) & (d_facet < best), d_facet, best)
            # draft at r = kk p, from the ring bottoms to ring kk's top
            d_draft = np.abs(rho - kk * p)
            within = (kk > 0) & (y >= base - tol) & (y <= base + sk * p + tol)
            best = np.where(within & (k == kk) & (d_draft < best), d_draft, best)
        return best

    return distance


def prism_plate_mesh(lamp: dict, segments: int) -> MeshData:
    """The plate: front face (normal -y) and the revolved ring face (normals out of the plate)."""
    g = lamp_geometry(lamp)
    R = lamp["lens"]["radius"]
    r, y, kind = ring_profile(lamp)
    mb = MeshBuilder()
    a = 2.0 * math.pi * np.arange(segments) / segments
    cos_a, sin_a = np.cos(a), np.sin(a)
    front = [mb.vertex(R * c, g["plate_front"], R * t) for c, t in zip(cos_a, sin_a, strict=True)]
    mb.face(front, FLAT)  # counter-clockwise seen from -y: faces the lens
    pole = mb.vertex(0.0, float(y[0]), 0.0)
    rows = [[mb.vertex(ri * c, float(yi), ri * t) for c, t in zip(cos_a, sin_a, strict=True)]
            for ri, yi in zip(r[1:], y[1:], strict=True)]
    for j in range(segments):
        j1 = (j + 1) % segments
        mb.face([pole, rows[0][j1], rows[0][j]], 0)  # the central cone, facing +y
        for i in range(len(rows) - 1):
            group = int(kind[i + 1]) if kind[i + 1] >= 0 else 100_000 - int(kind[i + 1])
            mb.face([rows[i][j], rows[i][j1], rows[i + 1][j1], rows[i + 1][j]], group)
    data = mb.result()
    rings = [f for f, grp in zip(data.faces, data.group, strict=True) if grp != FLAT]
    data.max_deviation = triangle_deviation(data.verts, fan_triangles(rings), ring_distance(lamp))
    return data


def housing_mesh(lamp: dict, segments: int) -> MeshData:
    """The housing: cylinder r = R from the plate's front face back, closed by the back disk."""
    g = lamp_geometry(lamp)
    R = lamp["lens"]["radius"]
    a = 2.0 * math.pi * np.arange(segments) / segments
    mb = MeshBuilder()
    front = [mb.vertex(R * math.cos(t), g["plate_front"], R * math.sin(t)) for t in a]
    back = [mb.vertex(R * math.cos(t), g["vertex"], R * math.sin(t)) for t in a]
    for k in range(segments):
        k1 = (k + 1) % segments
        mb.face([front[k], front[k1], back[k1], back[k]], 0)  # normals toward the axis
    mb.face(back, FLAT)  # faces -y, into the lamp
    data = mb.result()
    side = [f for f, grp in zip(data.faces, data.group, strict=True) if grp == 0]
    data.max_deviation = triangle_deviation(data.verts, fan_triangles(side),
                                            lambda q: np.abs(np.hypot(q[:, 0], q[:, 2]) - R))
    return data

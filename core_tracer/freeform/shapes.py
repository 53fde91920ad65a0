"""Simple meshes with outward faces, for tests, benchmarks and examples of free-form designs.

Model coordinates (docs/model.md §2): millimetres, x right, y into the lamp, z up. Every closed shape
is wound counter-clockwise seen from outside; the open reflector dish faces the lamp's opening
(-y) with its normals toward the inside of the bowl.
"""

from __future__ import annotations

import math

import numpy as np

from .meshes import MeshData


def box(name: str, lo: tuple[float, float, float], hi: tuple[float, float, float]) -> MeshData:
    """An axis-aligned box, flat-shaded, 12 triangles."""
    x0, y0, z0 = lo
    x1, y1, z1 = hi
    v = np.array([[x0, y0, z0], [x1, y0, z0], [x1, y1, z0], [x0, y1, z0],
                  [x0, y0, z1], [x1, y0, z1], [x1, y1, z1], [x0, y1, z1]], np.float64)
    quads = [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (2, 3, 7, 6), (1, 2, 6, 5), (3, 0, 4, 7)]
    t = np.array([tri for a, b, c, d in quads for tri in ((a, b, c), (a, c, d))], np.int32)
    return MeshData(name, v, t, None)


def _grid_triangles(rows: int, cols: int, wrap: bool) -> np.ndarray:
    """Triangles of a (rows+1) x cols vertex grid (columns wrapped around when ``wrap``)."""
    tris = []
    width = cols if wrap else cols + 1
    for i in range(rows):
        for j in range(cols):
            a = i * width + j
            b = i * width + (j + 1) % width if wrap else a + 1
            c, d = a + width, b + width
            tris += [(a, c, d), (a, d, b)]
    return np.array(tris, np.int32)


def uv_sphere(name: str, centre: tuple[float, float, float], radius: float, segments: int = 32,
              smooth: bool = True) -> MeshData:
    """A UV sphere with poles on z; smooth-shaded with the exact sphere normals."""
    rings = max(2, segments // 2)
    theta = np.linspace(0.0, math.pi, rings + 1)
    phi = np.linspace(0.0, 2 * math.pi, segments, endpoint=False)
    th, ph = np.meshgrid(theta, phi, indexing="ij")
    n = np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)], axis=-1).reshape(-1, 3)
    v = np.asarray(centre, np.float64) + radius * n
    t = _grid_triangles(rings, segments, wrap=True)
    p = v[t]
    area = np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    t = t[area > 1e-12 * radius * radius]  # the collapsed triangles at the poles
    corner = n[t] if smooth else None
    return MeshData(name, v, t, corner)


def paraboloid_dish(name: str, focal: float, rim_radius: float, vertex_y: float, rings: int = 64,
                    segments: int = 128, smooth: bool = True) -> MeshData:
    """The reflector y = vertex_y - r²/(4f) for r <= rim_radius, an open bowl opening toward -y,
    normals toward the focus side (the inside of the bowl)."""
    r = np.linspace(0.0, rim_radius, rings + 1)
    phi = np.linspace(0.0, 2 * math.pi, segments, endpoint=False)
    rr, pp = np.meshgrid(r, phi, indexing="ij")
    x, z = rr * np.cos(pp), rr * np.sin(pp)
    y = vertex_y - rr * rr / (4 * focal)
    v = np.stack([x, y, z], axis=-1).reshape(-1, 3)
    # Surface F = y - vertex_y + r²/(4f) = 0; the gradient (x/2f, 1, z/2f) points away from the
    # focus (into +y, behind the bowl): the inside normal is its opposite.
    g = np.stack([x / (2 * focal), np.ones_like(x), z / (2 * focal)], axis=-1).reshape(-1, 3)
    n = -g / np.linalg.norm(g, axis=1, keepdims=True)
    t = _grid_triangles(rings, segments, wrap=True)
    p = v[t]
    face = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    area = np.linalg.norm(face, axis=1)
    t = t[area > 1e-12]
    if (np.cross(v[t][:, 1] - v[t][:, 0], v[t][:, 2] - v[t][:, 0])[:, 1] > 0).mean() > 0.5:
        t = np.ascontiguousarray(t[:, ::-1])  # face the inside (-y side) of the bowl
    return MeshData(name, v, t, n[t] if smooth else None)


def cylinder(name: str, centre_xz: tuple[float, float], radius: float, y0: float, y1: float,
             segments: int = 64, smooth_side: bool = True) -> MeshData:
    """A closed cylinder along y from y0 to y1 (flat caps, smooth side)."""
    cx, cz = centre_xz
    phi = np.linspace(0.0, 2 * math.pi, segments, endpoint=False)
    ring = np.stack([cx + radius * np.cos(phi), np.zeros(segments), cz + radius * np.sin(phi)], axis=1)
    front, back = ring + [0, y0, 0], ring + [0, y1, 0]
    v = np.concatenate([front, back, [[cx, y0, cz], [cx, y1, cz]]])
    c0, c1 = 2 * segments, 2 * segments + 1
    tris, normals = [], []
    radial = np.stack([np.cos(phi), np.zeros(segments), np.sin(phi)], axis=1)
    for j in range(segments):
        k = (j + 1) % segments
        # Side, facing outward.
        for tri in ((j, segments + k, k), (j, segments + j, segments + k)):
            tris.append(tri)
            normals.append([radial[i % segments] for i in tri] if smooth_side else None)
        tris.append((c0, j, k))  # front cap, facing -y
        normals.append(None)
        tris.append((c1, segments + k, segments + j))  # back cap, facing +y
        normals.append(None)
    t = np.array(tris, np.int32)
    p = v[t]
    face = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    face /= np.linalg.norm(face, axis=1, keepdims=True)
    corner = np.array([np.asarray(nrm) if nrm is not None else np.repeat(f[None], 3, axis=0)
                       for nrm, f in zip(normals, face, strict=True)])
    return MeshData(name, v, t, corner)

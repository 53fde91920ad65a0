"""The meshes of a free-form design as one set of triangles with their roles, checked (the Embree
scene over them, built once per geometry change, is ``cache.GeometryCache``'s).

Each triangle knows its part, the surface it is in Table 1's terms and, for a lens, which lens
volume it bounds. Table 1's surfaces follow from the roles (docs/model.md, "Free-form"):

- lens triangles facing the viewer (outward normal with y < 0) are the outer face, every other
  lens triangle the inner (cut) face;
- reflector, bulb, socket and side wall are the paper's parts; body is the housing (eq. 1).
"""

from __future__ import annotations

import zlib
from dataclasses import dataclass

import numpy as np

from ..raytrace import paths as P
from ..scene.reading import SceneError
from ..scene.safe_text import printable
from .meshes import MAX_TRIANGLES, MeshData, area_normals, check_lens_volume, check_mesh, face_normals

# a surface beyond those of the parametric lamp (``paths.SURFACES``): the housing, shaded by eq. (1), ends the path
BODY = P.SURFACES
SURFACE_OF_ROLE = {"reflector": P.REFLECTOR, "bulb": P.BULB, "socket": P.SOCKET, "side_wall": P.WALL, "body": BODY}

# Rays leave a surface this far along its geometric normal (relative to the design's size, at
# least 0.1 µm), and a ray never takes its own triangle as its next hit: Embree intersects in
# single precision, so a ray starting exactly on a surface could find it again at t ≈ 0.
EPSILON_MIN = 1e-4  # mm
EPSILON_RELATIVE = 2e-6


@dataclass(frozen=True)
class Geometry:
    """All triangles of the design's parts, concatenated in the order of ``freeform.parts``."""

    vertices: np.ndarray  # (V, 3) float64 mm
    triangles: np.ndarray  # (T, 3) int64 into vertices
    normal: np.ndarray  # (T, 3) unit geometric normal (outward for a lens)
    corner_normals: np.ndarray  # (T, 3, 3) shading normals per corner (the face normal when flat),
    # as the mesh gives them: normalised where they are interpolated
    part: np.ndarray  # (T,) index into freeform.parts
    surface: np.ndarray  # (T,) int8 surface id (paths.OUTER, CUT, REFLECTOR … or BODY)
    epsilon: float  # mm, the offset of a ray's origin off its surface
    fingerprint: tuple

    def corners(self, which: np.ndarray) -> np.ndarray:
        """The vertex positions (N, 3, 3) of the triangles ``which`` (indices or a mask)."""
        return self.vertices[self.triangles[which]]


def part_meshes(scene: dict, meshes: dict[str, MeshData]) -> list[MeshData]:
    """The mesh of every part, in order; a part naming no mesh is the user's mistake."""
    section = scene.get("freeform")
    if not section:
        raise SceneError("freeform", "is missing; a free-form render needs the freeform section with its parts")
    out = []
    for i, part in enumerate(section["parts"]):
        mesh = meshes.get(part["object"])
        if mesh is None:
            names = ", ".join(f'"{printable(n, 30)}"' for n in list(meshes)[:8]) or "none"
            raise SceneError(f"freeform.parts[{i}].object", f'"{printable(part["object"], 40)}" is not a mesh of '
                                                            f"{section['mesh_file'] or 'the mesh file'}; allowed one "
                                                            f"of {names}{' …' if len(meshes) > 8 else ''}")
        out.append(mesh)
    return out


def fingerprint(scene: dict, mesh_list: list[MeshData]) -> tuple:
    """What the acceleration structure depends on: the parts' roles and the meshes' contents (a
    checksum, so that arrays edited in place count as a change)."""
    roles = tuple(part["role"] for part in scene["freeform"]["parts"])
    sums = tuple((m.name, m.vertices.shape, m.triangles.shape, zlib.crc32(np.ascontiguousarray(m.vertices)),
                  zlib.crc32(np.ascontiguousarray(m.triangles)),
                  None if m.corner_normals is None else zlib.crc32(np.ascontiguousarray(m.corner_normals)))
                 for m in mesh_list)
    return roles, sums


def build_geometry(scene: dict, meshes: dict[str, MeshData], key: tuple | None = None) -> Geometry:
    """Check every part's mesh and concatenate them; raises ``SceneError`` naming the object.
    ``key`` is the meshes' ``fingerprint`` when the caller has it already."""
    mesh_list = part_meshes(scene, meshes)
    total = sum(len(m.triangles) for m in mesh_list if m.triangles.ndim == 2)
    if total > MAX_TRIANGLES:
        raise SceneError("freeform.parts", f"the meshes have {total} triangles together; allowed at most "
                                           f"{MAX_TRIANGLES} (decimate the largest)")
    parts = scene["freeform"]["parts"]
    verts, tris, cn, normals, part_of, surf = [], [], [], [], [], []
    base = 0
    for i, (part, mesh) in enumerate(zip(parts, mesh_list, strict=True)):
        check_mesh(mesh)
        area = area_normals(mesh)
        if part["role"] == "lens":
            check_lens_volume(mesh, area)
        n = face_normals(mesh, area)
        v = np.asarray(mesh.vertices, np.float64)
        t = np.asarray(mesh.triangles, np.int64)
        verts.append(v)
        tris.append(t + base)
        normals.append(n)
        base += len(v)
        if mesh.corner_normals is None:
            cn.append(np.broadcast_to(n[:, None, :], (len(n), 3, 3)))
        else:
            cn.append(np.asarray(mesh.corner_normals, np.float64))
        part_of.append(np.full(len(t), i, np.int32))
        if part["role"] == "lens":
            surf.append(np.where(n[:, 1] < 0.0, P.OUTER, P.CUT).astype(np.int8))
        else:
            surf.append(np.full(len(t), SURFACE_OF_ROLE[part["role"]], np.int8))
    vertices, triangles = _joined(verts), _joined(tris)
    extent = float(np.ptp(vertices, axis=0).max())
    geometry = Geometry(vertices, triangles, _joined(normals), _joined(cn), _joined(part_of), _joined(surf),
                        max(EPSILON_MIN, EPSILON_RELATIVE * extent),
                        key if key is not None else fingerprint(scene, mesh_list))
    return geometry


def _joined(arrays: list[np.ndarray]) -> np.ndarray:
    """The arrays one after another (one part's own array, not a copy: a large lens is not copied)."""
    return np.asarray(arrays[0]) if len(arrays) == 1 else np.concatenate(arrays)

"""Triangle meshes of free-form parts, in model space, and the checks a lens mesh must pass.

Model space is the design root's frame in millimetres: x right, y into the lamp, z up; the lamp
faces -y (MODEL.md §2). A lens must be a closed, consistently outward-oriented surface: the
tracer tells inside from outside by the side a ray meets a face from, and measures the path
length inside for absorption (eq. 2), which only means something for a closed volume.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..scene.reading import SceneError
from ..scene.safe_text import printable

# A 1-million-triangle lens is the largest the benchmark builds in about a second; a design of
# several such parts still fits in memory (about 100 bytes a triangle with normals).
MAX_TRIANGLES_PER_MESH = 2_000_000
MAX_TRIANGLES = 4_000_000


@dataclass(frozen=True)
class MeshData:
    """One mesh: ``vertices`` (V, 3) float64 mm in model space, ``triangles`` (T, 3) int32 vertex
    indices, counter-clockwise seen from outside; ``corner_normals`` (T, 3, 3) float64 unit
    normals per triangle corner (smooth shading), or None for flat shading."""

    name: str
    vertices: np.ndarray
    triangles: np.ndarray
    corner_normals: np.ndarray | None = None

    @property
    def triangle_count(self) -> int:
        return len(self.triangles)


def mesh_error(name: str, message: str) -> SceneError:
    """The one-line error about mesh ``name``."""
    return SceneError(f'mesh "{printable(name, 40)}"', message)


def check_mesh(mesh: MeshData) -> None:
    """Shapes, index range, finite numbers and the size limit; raises a ``SceneError`` naming the mesh."""
    v, t = mesh.vertices, mesh.triangles
    if v.ndim != 2 or v.shape[1] != 3 or t.ndim != 2 or t.shape[1] != 3:
        raise mesh_error(mesh.name, "is not a triangle mesh; allowed (V, 3) vertices and (T, 3) triangles")
    if len(t) == 0:
        raise mesh_error(mesh.name, "has no triangles; allowed a mesh of 1 to "
                                    f"{MAX_TRIANGLES_PER_MESH} triangles")
    if len(t) > MAX_TRIANGLES_PER_MESH:
        raise mesh_error(mesh.name, f"has {len(t)} triangles; allowed at most {MAX_TRIANGLES_PER_MESH} "
                                    "(decimate it, or apply fewer subdivision levels)")
    if not np.isfinite(v).all():
        raise mesh_error(mesh.name, "has vertices that are not finite numbers; allowed finite coordinates")
    if t.min() < 0 or t.max() >= len(v):
        raise mesh_error(mesh.name, f"has triangle indices outside 0..{len(v) - 1}; allowed indices of its vertices")
    n = mesh.corner_normals
    if n is not None and (n.shape != (len(t), 3, 3) or not np.isfinite(n).all()):
        raise mesh_error(mesh.name, "has corner normals of the wrong shape or not finite; allowed (T, 3, 3)")


def signed_volume(mesh: MeshData) -> float:
    """The enclosed volume in mm³ (divergence theorem): positive when the faces point outward."""
    p = mesh.vertices[mesh.triangles]
    centre = mesh.vertices.mean(axis=0)  # about the centre: fewer digits lost far from the origin
    a, b, c = p[:, 0] - centre, p[:, 1] - centre, p[:, 2] - centre
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def open_edges(mesh: MeshData) -> int:
    """The number of edges not shared by exactly two triangles in opposite directions (0 for a
    closed, consistently oriented surface). Vertices at the same position count as one: glTF
    splits vertices along creases and seams of the normals."""
    _, weld = np.unique(np.round(mesh.vertices, 9), axis=0, return_inverse=True)
    tri = weld.reshape(-1)[mesh.triangles]
    a = tri.reshape(-1)
    b = tri[:, [1, 2, 0]].reshape(-1)
    keep = a != b  # degenerate edges of collapsed triangles say nothing about closure
    a, b = a[keep].astype(np.int64), b[keep].astype(np.int64)
    n = int(tri.max()) + 1
    forward = np.unique(a * n + b, return_counts=True)
    backward = np.unique(b * n + a, return_counts=True)
    f_keys, f_counts = forward
    b_keys, b_counts = backward
    # Each directed edge must appear once, and its reverse once.
    if (f_counts > 1).any():
        return int((f_counts > 1).sum()) + int(np.setxor1d(f_keys, b_keys).size)
    return int(np.setxor1d(f_keys, b_keys).size)


def check_lens_volume(mesh: MeshData) -> float:
    """A lens must be closed and oriented outward with a volume; returns the volume (mm³)."""
    edges = open_edges(mesh)
    if edges:
        raise mesh_error(mesh.name, f"is not closed ({edges} open or non-manifold edges); a lens must be a "
                                    "closed surface: fill the holes (Blender: Select > All by Trait > Non "
                                    "Manifold, then F)")
    volume = signed_volume(mesh)
    extent = np.ptp(mesh.vertices, axis=0)
    tiny = 1e-9 * float(np.prod(np.maximum(extent, 1e-9)))
    if abs(volume) <= max(tiny, 1e-12):
        raise mesh_error(mesh.name, "encloses no volume; a lens must be a solid with thickness "
                                    "(Blender: Solidify modifier, applied)")
    if volume < 0:
        raise mesh_error(mesh.name, f"has its normals pointing inward (volume {volume:.4g} mm³); allowed "
                                    "outward normals (Blender: Mesh > Normals > Recalculate Outside)")
    return volume


def face_normals(mesh: MeshData) -> np.ndarray:
    """Unit geometric normals (T, 3) by the triangles' winding (zero for degenerate triangles)."""
    p = mesh.vertices[mesh.triangles]
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    length = np.linalg.norm(n, axis=1)
    return n / np.where(length > 0, length, 1.0)[:, None]

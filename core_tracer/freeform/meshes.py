"""Triangle meshes of free-form parts, in model space, and the checks a lens mesh must pass.

Model space is the design root's frame in millimetres: x right, y into the lamp, z up; the lamp
faces -y (docs/model.md §2). A lens must be a closed, consistently outward-oriented surface: the
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
# A lamp is at most a few metres across; 10 km from the origin is absurd, and keeps the volume
# check's cubes (about 1e21 mm³) far inside the float range.
MAX_COORDINATE_MM = 1e7


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
    if len(v) and np.abs(v).max() > MAX_COORDINATE_MM:
        raise mesh_error(mesh.name, f"has vertices {np.abs(v).max():.4g} mm from the origin; allowed within "
                                    f"±{MAX_COORDINATE_MM:g} mm (a lamp's size: check the units and scales)")
    if t.min() < 0 or t.max() >= len(v):
        raise mesh_error(mesh.name, f"has triangle indices outside 0..{len(v) - 1}; allowed indices of its vertices")
    n = mesh.corner_normals
    if n is not None and (n.shape != (len(t), 3, 3) or not np.isfinite(n).all()):
        raise mesh_error(mesh.name, "has corner normals of the wrong shape or not finite; allowed (T, 3, 3)")


def area_normals(mesh: MeshData) -> np.ndarray:
    """(p1 - p0) × (p2 - p0) of every triangle (T, 3): twice its area along its outward normal."""
    v, t = mesh.vertices, mesh.triangles
    p0, p1, p2 = v[t[:, 0]], v[t[:, 1]], v[t[:, 2]]
    a, b = p1 - p0, p2 - p0
    return np.stack([a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1], a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2],
                     a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]], axis=1)


def signed_volume(mesh: MeshData, normals: np.ndarray | None = None) -> float:
    """The enclosed volume in mm³ (divergence theorem, Σ p0 · N / 6): positive when the faces point
    outward. Measured about the vertices' mean: fewer digits lost far from the origin."""
    n = area_normals(mesh) if normals is None else normals
    centre = mesh.vertices.mean(axis=0)
    p0 = mesh.vertices[mesh.triangles[:, 0]] - centre
    return float(np.einsum("ij,ij->", p0, n) / 6.0)


def _welded(mesh: MeshData) -> np.ndarray:
    """Every vertex index replaced by the first of the vertices at its position (to about 1e-6 of
    the mesh's size): glTF splits vertices along seams and creases of the normals."""
    v = mesh.vertices
    lo = v.min(axis=0)
    quantum = max(float(np.ptp(v, axis=0).max()), 1e-300) / (2**20 - 2)
    q = np.rint((v - lo) / quantum).astype(np.int64)
    key = (q[:, 0] << 42) | (q[:, 1] << 21) | q[:, 2]
    _, first, inverse = np.unique(key, return_index=True, return_inverse=True)
    return first[inverse]


def open_edges(mesh: MeshData) -> int:
    """The number of edges not used by exactly two triangles in opposite directions (0 for a
    closed, consistently oriented, manifold surface); vertices at the same position count as one."""
    weld = _welded(mesh)
    tri = weld[mesh.triangles]
    a = tri.reshape(-1)
    b = tri[:, [1, 2, 0]].reshape(-1)
    keep = a != b  # the edges of collapsed triangles say nothing about closure
    a, b = a[keep].astype(np.int64), b[keep].astype(np.int64)
    n = len(mesh.vertices)
    # Closed and oriented: every undirected edge is used exactly twice, once in each direction.
    # Sorted by the undirected edge, the two uses lie side by side.
    # One sort of the undirected edge with the direction in its lowest bit.
    both = np.sort((np.minimum(a, b) * n + np.maximum(a, b)) * 2 + (a < b))
    key, forward = both >> 1, (both & 1).astype(bool)
    if len(key) == 0:
        return 0
    start = np.flatnonzero(np.concatenate([[True], key[1:] != key[:-1]]))
    uses = np.diff(np.append(start, len(key)))
    twice = uses == 2
    opposite = forward[start[twice]] != forward[start[twice] + 1]
    # The undirected edges used other than once in each direction.
    return int(np.count_nonzero(~twice) + np.count_nonzero(~opposite))


def check_lens_volume(mesh: MeshData, normals: np.ndarray | None = None) -> float:
    """A lens must enclose a volume, be closed and face outward; returns the volume (mm³). The
    volume is checked first: a plane given the lens role needs thickness more than closing."""
    volume = signed_volume(mesh, normals)
    extent = np.ptp(mesh.vertices, axis=0)
    if abs(volume) <= 1e-9 * float(extent.max()) ** 3:
        raise mesh_error(mesh.name, "encloses no volume; a lens must be a solid with thickness "
                                    "(Blender: Solidify modifier, applied)")
    edges = open_edges(mesh)
    if edges:
        raise mesh_error(mesh.name, f"is not closed ({edges} open or non-manifold edges); a lens must be a "
                                    "closed surface: fill the holes (Blender: Select > All by Trait > Non "
                                    "Manifold, then F)")
    if volume < 0:
        raise mesh_error(mesh.name, f"has its normals pointing inward (volume {volume:.4g} mm³); allowed "
                                    "outward normals (Blender: Mesh > Normals > Recalculate Outside)")
    return volume


def face_normals(mesh: MeshData, normals: np.ndarray | None = None) -> np.ndarray:
    """Unit geometric normals (T, 3) by the triangles' winding (zero for degenerate triangles)."""
    n = area_normals(mesh) if normals is None else normals
    length = np.sqrt(np.einsum("ij,ij->i", n, n))
    return n / np.where(length > 0, length, 1.0)[:, None]

"""The built parts' meshes made into the solids and walls the free-form tracer needs (Convert to
Free-form): a lens's closed glass and its side wall, the prism plate closed at its rim.

The side wall and the prism-plate housing are moved ``INSET_MM`` toward the lamp axis, so that a ray
travelling in the glass meets the opaque wall, not the glass's own rim face, as in the parametric
model where such a ray ends at the side wall (Table 1 ⑦) or at the housing (⑲); the inset is well
below the meshes' chord tolerance.
"""

from __future__ import annotations

import bmesh
import bpy
import numpy as np

from ..convert import units
from ..convert.meshes import builder as mesh_builder

INSET_MM = 0.005


def keep_faces(mesh: bpy.types.Mesh, keep: np.ndarray) -> None:
    """Delete the faces of ``mesh`` where ``keep`` is False (and the vertices left without a face)."""
    bm = bmesh.new()
    bm.from_mesh(mesh)
    bm.faces.ensure_lookup_table()
    doomed = [f for f, k in zip(bm.faces, keep, strict=False) if not k]
    bmesh.ops.delete(bm, geom=doomed, context="FACES")
    bm.to_mesh(mesh)
    bm.free()


def _face_vertices(mesh: bpy.types.Mesh) -> tuple[np.ndarray, np.ndarray]:
    """Every face corner's vertex, and the index of each face's first corner."""
    starts = np.empty(len(mesh.polygons), np.int32)
    mesh.polygons.foreach_get("loop_start", starts)
    corner_vertex = np.empty(len(mesh.loops), np.int32)
    mesh.loops.foreach_get("vertex_index", corner_vertex)
    return corner_vertex, starts


def split_lens(mesh: bpy.types.Mesh) -> tuple[bpy.types.Mesh, bpy.types.Mesh]:
    """The lens mesh (axis frame, BU) as the closed glass and the side wall pushed inward.

    The glass is the faces of material ``LENS_GLASS`` (cut surface, outer face) and the side wall's
    rim band between them; the collar above the cut surface stands open (up to the apex plane, or to
    the reflector's edge for a rectangular lens), so it stays with the wall only. The band is told
    from the collar by its corners: every corner of a band face lies on a glass face (the outer
    face's rim, the cut surface's rim), while a collar face reaches up to corners no glass face has.
    This holds for every outer face: flat, or the cylinder of a wrap-around lens."""
    keep, walls = glass_faces(mesh)
    glass = mesh.copy()
    keep_faces(glass, keep)
    wall = mesh.copy()
    keep_faces(wall, walls)
    inset(wall)
    return glass, wall


def glass_faces(mesh: bpy.types.Mesh) -> tuple[np.ndarray, np.ndarray]:
    """Per face of the lens mesh: whether it belongs to the closed glass, and to the side wall
    (``split_lens``)."""
    material = np.empty(len(mesh.polygons), np.int32)
    mesh.polygons.foreach_get("material_index", material)
    corner_vertex, starts = _face_vertices(mesh)
    corner_face = np.repeat(np.arange(len(starts)), np.diff(np.append(starts, len(corner_vertex))))
    on_glass = np.zeros(len(mesh.vertices), bool)
    on_glass[corner_vertex[material[corner_face] == mesh_builder.LENS_GLASS]] = True
    band = (material == mesh_builder.LENS_SIDE_WALL) & np.logical_and.reduceat(on_glass[corner_vertex], starts)
    return (material == mesh_builder.LENS_GLASS) | band, material == mesh_builder.LENS_SIDE_WALL


def inset(mesh: bpy.types.Mesh) -> None:
    """Move every vertex of ``mesh`` (axis frame, BU) ``INSET_MM`` toward the lamp axis (y)."""
    co = np.empty(len(mesh.vertices) * 3, np.float32)
    mesh.vertices.foreach_get("co", co)
    co = co.reshape(-1, 3).astype(np.float64)
    radius = np.hypot(co[:, 0], co[:, 2])
    scale = np.where(radius > 0, 1.0 - INSET_MM * units.BU_PER_MM / np.maximum(radius, 1e-12), 1.0)
    co[:, 0] *= scale
    co[:, 2] *= scale
    mesh.vertices.foreach_set("co", co.astype(np.float32).ravel())
    mesh.update()


def close_plate(mesh: bpy.types.Mesh) -> None:
    """Close the prism plate at its rim: the builder's plate has no rim face (the housing's cylinder
    r = R closes it, as in the tracer), but a free-form lens must be a closed solid. The band bridges
    the front face's rim to the ring face's outer edge, both at r = R; it lies just outside the
    inset housing, so a ray in the plate still ends on the housing (⑲)."""
    bm = bmesh.new()
    bm.from_mesh(mesh)
    rim = [e for e in bm.edges if e.is_boundary]
    try:
        bmesh.ops.bridge_loops(bm, edges=rim)
    except RuntimeError:
        # A plate reshaped by the designer's modifiers into other than two rims stays as it is: the
        # free-form checks then name it as an open lens, with how to close it.
        bm.free()
        return
    bm.to_mesh(mesh)
    bm.free()
    mesh.update()

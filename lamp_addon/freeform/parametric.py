"""The built parametric lamps of a design with free-form parts, as meshes with their implicit roles.

When a design mixes the designer's own parts with parametric lamps still in use, the free-form
tracer traces both: each built part (``design.root.PART_KEY``) that a Convert did not hide is read
as the viewport shows it and split into the roles Convert to Free-form gives it
(``freeform.conversion.roles_of``: the lens's closed glass and side wall, a prism plate closed at its
rim, its housing, the reflector, bulb, socket and body). Unlike Convert, nothing is made or changed
in Blender: the evaluated object's own temporary mesh is read (safe in a render thread) and split
here with numpy, in the design root's frame (mm), the numbers ``freeform.meshes`` gives a part.

The glass is the faces Convert keeps (``freeform.solids.glass_faces``) with the corner normals
Blender computed on the whole lens; the walls are moved ``freeform.solids.INSET_MM`` toward the lamp
axis as Convert moves them. A lamp that is not built at its current design is left out (the panel
says so): its meshes would not be the design the values come from. A preview build is traced: it is
the current design, with a coarser lens.
"""

from __future__ import annotations

import json
from dataclasses import dataclass

import bmesh
import bpy
import numpy as np

from ...core_tracer.freeform.meshes import MeshData
from ..convert import units
from ..design import builder as design_builder
from ..design import root as design_root
from . import conversion, meshes, solids

SUFFIX = " (Parametric)"


def built_parts(bl_scene: bpy.types.Scene, depsgraph: bpy.types.Depsgraph | None) -> list[bpy.types.Object]:
    """The built lamp parts the design still uses: not hidden from renders (Convert hides the parts it
    copied) and shown by ``depsgraph`` (any, when None), by part key. Empty when the lamp is not built
    at its current design (a preview build, Auto Build's lighter lens while a value is dragged, is)."""
    if design_builder.build_status(bl_scene) not in (design_builder.UP_TO_DATE, design_builder.PREVIEW):
        return []
    return used_parts(bl_scene, depsgraph)


def used_parts(bl_scene: bpy.types.Scene, depsgraph: bpy.types.Depsgraph | None) -> list[bpy.types.Object]:
    """``built_parts`` whether or not the lamp is up to date."""
    shown = None if depsgraph is None else {obj.original.name for obj in depsgraph.objects if obj.type == "MESH"}
    parts = [obj for obj in bl_scene.objects
             if obj.type == "MESH" and (shown is None or obj.name in shown) and not obj.hide_render
             and conversion.is_convertible(obj.get(design_root.PART_KEY, ""))]
    return sorted(parts, key=lambda obj: obj[design_root.PART_KEY])


def part_names(obj: bpy.types.Object) -> list[str]:
    """The names of the meshes one built part gives: two for a lens (glass, side wall)."""
    if obj[design_root.PART_KEY].endswith(".lens"):
        return [obj.name + SUFFIX, obj.name.replace(" Lens", " Side Wall") + SUFFIX]
    return [obj.name + SUFFIX]


@dataclass(frozen=True)
class _Piece:
    """One mesh as Blender gives it, in the design's frame: 32-bit positions (BU), triangles, and
    32-bit corner normals (T, 3, 3) as the glTF exporter would read them from a Blender mesh."""

    name: str
    vertices: np.ndarray
    triangles: np.ndarray
    normals: np.ndarray

    def mesh_data(self) -> MeshData:
        """As ``freeform.meshes.mesh_data`` makes it (and the ``.glb`` reader reads it)."""
        normals = meshes.exported_normals(self.normals.reshape(-1, 3)).reshape(-1, 3, 3)
        return MeshData(self.name, self.vertices.astype(np.float64) * units.MM_PER_BU, self.triangles, normals)

    def blender_mesh(self) -> bpy.types.Mesh:
        """A new Blender mesh of these very numbers (the normals kept exactly, as a free
        ``custom_normal`` attribute), for the exporter; the caller removes it."""
        mesh = bpy.data.meshes.new(self.name)
        mesh.vertices.add(len(self.vertices))
        mesh.vertices.foreach_set("co", self.vertices.ravel())
        mesh.loops.add(3 * len(self.triangles))
        mesh.loops.foreach_set("vertex_index", self.triangles.ravel())
        mesh.polygons.add(len(self.triangles))
        mesh.polygons.foreach_set("loop_start", np.arange(0, 3 * len(self.triangles), 3, dtype=np.int32))
        mesh.update(calc_edges=True)
        normals = mesh.attributes.new("custom_normal", "FLOAT_VECTOR", "CORNER")
        normals.data.foreach_set("vector", self.normals.astype(np.float32).ravel())
        mesh.update()
        return mesh


def _subset(piece: _Piece, keep: np.ndarray, name: str) -> _Piece:
    """The triangles of ``piece`` where ``keep``, with only the vertices they use."""
    tri = piece.triangles[keep]
    used, remap = np.unique(tri, return_inverse=True)
    return _Piece(name, piece.vertices[used], remap.reshape(-1, 3).astype(np.int32), piece.normals[keep])


def _inset(piece: _Piece, axis_from_design: np.ndarray) -> _Piece:
    """``piece`` with its vertices moved ``INSET_MM`` toward the lamp's axis (y of the part's own
    frame, where Convert moves them), rounded to 32 bits again."""
    local = np.c_[piece.vertices.astype(np.float64), np.ones(len(piece.vertices))] @ axis_from_design.T
    radius = np.hypot(local[:, 0], local[:, 2])
    scale = np.where(radius > 0, 1.0 - solids.INSET_MM * units.BU_PER_MM / np.maximum(radius, 1e-12), 1.0)
    local[:, 0] *= scale
    local[:, 2] *= scale
    back = (local @ np.linalg.inv(axis_from_design).T)[:, :3]
    return _Piece(piece.name, back.astype(np.float32), piece.triangles, piece.normals)


def _closed_plate(mesh: bpy.types.Mesh, piece: _Piece) -> _Piece:
    """``piece`` (the plate, read from ``mesh``) with the band that closes its rim as
    ``freeform.solids.close_plate`` makes it, flat-shaded; as it was when its rim is not two loops
    (the checks then name it as an open lens)."""
    tris, normals = [], []
    bm = bmesh.new()
    try:
        bm.from_mesh(mesh)
        rim = [e for e in bm.edges if e.is_boundary]
        try:
            faces = bmesh.ops.bridge_loops(bm, edges=rim)["faces"]
        except RuntimeError:
            faces = []
        for face in faces:  # bridging adds faces, no vertices: the indices are the mesh's
            ids = [v.index for v in face.verts]
            face.normal_update()
            for i in range(1, len(ids) - 1):
                tris.append((ids[0], ids[i], ids[i + 1]))
                normals.append([tuple(face.normal)] * 3)
    finally:
        bm.free()
    if not tris:
        return piece
    return _Piece(piece.name, piece.vertices, np.vstack([piece.triangles, np.array(tris, np.int32)]),
                  np.concatenate([piece.normals, np.array(normals, np.float32)]))


def _read(mesh: bpy.types.Mesh, name: str) -> tuple[_Piece, np.ndarray]:
    """The piece of a mesh already in the design's frame, and each triangle's face index."""
    mesh.calc_loop_triangles()
    n_tri = len(mesh.loop_triangles)
    co = np.empty(len(mesh.vertices) * 3, np.float32)
    mesh.vertices.foreach_get("co", co)
    tris = np.empty(n_tri * 3, np.int32)
    mesh.loop_triangles.foreach_get("vertices", tris)
    loops = np.empty(n_tri * 3, np.int32)
    mesh.loop_triangles.foreach_get("loops", loops)
    corner = np.empty(len(mesh.corner_normals) * 3, np.float32)
    mesh.corner_normals.foreach_get("vector", corner)
    polygon = np.empty(n_tri, np.int32)
    mesh.loop_triangles.foreach_get("polygon_index", polygon)
    piece = _Piece(name, co.reshape(-1, 3), tris.reshape(-1, 3), corner.reshape(-1, 3)[loops].reshape(-1, 3, 3))
    return piece, polygon


def _pieces(obj: bpy.types.Object, depsgraph: bpy.types.Depsgraph, to_design) -> list[_Piece]:
    """The meshes one built part gives, as Convert would make them from it."""
    kind = obj[design_root.PART_KEY].rsplit(".", 1)[-1]
    names = part_names(obj)
    obj_eval = obj.evaluated_get(depsgraph)
    mesh = obj_eval.to_mesh()  # the evaluated object's own temporary mesh: no data-block is made
    try:
        matrix = to_design @ obj_eval.matrix_world
        faces = solids.glass_faces(mesh) if kind == "lens" else None
        meshes.to_frame(mesh, matrix)
        piece, polygon = _read(mesh, names[0])
        if kind == "prism_plate":
            return [_closed_plate(mesh, piece)]
    finally:
        obj_eval.to_mesh_clear()
    axis_from_design = np.array(matrix.inverted_safe())
    if kind == "lens":
        glass, wall = faces
        return [_subset(piece, glass[polygon], names[0]),
                _inset(_subset(piece, wall[polygon], names[1]), axis_from_design)]
    if kind == "housing":
        return [_inset(piece, axis_from_design)]
    return [piece]


def part_documents(objects, scene: dict) -> list[dict]:
    """The ``freeform.parts`` entries of the built parts ``objects`` of ``scene``'s design, with the
    roles and values Convert would give their copies."""
    docs = []
    for obj in objects:
        roles = conversion.roles_of(obj[design_root.PART_KEY], scene)
        for name, (role, values) in zip(part_names(obj), roles, strict=True):
            # as the JSON document holds them (lists, not tuples), and not shared with the design
            docs.append({"object": name, "role": role, role: json.loads(json.dumps(values))})
    return docs


def part_meshes(bl_scene: bpy.types.Scene, depsgraph: bpy.types.Depsgraph, objects) -> dict[str, MeshData]:
    """The meshes of the built parts ``objects`` in the design's frame (mm), by part name."""
    to_design = meshes.design_from_world(bl_scene)
    return {p.name: p.mesh_data() for obj in objects for p in _pieces(obj, depsgraph, to_design)}


def blender_meshes(bl_scene: bpy.types.Scene, depsgraph: bpy.types.Depsgraph, objects) -> dict[str, bpy.types.Mesh]:
    """New Blender meshes (in ``bpy.data``, for the glTF exporter) holding exactly the numbers
    ``part_meshes`` traces, by part name; the caller removes them."""
    to_design = meshes.design_from_world(bl_scene)
    return {p.name: p.blender_mesh() for obj in objects for p in _pieces(obj, depsgraph, to_design)}

"""The free-form parts of a scene as meshes in the design's frame: for the tracer (``MeshData``, mm)
and for the glTF exporter (Blender meshes, metres), the same numbers for both.

A part's geometry is what the viewport shows: the evaluated object (modifiers applied), taken to the
design root's local space (``design.root.world_from_design``; the world before the first build) by
Blender itself (``Mesh.transform``, which turns the normals, custom ones included, with the inverse
transpose). That mesh is what the exporter writes, with no transform of its own, so the ``.glb`` holds
exactly its 32-bit positions and normals; the tracer inside Blender reads the very same numbers
(``mesh_data``), which is why a render of the exported pair outside Blender matches the one inside.

Corner normals are Blender's (``Mesh.corner_normals``: auto smooth, sharp edges and custom normals
included), for flat faces too (their face normal), taken as the exporter writes them and the glb reader
reads them (``exported_normals``): so the tracer shades the very same normals inside Blender and from
the file, and the two renders agree pixel for pixel.
A mirroring transform (negative determinant) would turn the faces inside out, so their winding is
flipped back (``Mesh.flip_normals``) and the triangles stay counter-clockwise seen from outside.
"""

from __future__ import annotations

import bpy
import numpy as np
from mathutils import Matrix

from ...core_tracer.freeform.meshes import MeshData
from ..convert import units
from ..design import root as design_root


def design_from_world(bl_scene: bpy.types.Scene) -> Matrix:
    """The matrix from world space to the design's model space (both in Blender units)."""
    return design_root.world_from_design(bl_scene).inverted_safe()


def to_frame(mesh: bpy.types.Mesh, matrix: Matrix) -> None:
    mesh.transform(matrix)
    if matrix.to_3x3().determinant() < 0:
        mesh.flip_normals()
    mesh.update()


def frame_mesh(obj: bpy.types.Object, depsgraph: bpy.types.Depsgraph, to_design: Matrix) -> bpy.types.Mesh:
    """A new Blender mesh (in ``bpy.data``, for the exporter): ``obj`` evaluated in ``depsgraph``, in the
    design's frame (BU). The caller removes it (``bpy.data.meshes.remove``)."""
    obj_eval = obj.evaluated_get(depsgraph)
    mesh = bpy.data.meshes.new_from_object(obj_eval, preserve_all_data_layers=False, depsgraph=depsgraph)
    to_frame(mesh, to_design @ obj_eval.matrix_world)
    return mesh


def mesh_data(mesh: bpy.types.Mesh, name: str) -> MeshData:
    """``MeshData`` (mm) of a mesh already in the design's frame (``frame_mesh``)."""
    mesh.calc_loop_triangles()
    n_tri = len(mesh.loop_triangles)
    co = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", co)
    vertices = co.reshape(-1, 3).astype(np.float64) * units.MM_PER_BU
    triangles = np.empty(n_tri * 3, dtype=np.int32)
    mesh.loop_triangles.foreach_get("vertices", triangles)
    normals = None
    if n_tri:
        loops = np.empty(n_tri * 3, dtype=np.int32)
        mesh.loop_triangles.foreach_get("loops", loops)
        corner = np.empty(len(mesh.corner_normals) * 3, dtype=np.float32)
        mesh.corner_normals.foreach_get("vector", corner)
        normals = exported_normals(corner.reshape(-1, 3))[loops].reshape(-1, 3, 3)
    return MeshData(name, vertices, triangles.reshape(-1, 3), normals)


def _rounding_digit() -> int:
    try:
        from io_scene_gltf2.io.com.constants import ROUNDING_DIGIT
    except ImportError:  # pragma: no cover - the glTF add-on ships with Blender
        ROUNDING_DIGIT = 4
    return ROUNDING_DIGIT


def exported_normals(corner: np.ndarray) -> np.ndarray:
    """Blender's corner normals (float32, (N, 3)) as the ``.glb`` gives them to the tracer: Blender's
    glTF exporter rounds them to ``ROUNDING_DIGIT`` (4) decimals, normalises them in 32 bits and
    writes a zero normal (a degenerate triangle's) as up, (0, 0, 1) (``primitive_extract
    .__get_normals``); ``core_tracer.freeform.gltf`` scales them to millimetres with the axes (a
    rotation times 1000) and normalises them in 64 bits. The same operations here give the same
    bits. (Rounding to 1e-4 turns a normal by at most about 1e-4 rad.)"""
    n = np.round(np.asarray(corner, np.float32), _rounding_digit())
    norms = np.linalg.norm(n, axis=1, keepdims=True)
    np.divide(n, norms, out=n, where=norms != 0)
    n[~n.any(axis=1), 2] = 1.0
    n = n.astype(np.float64) * units.MM_PER_BU
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    return n


# The steps (in units of the exporter's last decimal) tried around a file normal's rounded
# components, nearest first: the 4-decimal vector the exporter normalised lies within one step.
_STEPS = sorted(np.ndindex(3, 3, 3), key=lambda k: (sum(abs(i - 1) for i in k), k))
_STEPS = np.array(_STEPS, np.float64) - 1.0


def normals_exporting_as(target: np.ndarray) -> np.ndarray:
    """Corner normals for a Blender mesh (float32, (N, 3)) that ``exported_normals`` turns into
    ``target`` (unit float64 normals, (N, 3), as ``core_tracer.freeform.gltf`` read them from a .glb)
    bit for bit: so parts made from a .glb are traced inside Blender, and exported again, with the
    file's very normals. A normal Blender's exporter wrote is a 4-decimal vector normalised in 32
    bits; that vector is found among the 27 within one last decimal of the normal's rounded
    components (the rounded components themselves for about 98 % of them). A normal no 4-decimal
    vector gives (a file from another exporter) is kept in 32 bits: exported, it moves by the
    exporter's rounding (under about 1e-4). When the rounded components give fewer than half of the
    normals, the file is not Blender's and the other 26 are not searched (a second a million)."""
    target = np.asarray(target, np.float64).reshape(-1, 3)
    scale = 10.0 ** _rounding_digit()
    base = np.rint(target * scale)
    out = target.astype(np.float32)
    todo = np.arange(len(target))
    for step in _STEPS:
        if not len(todo):
            break
        candidate = np.round(((base[todo] + step) / scale).astype(np.float32), _rounding_digit())
        hit = (exported_normals(candidate) == target[todo]).all(axis=1)
        out[todo[hit]] = candidate[hit]
        if len(todo) == len(target) and hit.sum() < len(target) / 2:
            break
        todo = todo[~hit]
    return out


def scene_meshes(bl_scene: bpy.types.Scene, depsgraph: bpy.types.Depsgraph, objects) -> dict[str, MeshData]:
    """``MeshData`` of each of ``objects`` (objects of ``bl_scene``), by object name."""
    to_design = design_from_world(bl_scene)
    out = {}
    for obj in objects:
        # The evaluated object's own temporary mesh: no data-block is made, so this is safe in a
        # render thread too.
        obj_eval = obj.evaluated_get(depsgraph)
        mesh = obj_eval.to_mesh()
        try:
            to_frame(mesh, to_design @ obj_eval.matrix_world)
            out[obj.name] = mesh_data(mesh, obj.name)
        finally:
            obj_eval.to_mesh_clear()
    return out

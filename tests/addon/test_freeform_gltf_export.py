"""Blender's own glTF exporter and the free-form reader agree on the contract: node names are
object names, glTF metres +Y up become model millimetres z up, windings stay outward."""

from __future__ import annotations

import numpy as np
import pytest

from core_tracer.freeform.gltf import read_glb
from core_tracer.freeform.meshes import check_lens_volume

pytestmark = pytest.mark.blender


@pytest.mark.slow
@pytest.mark.parametrize("smooth", [False, True])
def test_a_mesh_exported_by_blender_reads_back_in_model_millimetres(tmp_path, smooth):
    import bmesh
    import bpy

    mesh = bpy.data.meshes.new("Lens data")
    bm = bmesh.new()
    bmesh.ops.create_uvsphere(bm, u_segments=24, v_segments=12, radius=0.02)
    bm.to_mesh(mesh)
    bm.free()
    for polygon in mesh.polygons:
        polygon.use_smooth = smooth
    obj = bpy.data.objects.new("Stop Lens", mesh)
    bpy.context.scene.collection.objects.link(obj)
    obj.location = (0.01, 0.05, 0.002)  # x 10 mm, 50 mm into the lamp (+y), z 2 mm
    obj.rotation_euler = (0.3, 0.0, 0.5)
    obj.scale = (1.0, 0.5, 1.0)
    bpy.context.view_layer.update()
    world = np.array([list(obj.matrix_world @ v.co) for v in mesh.vertices]) * 1000.0
    obj.select_set(True)
    path = tmp_path / "lamp.glb"
    bpy.ops.export_scene.gltf(filepath=str(path), export_format="GLB", use_selection=True)

    meshes = read_glb(path)
    assert list(meshes) == ["Stop Lens"]
    got = meshes["Stop Lens"]
    distance = np.abs(got.vertices[:, None, :] - world[None]).sum(axis=2).min(axis=1)
    assert distance.max() < 1e-3  # float32 metres: well under a micrometre
    volume = check_lens_volume(got)  # closed and outward after the axis change
    assert volume == pytest.approx(abs(np.linalg.det(np.asarray(obj.matrix_world)[:3, :3])) * 1e9 *
                                   sum(_tet_volumes(mesh)), rel=1e-4)
    if smooth:  # the corner normals are the sphere's, turned with the object
        centre = np.asarray(obj.matrix_world.translation) * 1000.0
        corners = got.vertices[got.triangles]
        outward = np.einsum("tcx,tcx->tc", got.corner_normals, corners - centre)
        assert (outward > 0).all()


def _tet_volumes(mesh) -> list[float]:
    """The mesh's own volume in its local frame (m³), by the divergence theorem over its triangles."""
    mesh.calc_loop_triangles()
    v = np.array([list(x.co) for x in mesh.vertices])
    return [float(np.dot(v[a], np.cross(v[b], v[c])) / 6.0) for a, b, c in (t.vertices for t in mesh.loop_triangles)]

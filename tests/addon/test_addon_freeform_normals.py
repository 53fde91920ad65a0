"""Free-form normals between Blender and the .glb: the tracer inside Blender shades a part with the
normals Blender's glTF exporter would write for it (``freeform.meshes.exported_normals``), and parts
made from a .glb carry normals that the exporter writes back as the file's, bit for bit
(``freeform.meshes.normals_exporting_as``, stored as free ``custom_normal`` corner vectors)."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import PRESETS

pytestmark = pytest.mark.blender

EXAMPLE = PRESETS / "freeform-sculpted-wrap-lamp.json"


def _corners(mesh) -> tuple[np.ndarray, np.ndarray]:
    """(positions, normals) of every triangle corner, (T, 3, 3) each: independent of the vertex order
    an exporter chooses."""
    return mesh.vertices[mesh.triangles], mesh.corner_normals


@pytest.mark.slow
def test_parts_made_from_the_example_export_back_to_its_numbers(lamp_addon, startup_scene, tmp_path):
    import bpy

    from core_tracer.freeform.gltf import read_glb

    bl_scene = startup_scene
    bpy.ops.lamp.preset_refresh()
    wm = bpy.context.window_manager
    wm.lamp_presets_index = next(i for i, item in enumerate(wm.lamp_presets) if item.file.endswith(EXAMPLE.name))
    assert bpy.ops.lamp.preset_apply() == {"FINISHED"}
    parts = lamp_addon.freeform.properties.role_objects(bl_scene)
    lamp_addon.freeform.export.write_glb(bl_scene, parts, str(tmp_path / "again.glb"))
    before, after = read_glb(EXAMPLE.with_suffix(".glb")), read_glb(tmp_path / "again.glb")
    assert sorted(before) == sorted(after)
    for name in before:
        (p0, n0), (p1, n1) = _corners(before[name]), _corners(after[name])
        assert np.array_equal(p0, p1), name
        assert np.array_equal(n0, n1), (name, f"{(n0 != n1).any(axis=2).mean():.1%} of the corners differ")


def test_a_normal_no_four_decimal_vector_gives_is_kept_to_the_exporters_rounding(lamp_addon, addon):
    meshes = lamp_addon.freeform.meshes
    rng = np.random.default_rng(7)
    target = rng.normal(size=(1000, 3))
    target /= np.linalg.norm(target, axis=1, keepdims=True)
    back = meshes.exported_normals(meshes.normals_exporting_as(target))
    turned = np.arccos(np.clip(np.einsum("ij,ij->i", back, target), -1.0, 1.0))
    assert turned.max() < 1e-4  # radians: the exporter's 4 decimals


def test_a_degenerate_triangle_is_shaded_with_the_normal_the_exporter_writes(lamp_addon, addon, bl_scene,
                                                                             tmp_path):
    """Blender gives a zero-area triangle zero corner normals; its glTF exporter writes them as up."""
    import bpy

    from core_tracer.freeform.gltf import read_glb

    mesh = bpy.data.meshes.new("Sliver")
    # A tetrahedron (closed) and a triangle of three points on a line.
    points = np.array([[0, 0, 0], [0.01, 0, 0], [0, 0.01, 0], [0, 0, 0.01], [0.02, 0, 0], [0.03, 0, 0],
                       [0.04, 0, 0]], np.float32)
    mesh.from_pydata(points.tolist(), [], [(0, 2, 1), (0, 1, 3), (1, 2, 3), (0, 3, 2), (4, 5, 6)])
    mesh.update()
    obj = bpy.data.objects.new("Sliver", mesh)
    bl_scene.collection.objects.link(obj)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    in_blender = lamp_addon.freeform.meshes.scene_meshes(bl_scene, depsgraph, [obj])["Sliver"]
    lamp_addon.freeform.export.write_glb(bl_scene, [obj], str(tmp_path / "sliver.glb"))
    from_file = read_glb(tmp_path / "sliver.glb")["Sliver"]
    p0, n0 = _corners(in_blender)
    p1, n1 = _corners(from_file)
    assert p0.shape == p1.shape and np.array_equal(p0, p1)
    assert np.array_equal(n0, n1)
    assert (n0 == [0.0, 0.0, 1.0]).all(axis=2).any()  # the sliver's corners, as the file has them

"""Writing a small .glb with pygltflib for the tests: meshes in model millimetres are stored as
Blender's exporter stores them, in glTF metres with +Y up, optionally under a node transform."""

from __future__ import annotations

import numpy as np
import pygltflib

from core_tracer.freeform.gltf import GLTF_TO_MODEL
from core_tracer.freeform.meshes import MeshData

MODEL_TO_GLTF = np.linalg.inv(GLTF_TO_MODEL)


def write_glb(path, meshes: list[MeshData], translation=None, rotation=None, scale=None) -> None:
    """One node per mesh, named by the mesh; the node transform (glTF's TRS) is given and the
    vertices stored are those that the transform brings to the model positions."""
    blob = bytearray()
    gltf = pygltflib.GLTF2(scene=0, scenes=[pygltflib.Scene(nodes=[])])
    local = np.eye(4)
    if translation is not None or rotation is not None or scale is not None:
        from core_tracer.freeform.gltf import _local_matrix

        trs = {"translation": translation, "rotation": rotation, "scale": scale}
        local = _local_matrix({key: list(value) for key, value in trs.items() if value is not None})
    inverse = np.linalg.inv(local)
    for mesh in meshes:
        v = (mesh.vertices @ MODEL_TO_GLTF.T)
        v = v @ inverse[:3, :3].T + inverse[:3, 3]
        # Per-corner vertices (as the exporter writes split normals): positions, normals, indices.
        corners = v[mesh.triangles].reshape(-1, 3).astype(np.float32)
        attributes = pygltflib.Attributes(POSITION=_add(gltf, blob, corners, pygltflib.VEC3, pygltflib.FLOAT,
                                                        bounds=True))
        if mesh.corner_normals is not None:
            n = mesh.corner_normals.reshape(-1, 3) @ MODEL_TO_GLTF.T
            n = n @ local[:3, :3]  # normals transform with the inverse transpose
            n /= np.linalg.norm(n, axis=1, keepdims=True)
            attributes.NORMAL = _add(gltf, blob, n.astype(np.float32), pygltflib.VEC3, pygltflib.FLOAT)
        index = np.arange(len(corners), dtype=np.uint32)
        indices = _add(gltf, blob, index, pygltflib.SCALAR, pygltflib.UNSIGNED_INT)
        gltf.meshes.append(pygltflib.Mesh(name=mesh.name + "-data",
                                          primitives=[pygltflib.Primitive(attributes=attributes, indices=indices)]))
        gltf.nodes.append(pygltflib.Node(name=mesh.name, mesh=len(gltf.meshes) - 1, translation=translation,
                                         rotation=rotation, scale=scale))
        gltf.scenes[0].nodes.append(len(gltf.nodes) - 1)
    gltf.buffers = [pygltflib.Buffer(byteLength=len(blob))]
    gltf.set_binary_blob(bytes(blob))
    gltf.save_binary(str(path))


def _add(gltf, blob: bytearray, data: np.ndarray, kind: str, component: int, bounds: bool = False) -> int:
    while len(blob) % 4:
        blob.append(0)
    offset = len(blob)
    raw = np.ascontiguousarray(data).tobytes()
    blob.extend(raw)
    gltf.bufferViews.append(pygltflib.BufferView(buffer=0, byteOffset=offset, byteLength=len(raw)))
    accessor = pygltflib.Accessor(bufferView=len(gltf.bufferViews) - 1, componentType=component, count=len(data),
                                  type=kind)
    if bounds:
        accessor.min = data.min(axis=0).tolist()
        accessor.max = data.max(axis=0).tolist()
    gltf.accessors.append(accessor)
    return len(gltf.accessors) - 1

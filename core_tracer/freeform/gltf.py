"""Reading the meshes of a glTF binary (.glb) into model space, with limits, never trusting it.

glTF is metres with +Y up; the model is millimetres with z up and the lamp facing -y (docs/model.md §2),
which is what Blender's exporter undoes: (x, y, z)_glTF → (1000 x, -1000 z, 1000 y). Each node
with a mesh becomes one ``MeshData`` named by the node (Blender's object name), its vertices
moved by the node's world transform. The file is parsed by ``pygltflib`` (the JSON chunk and the
binary chunk); the accessors are read here with every offset and count checked against the
buffer, so a corrupt or hostile file gives a message, not a crash or a huge allocation.
"""

from __future__ import annotations

import os
import stat
import struct
import warnings

import numpy as np

from ..scene.reading import SceneError
from ..scene.safe_text import printable
from .meshes import MAX_TRIANGLES, MAX_TRIANGLES_PER_MESH, MeshData

MAX_MESH_FILE_BYTES = 256 * 1024 * 1024  # a 2-million-triangle mesh with normals is about 100 MB
TRIANGLES_MODE = 4
# glTF (metres, +Y up) to model millimetres (z up, lamp facing -y): a rotation, so windings keep.
GLTF_TO_MODEL = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]]) * 1000.0
_COMPONENTS = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}
_WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}


def _error(path: str, message: str) -> SceneError:
    return SceneError(printable(path, 200), message)


def read_glb(path: str | os.PathLike, max_bytes: int = MAX_MESH_FILE_BYTES) -> dict[str, MeshData]:
    """Every mesh node of a .glb as ``MeshData`` in model space, by node name."""
    name = os.fspath(path)
    try:
        st = os.stat(name)
        if not stat.S_ISREG(st.st_mode):
            raise _error(name, "is not a regular file; allowed a .glb file")
        if st.st_size > max_bytes:
            raise _error(name, f"is {st.st_size} bytes; allowed at most {max_bytes} bytes (decimate the meshes)")
        with open(name, "rb") as f:
            data = f.read(max_bytes + 1)
    except SceneError:
        raise
    except OSError as e:
        raise _error(name, f"cannot be read ({e.strerror or e}); allowed a readable .glb beside the design") from None
    _check_header(name, data)
    from pygltflib import GLTF2  # it and its dependencies load only when a mesh file is read (start-up)

    try:
        with warnings.catch_warnings():  # its warnings about odd chunks would be a second line
            warnings.simplefilter("ignore")
            gltf = GLTF2.load_from_bytes(data)
            blob = gltf.binary_blob() or b""
    except Exception as e:  # noqa: BLE001 - pygltflib raises anything on a corrupt file
        raise _error(name, f"is not a readable glTF binary ({type(e).__name__}); export it again") from None
    try:
        return _meshes(gltf, blob)
    except SceneError as e:
        raise _error(name, e.message if not e.path else f"{e.path}: {e.message}") from None
    except (IndexError, KeyError, TypeError, ValueError, AttributeError) as e:
        raise _error(name, f"has an inconsistent glTF structure ({type(e).__name__}); export it again") from None


def _check_header(name: str, data: bytes) -> None:
    """The GLB container (glTF 2.0 §4.4): magic, version 2, the length of the file, a JSON chunk first."""
    if data[:4] != b"glTF":
        raise _error(name, "is not a glTF binary (no glTF header); allowed a .glb exported by Blender's glTF exporter")
    if len(data) < 20:
        raise _error(name, f"is cut short ({len(data)} bytes); export it again")
    version, length, chunk_length, chunk_type = struct.unpack_from("<IIII", data, 4)
    if version != 2:
        raise _error(name, f"is glTF binary version {version}; allowed version 2 (Blender's exporter writes it)")
    if length != len(data):
        raise _error(name, f"says it is {length} bytes but is {len(data)}: the file is cut or corrupt; export it again")
    if chunk_type != 0x4E4F534A or 20 + chunk_length > len(data):
        raise _error(name, "is not a readable glTF binary (no JSON chunk); export it again")


def _meshes(gltf, blob: bytes) -> dict[str, MeshData]:
    required = [e for e in (gltf.extensionsRequired or []) if isinstance(e, str)]
    if required:
        raise SceneError("extensionsRequired", f"the file needs {', '.join(printable(e, 40) for e in required[:4])}; "
                                               "allowed a .glb without required extensions (export without Draco "
                                               "compression or quantisation)")
    nodes = gltf.nodes or []
    world = _world_matrices(gltf)
    out: dict[str, MeshData] = {}
    total = 0
    for i, node in enumerate(nodes):
        if node.mesh is None:
            continue
        node_name = node.name or (gltf.meshes[node.mesh].name if gltf.meshes[node.mesh].name else f"node {i}")
        if node_name in out:
            raise SceneError(f'node "{printable(node_name, 40)}"', "is named twice; allowed unique object names")
        mesh = gltf.meshes[node.mesh]
        verts, tris, norms = [], [], []
        base = 0
        for prim in mesh.primitives:
            mode = TRIANGLES_MODE if prim.mode is None else prim.mode
            if mode != TRIANGLES_MODE:
                raise SceneError(f'mesh "{printable(node_name, 40)}"', f"has primitives of mode {mode}; allowed "
                                                                      "triangles only (no loose edges or points)")
            position = _accessor(gltf, blob, prim.attributes.POSITION, "VEC3", (5126,))
            if prim.indices is None:
                index = np.arange(len(position), dtype=np.int64)
            else:
                index = _accessor(gltf, blob, prim.indices, "SCALAR", (5121, 5123, 5125)).astype(np.int64)
            if len(index) % 3 or (len(index) and (index.max() >= len(position))):
                raise SceneError(f'mesh "{printable(node_name, 40)}"', "has triangle indices outside its vertices; "
                                                                      "export it again")
            total += len(index) // 3
            if len(index) // 3 > MAX_TRIANGLES_PER_MESH or total > MAX_TRIANGLES:
                raise SceneError(f'mesh "{printable(node_name, 40)}"',
                                 f"has too many triangles; allowed at most {MAX_TRIANGLES_PER_MESH} per mesh and "
                                 f"{MAX_TRIANGLES} in the file (decimate it)")
            normal = None
            if prim.attributes.NORMAL is not None:
                normal = _accessor(gltf, blob, prim.attributes.NORMAL, "VEC3", (5126,))
                if len(normal) != len(position):
                    raise SceneError(f'mesh "{printable(node_name, 40)}"', "has a normal count unlike its vertex "
                                                                          "count; export it again")
            verts.append(position.astype(np.float64))
            tris.append(index.reshape(-1, 3) + base)
            norms.append(normal)
            base += len(position)
        if not verts:
            continue
        matrix = world[i]
        v = np.concatenate(verts) @ matrix[:3, :3].T + matrix[:3, 3]
        v = v @ GLTF_TO_MODEL.T
        t = np.concatenate(tris)
        corner = None
        if all(n is not None for n in norms):
            normal_matrix = np.linalg.inv(matrix[:3, :3]).T if abs(np.linalg.det(matrix[:3, :3])) > 1e-300 else None
            if normal_matrix is not None:
                n = np.concatenate(norms).astype(np.float64) @ normal_matrix.T @ GLTF_TO_MODEL.T
                n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
                corner = n[t]
        if np.linalg.det(matrix[:3, :3]) < 0:  # a mirrored node: keep the faces' winding outward
            t = t[:, ::-1].copy()
            corner = None if corner is None else corner[:, ::-1].copy()
        out[node_name] = MeshData(node_name, v, t.astype(np.int32), corner)
    return out


def _world_matrices(gltf) -> dict[int, np.ndarray]:
    """Every node's world transform (parents first; a cycle or a node with two parents refused)."""
    nodes = gltf.nodes or []
    parent: dict[int, int] = {}
    for i, node in enumerate(nodes):
        for c in node.children or []:
            if c in parent or c == i or not 0 <= c < len(nodes):
                raise SceneError("nodes", "the node tree is not a tree; export it again")
            parent[c] = i
    world: dict[int, np.ndarray] = {}
    for i in range(len(nodes)):
        chain, j = [], i
        while j not in world:
            chain.append(j)
            if len(chain) > len(nodes):
                raise SceneError("nodes", "the node tree has a cycle; export it again")
            if j not in parent:
                break
            j = parent[j]
        m = world.get(j, np.eye(4)) if j in world else np.eye(4)
        for k in reversed(chain):
            m = m @ _local_matrix(nodes[k])
            world[k] = m
    return world


def _local_matrix(node) -> np.ndarray:
    if node.matrix:
        m = np.asarray(node.matrix, np.float64)
        if m.shape != (16,) or not np.isfinite(m).all():
            raise SceneError(f'node "{printable(node.name or "", 40)}"', "has a bad matrix; export it again")
        return m.reshape(4, 4).T  # glTF stores matrices column by column
    m = np.eye(4)
    t = np.asarray(node.translation or (0, 0, 0), np.float64)
    x, y, z, w = np.asarray(node.rotation or (0, 0, 0, 1), np.float64)
    s = np.asarray(node.scale or (1, 1, 1), np.float64)
    if not (np.isfinite(t).all() and np.isfinite([x, y, z, w]).all() and np.isfinite(s).all()):
        raise SceneError(f'node "{printable(node.name or "", 40)}"', "has a transform that is not finite")
    r = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                  [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                  [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    m[:3, :3] = r * s
    m[:3, 3] = t
    return m


def _accessor(gltf, blob: bytes, index: int | None, kind: str, components: tuple[int, ...]) -> np.ndarray:
    """The data of one accessor, every offset checked against the binary chunk."""
    if index is None or not 0 <= index < len(gltf.accessors or []):
        raise SceneError("accessors", "a mesh refers to a missing accessor; export it again")
    acc = gltf.accessors[index]
    if acc.sparse is not None:
        raise SceneError("accessors", "sparse accessors are not read; export without shape keys")
    if acc.type != kind or acc.componentType not in components:
        raise SceneError("accessors", f"expected {kind} data of a supported type; export it again")
    if acc.bufferView is None or not 0 <= acc.bufferView < len(gltf.bufferViews or []):
        raise SceneError("accessors", "an accessor has no buffer view; export it again")
    view = gltf.bufferViews[acc.bufferView]
    if view.buffer != 0:
        raise SceneError("bufferViews", "data outside the .glb's own buffer; allowed a self-contained .glb")
    dtype = np.dtype(_COMPONENTS[acc.componentType]).newbyteorder("<")
    width = _WIDTH[kind]
    item = dtype.itemsize * width
    stride = view.byteStride or item
    count = int(acc.count)
    start = int(view.byteOffset or 0) + int(acc.byteOffset or 0)
    end = start + (stride * (count - 1) + item if count else 0)
    view_end = int(view.byteOffset or 0) + int(view.byteLength)
    if count < 0 or stride < item or start < 0 or end > view_end or view_end > len(blob):
        raise SceneError("accessors", "an accessor reaches outside the file's data; the file is cut or corrupt")
    if count == 0:
        return np.zeros((0, width) if width > 1 else 0, dtype)
    raw = np.ndarray((count, width), dtype=dtype, buffer=blob, offset=start, strides=(stride, dtype.itemsize))
    out = np.array(raw)
    if out.dtype.kind == "f" and not np.isfinite(out).all():
        raise SceneError("accessors", "holds numbers that are not finite; export it again")
    return out if width > 1 else out[:, 0]

"""Reading the meshes of a glTF binary (.glb) into model space, with limits, never trusting it.

glTF is metres with +Y up; the model is millimetres with z up and the lamp facing -y (docs/model.md §2),
which is what Blender's exporter undoes: (x, y, z)_glTF → (1000 x, -1000 z, 1000 y). Each node
with a mesh becomes one ``MeshData`` named by the node (Blender's object name), its vertices
moved by the node's world transform.

The container (glTF 2.0 §4.4) and its JSON are read here, not by a glTF library, so that every
count is bounded before any work grows with it: the chunks are counted as they are walked, the
JSON chunk is limited in bytes before it is parsed, and every list is counted before any of its
entries is used. Every index, offset and stride is checked to be a whole number in range, every
transform and vertex to be finite and of a lamp's size, so a corrupt or hostile file gives a
one-line message naming the file and the glTF path (``nodes[3].scale``), never a traceback, a
huge allocation or minutes of parsing.
"""

from __future__ import annotations

import json
import os
import struct
from typing import NamedTuple

import numpy as np

from ..scene.reading import SceneError, read_bounded
from ..scene.safe_text import printable
from .meshes import MAX_COORDINATE_MM, MAX_TRIANGLES, MAX_TRIANGLES_PER_MESH, MeshData

MAX_MESH_FILE_BYTES = 256 * 1024 * 1024  # a 2-million-triangle mesh with normals is about 100 MB
# The JSON of Blender's export is about 1 kB an object; 16 MB is thousands of objects with room for
# their custom properties, and parses in well under a second.
MAX_JSON_BYTES = 16 * 1024 * 1024
# A glTF binary has a JSON chunk and a BIN chunk; the format lets readers skip unknown chunks, a few
# of which are allowed, not millions of empty ones.
MAX_CHUNKS = 16
# One node per Blender object: a lamp is tens to hundreds of parts. 4096 nodes (and meshes) leave
# room for the largest and are read in a fraction of a second.
MAX_NODES = 4096
MAX_MESHES = 4096
# The primitives read: one per material slot of each mesh node.
MAX_PRIMITIVES = 16384
# Four to eight accessors a primitive (positions, normals, texture coordinates, indices...).
MAX_ACCESSORS = 8 * MAX_PRIMITIVES
MAX_BUFFER_VIEWS = 8 * MAX_PRIMITIVES
MAX_BUFFERS = 16  # the .glb's own buffer is the only one read
MAX_VERTICES = 3 * MAX_TRIANGLES  # Blender writes at most one vertex per triangle corner
# Node transforms: a lamp is metres across; scales beyond a million and moves beyond 10 km are
# absurd, and products of such numbers would overflow the volume check.
MAX_TRANSLATION_M = 10_000.0
MAX_SCALE = 1e6
MAX_POSITION_M = MAX_COORDINATE_MM / 1000.0  # a stored vertex, before its node's transform
MAX_NORMAL = 1e3  # normals are unit vectors; anything far from it is not a normal
TRIANGLES_MODE = 4
JSON_CHUNK, BIN_CHUNK = 0x4E4F534A, 0x004E4942
# glTF (metres, +Y up) to model millimetres (z up, lamp facing -y): a rotation, so windings keep.
GLTF_TO_MODEL = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]]) * 1000.0
_COMPONENTS = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}
_WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}


def _error(path: str, message: str) -> SceneError:
    return SceneError(printable(path, 200), message)


def read_glb(path: str | os.PathLike, max_bytes: int = MAX_MESH_FILE_BYTES) -> dict[str, MeshData]:
    """Every mesh node of a .glb as ``MeshData`` in model space, by node name."""
    name = os.fspath(path)
    data = read_bounded(name, max_bytes, shown=printable(name, 200),
                        not_regular="is not a regular file; allowed a .glb file",
                        too_large="is {size} bytes; allowed at most {max_bytes} bytes (decimate the meshes)",
                        unreadable="cannot be read ({reason}); allowed a readable .glb beside the design")
    document, blob = _chunks(name, data)
    try:
        with np.errstate(all="ignore"):  # every result is checked; numpy's warnings would be more lines
            return _meshes(document, blob)
    except SceneError as e:
        raise _error(name, e.message if not e.path else f"{e.path}: {e.message}") from None


def _chunks(name: str, data: bytes) -> tuple[dict, bytes]:
    """The container (glTF 2.0 §4.4): magic, version 2, the length of the file, a JSON chunk first,
    then at most ``MAX_CHUNKS`` chunks of which the first BIN chunk is the buffer. Returns (the
    parsed JSON object, the BIN chunk's bytes)."""
    if data[:4] != b"glTF":
        raise _error(name, "is not a glTF binary (no glTF header); allowed a .glb exported by Blender's glTF exporter")
    if len(data) < 20:
        raise _error(name, f"is cut short ({len(data)} bytes); export it again")
    version, length = struct.unpack_from("<II", data, 4)
    if version != 2:
        raise _error(name, f"is glTF binary version {version}; allowed version 2 (Blender's exporter writes it)")
    if length != len(data):
        raise _error(name, f"says it is {length} bytes but is {len(data)}: the file is cut or corrupt; export it again")
    chunks: list[tuple[int, int, int]] = []  # (type, start, end)
    at = 12
    while at < len(data):
        if len(chunks) == MAX_CHUNKS:
            raise _error(name, f"has more than {MAX_CHUNKS} chunks; a glTF binary has two (JSON and BIN): "
                               "export it again")
        if at + 8 > len(data):
            raise _error(name, "ends inside a chunk header: the file is cut or corrupt; export it again")
        size, kind = struct.unpack_from("<II", data, at)
        if at + 8 + size > len(data):
            raise _error(name, "has a chunk longer than the file: the file is cut or corrupt; export it again")
        chunks.append((kind, at + 8, at + 8 + size))
        at += 8 + size
    if not chunks or chunks[0][0] != JSON_CHUNK:
        raise _error(name, "is not a readable glTF binary (no JSON chunk); export it again")
    _, start, end = chunks[0]
    if end - start > MAX_JSON_BYTES:
        raise _error(name, f"has {end - start} bytes of glTF JSON; allowed at most {MAX_JSON_BYTES} "
                           "(export fewer objects or without custom properties)")
    try:
        document = json.loads(data[start:end].decode("utf-8").rstrip(" \t\r\n\0"))
    except (ValueError, RecursionError) as e:  # UnicodeDecodeError and JSONDecodeError are ValueErrors
        raise _error(name, f"is not a readable glTF binary ({type(e).__name__} in its JSON); export it again") from None
    if not isinstance(document, dict):
        raise _error(name, "is not a readable glTF binary (its JSON is not an object); export it again")
    blob = next((data[s:e] for kind, s, e in chunks[1:] if kind == BIN_CHUNK), b"")
    return document, blob


# ---------------------------------------------------------------------------------------------
# The JSON's values, each checked where it is used: the path names it in the message.


def _show(value: object) -> str:
    return printable(repr(value), 40)


def _list(parent: dict, key: str, where: str, limit: int) -> list:
    value = parent.get(key, [])
    if not isinstance(value, list):
        raise SceneError(where, f"is {_show(value)}; allowed a list")
    if len(value) > limit:
        raise SceneError(where, f"has {len(value)} entries; allowed at most {limit} (export fewer objects, "
                                "or join them)")
    return value


def _object(value: object, where: str) -> dict:
    if not isinstance(value, dict):
        raise SceneError(where, f"is {_show(value)}; allowed a JSON object")
    return value


def _whole(value: object, where: str, lo: int, hi: int, *, what: str = "a whole number") -> int:
    """An integer in [lo, hi] (JSON's 4.0 is accepted as 4, true is not a number)."""
    if isinstance(value, float) and value.is_integer():
        value = int(value)
    if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
        raise SceneError(where, f"is {_show(value)}; allowed {what} from {lo} to {hi}")
    return value


def _index(value: object, where: str, count: int, what: str) -> int:
    if count == 0:
        raise SceneError(where, f"is {_show(value)}; the file has no {what}")
    return _whole(value, where, 0, count - 1, what=f"an index of {what}")


def _numbers(value: object, where: str, size: int, bound: float) -> np.ndarray:
    """``size`` finite numbers within ±``bound``."""
    if (not isinstance(value, list) or len(value) != size
            or not all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in value)):
        raise SceneError(where, f"is {_show(value)}; allowed {size} numbers")
    out = np.array([x if isinstance(x, float) or abs(x) < 2**1000 else float("inf") for x in value], np.float64)
    if not np.isfinite(out).all():
        raise SceneError(where, "holds numbers that are not finite; export it again")
    if np.abs(out).max(initial=0.0) > bound:
        raise SceneError(where, f"holds {np.abs(out).max():.4g}; allowed values within ±{bound:g} "
                                "(apply the object's scale in Blender, or check the units)")
    return out


def _name(value: object, where: str) -> str | None:
    if value is None or isinstance(value, str):
        return value or None
    raise SceneError(where, f"is {_show(value)}; allowed a text")


# ---------------------------------------------------------------------------------------------
# Meshes


class _Document:
    """The counted lists of a glTF document and its BIN chunk."""

    def __init__(self, document: dict, blob: bytes):
        self.nodes = _list(document, "nodes", "nodes", MAX_NODES)
        self.meshes = _list(document, "meshes", "meshes", MAX_MESHES)
        self.accessors = _list(document, "accessors", "accessors", MAX_ACCESSORS)
        self.views = _list(document, "bufferViews", "bufferViews", MAX_BUFFER_VIEWS)
        self.buffers = _list(document, "buffers", "buffers", MAX_BUFFERS)
        self.blob = blob


def _meshes(document: dict, blob: bytes) -> dict[str, MeshData]:
    required = _list(document, "extensionsRequired", "extensionsRequired", 64)
    required = [e for e in required if isinstance(e, str)]
    if required:
        raise SceneError("extensionsRequired", f"the file needs {', '.join(printable(e, 40) for e in required[:4])}; "
                                               "allowed a .glb without required extensions (export without Draco "
                                               "compression or quantisation)")
    doc = _Document(document, blob)
    nodes = [_object(node, f"nodes[{i}]") for i, node in enumerate(doc.nodes)]
    mesh_of = {i: _index(node["mesh"], f"nodes[{i}].mesh", len(doc.meshes), "meshes")
               for i, node in enumerate(nodes) if node.get("mesh") is not None}
    primitives = {}
    for m in sorted(set(mesh_of.values())):
        mesh = _object(doc.meshes[m], f"meshes[{m}]")
        primitives[m] = _list(mesh, "primitives", f"meshes[{m}].primitives", MAX_PRIMITIVES)
    reads = sum(len(primitives[m]) for m in mesh_of.values())
    if reads > MAX_PRIMITIVES:
        raise SceneError("meshes", f"the mesh nodes have {reads} primitives in all; allowed at most "
                                   f"{MAX_PRIMITIVES} (join objects, or use fewer materials)")
    world = _world_matrices(nodes)
    out: dict[str, MeshData] = {}
    totals = [0, 0]  # triangles, vertices
    for i, m in mesh_of.items():
        node_name = (_name(nodes[i].get("name"), f"nodes[{i}].name")
                     or _name(doc.meshes[m].get("name"), f"meshes[{m}].name") or f"node {i}")
        if node_name in out:
            raise SceneError(f'node "{printable(node_name, 40)}"', "is named twice; allowed unique object names")
        mesh = _node_mesh(doc, i, m, node_name, primitives[m], world[i], totals)
        if mesh is not None:
            out[node_name] = mesh
    return out


def _node_mesh(doc: _Document, i: int, m: int, node_name: str, primitives: list, matrix: np.ndarray,
               totals: list[int]) -> MeshData | None:
    """The mesh of node ``i`` in model space (None for a mesh without primitives); ``totals``
    counts the triangles and vertices read so far, checked before each accessor is read."""
    label = f'mesh "{printable(node_name, 40)}"'
    verts, tris, norms = [], [], []
    base = 0
    for p, prim in enumerate(primitives):
        where = f"meshes[{m}].primitives[{p}]"
        prim = _object(prim, where)
        mode = _whole(prim.get("mode", TRIANGLES_MODE), f"{where}.mode", 0, 6)
        if mode != TRIANGLES_MODE:
            raise SceneError(label, f"has primitives of mode {mode}; allowed triangles only (no loose edges or points)")
        attributes = _object(prim.get("attributes"), f"{where}.attributes")
        position = _locate(doc, attributes.get("POSITION"), f"{where}.attributes.POSITION", "VEC3", (5126,))
        indices = (None if prim.get("indices") is None
                   else _locate(doc, prim["indices"], f"{where}.indices", "SCALAR", (5121, 5123, 5125)))
        normals = (None if attributes.get("NORMAL") is None
                   else _locate(doc, attributes["NORMAL"], f"{where}.attributes.NORMAL", "VEC3", (5126,)))
        triangles = (position.count if indices is None else indices.count) // 3
        totals[0] += triangles
        totals[1] += position.count
        if triangles > MAX_TRIANGLES_PER_MESH or totals[0] > MAX_TRIANGLES:
            raise SceneError(label, f"has too many triangles; allowed at most {MAX_TRIANGLES_PER_MESH} per mesh and "
                                    f"{MAX_TRIANGLES} in the file (decimate it)")
        if totals[1] > MAX_VERTICES:
            raise SceneError(label, f"has too many vertices; allowed at most {MAX_VERTICES} in the file (decimate it)")
        if normals is not None and normals.count != position.count:
            raise SceneError(label, "has a normal count unlike its vertex count; export it again")
        positions = _read(doc, position, MAX_POSITION_M)
        index = (np.arange(len(positions), dtype=np.int64) if indices is None
                 else _read(doc, indices).astype(np.int64))
        if len(index) % 3 or (len(index) and (index.max() >= len(positions))):
            raise SceneError(label, "has triangle indices outside its vertices; export it again")
        normal = None if normals is None else _read(doc, normals, MAX_NORMAL)
        verts.append(positions.astype(np.float64))
        tris.append(index.reshape(-1, 3) + base)
        norms.append(normal)
        base += len(positions)
    if not verts:
        return None
    v = np.concatenate(verts) @ matrix[:3, :3].T + matrix[:3, 3]
    v = v @ GLTF_TO_MODEL.T
    if not np.isfinite(v).all() or np.abs(v).max(initial=0.0) > MAX_COORDINATE_MM:
        raise SceneError(f"nodes[{i}]", f"places its mesh beyond ±{MAX_COORDINATE_MM:g} mm of the origin; allowed a "
                                        "lamp's size (apply the scales of the object and its parents in Blender)")
    t = np.concatenate(tris)
    corner = None
    if all(n is not None for n in norms):
        normal_matrix = np.linalg.inv(matrix[:3, :3]).T if abs(np.linalg.det(matrix[:3, :3])) > 1e-300 else None
        if normal_matrix is not None:
            n = np.concatenate(norms).astype(np.float64) @ normal_matrix.T @ GLTF_TO_MODEL.T
            n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
            corner = n[t] if np.isfinite(n).all() else None
    if np.linalg.det(matrix[:3, :3]) < 0:  # a mirrored node: keep the faces' winding outward
        t = t[:, ::-1].copy()
        corner = None if corner is None else corner[:, ::-1].copy()
    return MeshData(node_name, v, t.astype(np.int32), corner)


def _world_matrices(nodes: list[dict]) -> dict[int, np.ndarray]:
    """Every node's world transform (parents first; a cycle or a node with two parents refused)."""
    parent: dict[int, int] = {}
    for i, node in enumerate(nodes):
        children = _list(node, "children", f"nodes[{i}].children", len(nodes))
        for k, c in enumerate(children):
            c = _index(c, f"nodes[{i}].children[{k}]", len(nodes), "nodes")
            if c in parent or c == i:
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
            m = m @ _local_matrix(nodes[k], f"nodes[{k}]")
            world[k] = m
    return world


def _local_matrix(node: dict, where: str = "node") -> np.ndarray:
    """A node's transform: its ``matrix`` (column by column, affine) or its translation, rotation
    (a unit quaternion) and scale, each finite and of a lamp's size."""
    if node.get("matrix") is not None:
        m = _numbers(node["matrix"], f"{where}.matrix", 16, MAX_TRANSLATION_M * 1000).reshape(4, 4).T
        if np.abs(m[:3, :3]).max() > MAX_SCALE or np.abs(m[:3, 3]).max() > MAX_TRANSLATION_M or \
                m[3].tolist() != [0.0, 0.0, 0.0, 1.0]:
            raise SceneError(f"{where}.matrix", f"is not an affine transform within a scale of {MAX_SCALE:g} and a "
                                                f"move of {MAX_TRANSLATION_M:g} m; export it again")
        return m
    m = np.eye(4)
    t = _numbers(node.get("translation", [0, 0, 0]), f"{where}.translation", 3, MAX_TRANSLATION_M)
    x, y, z, w = _numbers(node.get("rotation", [0, 0, 0, 1]), f"{where}.rotation", 4, 1.01)
    if abs(x * x + y * y + z * z + w * w - 1.0) > 0.01:
        raise SceneError(f"{where}.rotation", "is not a unit quaternion; export it again")
    s = _numbers(node.get("scale", [1, 1, 1]), f"{where}.scale", 3, MAX_SCALE)
    r = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                  [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                  [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    m[:3, :3] = r * s
    m[:3, 3] = t
    return m


class _Accessor(NamedTuple):
    """Where an accessor's data lies in the BIN chunk, checked, before any of it is read."""

    index: int
    count: int
    start: int
    stride: int
    dtype: np.dtype
    width: int


def _locate(doc: _Document, index: object, where: str, kind: str, components: tuple[int, ...]) -> _Accessor:
    """The accessor ``index`` of ``kind`` data, every index, offset and stride a whole number in range
    and its data inside the binary chunk."""
    if index is None:
        raise SceneError(where, "is missing; a mesh needs vertex positions; export it again")
    index = _index(index, where, len(doc.accessors), "accessors")
    at = f"accessors[{index}]"
    acc = _object(doc.accessors[index], at)
    if acc.get("sparse") is not None:
        raise SceneError(at, "sparse accessors are not read; export without shape keys")
    component = acc.get("componentType")
    if acc.get("type") != kind or isinstance(component, bool) or component not in components:
        raise SceneError(at, f"{where} expects {kind} data of a supported type; export it again")
    count = _whole(acc.get("count"), f"{at}.count", 0, 2**32)
    view_index = _index(acc.get("bufferView"), f"{at}.bufferView", len(doc.views), "bufferViews")
    vat = f"bufferViews[{view_index}]"
    view = _object(doc.views[view_index], vat)
    if view.get("buffer") != 0 or isinstance(view.get("buffer"), bool):
        raise SceneError(f"{vat}.buffer", "data outside the .glb's own buffer; allowed a self-contained .glb")
    dtype = np.dtype(_COMPONENTS[component]).newbyteorder("<")
    width = _WIDTH[kind]
    item = dtype.itemsize * width
    stride = item
    if view.get("byteStride") is not None:
        stride = _whole(view["byteStride"], f"{vat}.byteStride", 4, 252, what="a whole number of bytes")
        if stride % 4 or stride < item:
            raise SceneError(f"{vat}.byteStride", f"is {stride}; allowed a multiple of 4 of at least {item} bytes")
    view_start = _whole(view.get("byteOffset", 0), f"{vat}.byteOffset", 0, 2**32)
    view_end = view_start + _whole(view.get("byteLength"), f"{vat}.byteLength", 1, 2**32)
    start = view_start + _whole(acc.get("byteOffset", 0), f"{at}.byteOffset", 0, 2**32)
    end = start + (stride * (count - 1) + item if count else 0)
    if end > view_end or view_end > len(doc.blob):
        raise SceneError("accessors", "an accessor reaches outside the file's data; the file is cut or corrupt")
    return _Accessor(index, count, start, stride, dtype, width)


def _read(doc: _Document, acc: _Accessor, bound: float | None = None) -> np.ndarray:
    """The data of a located accessor; float data finite and within ±``bound``."""
    if acc.count == 0:
        return np.zeros((0, acc.width) if acc.width > 1 else 0, acc.dtype)
    raw = np.ndarray((acc.count, acc.width), dtype=acc.dtype, buffer=doc.blob, offset=acc.start,
                     strides=(acc.stride, acc.dtype.itemsize))
    out = np.array(raw)
    if out.dtype.kind == "f":
        at = f"accessors[{acc.index}]"
        if not np.isfinite(out).all():
            raise SceneError(at, "holds numbers that are not finite; export it again")
        if bound is not None and np.abs(out).max() > bound:
            raise SceneError(at, f"holds {np.abs(out).max():.4g}; allowed values within ±{bound:g} (apply the "
                                 "object's scale in Blender, or check the units)")
    return out if acc.width > 1 else out[:, 0]

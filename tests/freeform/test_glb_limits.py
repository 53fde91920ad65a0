"""A hostile or careless .glb is refused in one line naming the file and the glTF path, quickly:
counts are bounded before parsing work grows with them, transforms and vertices are finite and of
a lamp's size, indices and strides are whole numbers in range (issue 21)."""

from __future__ import annotations

import json
import struct
import time

import numpy as np
import pytest
from glb_writer import write_glb
from helpers import run_cli

from core_tracer.freeform import load, render_passes, shapes
from core_tracer.freeform.gltf import MAX_CHUNKS, MAX_NODES, MAX_PRIMITIVES, read_glb
from core_tracer.freeform.meshes import MeshData
from core_tracer.scene.reading import SceneError
from core_tracer.scene.validate import parse_scene

JSON_CHUNK, BIN_CHUNK = 0x4E4F534A, 0x004E4942
DESIGN = {"schema": "lamp-scene/2", "lamps": [{}], "image": {"width": 8, "height": 8},
          "freeform": {"mesh_file": "lamp.glb", "parts": [{"object": "Lens", "role": "lens"}]}}


def split_glb(data: bytes) -> tuple[dict, bytes]:
    """(JSON document, BIN chunk) of a .glb written by ``write_glb``."""
    size, _ = struct.unpack_from("<II", data, 12)
    doc = json.loads(data[20:20 + size])
    bin_size, _ = struct.unpack_from("<II", data, 20 + size)
    return doc, data[28 + size:28 + size + bin_size]


def join_glb(doc: dict, blob: bytes = b"", extra: bytes = b"") -> bytes:
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    body = struct.pack("<II", len(text), JSON_CHUNK) + text
    if blob:
        blob += b"\0" * (-len(blob) % 4)
        body += struct.pack("<II", len(blob), BIN_CHUNK) + blob
    body += extra
    return struct.pack("<4sII", b"glTF", 2, 12 + len(body)) + body


def lens_glb(folder) -> tuple[dict, bytes]:
    write_glb(folder / "lens.glb", [shapes.box("Lens", (-20, 0, -20), (20, 3, 20))])
    return split_glb((folder / "lens.glb").read_bytes())


def write_pair(folder, data: bytes) -> str:
    (folder / "lamp.glb").write_bytes(data)
    (folder / "design.json").write_text(json.dumps(DESIGN))
    return str(folder / "design.json")


def refusal(folder, data: bytes) -> str:
    """The one-line message of ``load`` for this .glb, which names the file."""
    path = write_pair(folder, data)
    with pytest.raises(SceneError) as err:
        load(path)
    text = str(err.value)
    assert "\n" not in text and "lamp.glb" in text, text
    return text


@pytest.mark.slow
def test_a_huge_node_scale_is_refused_in_one_line_not_an_overflow(tmp_path):
    doc, blob = lens_glb(tmp_path)
    doc["nodes"][0]["scale"] = [1e103, 1e103, 1e103]
    path = write_pair(tmp_path, join_glb(doc, blob))
    proc = run_cli("render", path, "-o", tmp_path / "out.exr")
    assert proc.returncode == 2 and "Traceback" not in proc.stderr, proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1
    assert "lamp.glb: nodes[0].scale: holds 1e+103; allowed values within ±1e+06" in proc.stderr
    assert not (tmp_path / "out.exr").exists()


def test_a_mesh_of_absurd_size_given_in_memory_is_refused():
    m = shapes.box("Lens", (-20, 0, -20), (20, 3, 20))
    with pytest.raises(SceneError) as err:
        render_passes(parse_scene(DESIGN), {"Lens": MeshData("Lens", m.vertices * 1e104, m.triangles)})
    assert str(err.value).startswith('mesh "Lens": has vertices 2e+105 mm from the origin; allowed within ±1e+07 mm')


def test_scales_that_multiply_beyond_a_lamps_size_are_refused(tmp_path):
    doc, blob = lens_glb(tmp_path)
    doc["nodes"] += [{"name": f"Empty{k}", "scale": [1e5] * 3, "children": [k]} for k in range(4)]
    text = refusal(tmp_path, join_glb(doc, blob))
    assert "lamp.glb: nodes[0]: places its mesh beyond ±1e+07 mm of the origin" in text


@pytest.mark.slow
def test_many_empty_nodes_are_refused_at_once(tmp_path):
    # 250,000 empty nodes in 4.9 MB took 89 s for an 8x8 render.
    data = join_glb({"asset": {"version": "2.0"}, "nodes": [{"name": f"Empty.{k:06d}"} for k in range(250_000)]})
    start = time.perf_counter()
    text = refusal(tmp_path, data)
    assert time.perf_counter() - start < 5
    assert text.endswith(f"lamp.glb: nodes: has 250000 entries; allowed at most {MAX_NODES} (export fewer objects, "
                         "or join them)")


def test_many_empty_chunks_are_refused_at_once(tmp_path):
    data = join_glb({"asset": {"version": "2.0"}}, extra=struct.pack("<II", 0, 0x12345678) * 3_000_000)
    start = time.perf_counter()
    text = refusal(tmp_path, data)
    assert time.perf_counter() - start < 5
    assert f"lamp.glb: has more than {MAX_CHUNKS} chunks" in text


@pytest.mark.slow
def test_the_most_nodes_allowed_are_read_quickly(tmp_path):
    doc, blob = lens_glb(tmp_path)
    doc["nodes"] = [{"name": f"Lens.{k:04d}", "mesh": 0, "translation": [k * 0.05, 0, 0]} for k in range(MAX_NODES)]
    (tmp_path / "many.glb").write_bytes(join_glb(doc, blob))
    start = time.perf_counter()
    meshes = read_glb(tmp_path / "many.glb")
    assert time.perf_counter() - start < 10
    assert len(meshes) == MAX_NODES and meshes["Lens.4095"].vertices[:, 0].min() == pytest.approx(4095 * 50 - 20)


def test_primitives_are_counted_before_they_are_read(tmp_path):
    doc, blob = lens_glb(tmp_path)
    doc["meshes"][0]["primitives"] *= 8
    doc["nodes"] = [{"name": f"Lens.{k:04d}", "mesh": 0} for k in range(MAX_PRIMITIVES // 8 + 1)]
    text = refusal(tmp_path, join_glb(doc, blob))
    assert f"lamp.glb: meshes: the mesh nodes have {MAX_PRIMITIVES + 8} primitives in all" in text


def _set(doc: dict, dotted: str, value) -> None:
    keys = [int(k) if k.isdigit() else k for k in dotted.split(".")]
    target = doc
    for k in keys[:-1]:
        target = target[k]
    target[keys[-1]] = value


@pytest.mark.parametrize("field,value,needle", [
    ("nodes.0.mesh", -1, "nodes[0].mesh: is -1; allowed an index of meshes from 0 to 0"),
    ("nodes.0.mesh", 1, "nodes[0].mesh: is 1; allowed an index of meshes from 0 to 0"),
    ("nodes.0.mesh", 0.5, "nodes[0].mesh: is 0.5; allowed an index of meshes"),
    ("nodes.0.mesh", True, "nodes[0].mesh: is True; allowed an index of meshes"),
    ("nodes.0.mesh", "0", "nodes[0].mesh: is '0'; allowed an index of meshes"),
    ("nodes.0.children", [7], "nodes[0].children[0]: is 7; allowed an index of nodes from 0 to 0"),
    ("nodes.0.name", 5, "nodes[0].name: is 5; allowed a text"),
    ("nodes.0.translation", [0, 1e9, 0], "nodes[0].translation: holds 1e+09; allowed values within ±10000"),
    ("nodes.0.translation", [0, 0], "nodes[0].translation: is [0, 0]; allowed 3 numbers"),
    ("nodes.0.rotation", [0, 0, 0, 0.5], "nodes[0].rotation: is not a unit quaternion"),
    ("nodes.0.scale", [1, float("nan"), 1], "nodes[0].scale: holds numbers that are not finite"),
    ("nodes.0.scale", [1, 10**400, 1], "nodes[0].scale: holds numbers that are not finite"),
    ("nodes.0.matrix", [1] * 16, "nodes[0].matrix: is not an affine transform"),
    ("bufferViews.0.byteStride", 12.5, "bufferViews[0].byteStride: is 12.5; allowed a whole number of bytes from 4"),
    ("bufferViews.0.byteStride", 14, "bufferViews[0].byteStride: is 14; allowed a multiple of 4 of at least 12"),
    ("bufferViews.0.byteStride", 8, "bufferViews[0].byteStride: is 8; allowed a multiple of 4 of at least 12"),
    ("bufferViews.0.byteOffset", -4, "bufferViews[0].byteOffset: is -4; allowed a whole number from 0"),
    ("bufferViews.0.buffer", 1, "bufferViews[0].buffer: data outside the .glb's own buffer"),
    ("accessors.0.count", 1.5, "accessors[0].count: is 1.5; allowed a whole number from 0"),
    ("accessors.0.bufferView", -1, "accessors[0].bufferView: is -1; allowed an index of bufferViews"),
    ("accessors.0.componentType", True, "accessors[0]: meshes[0].primitives[0].attributes.POSITION expects VEC3"),
    ("meshes.0.primitives.0.indices", 99, "meshes[0].primitives[0].indices: is 99; allowed an index of accessors"),
    ("meshes.0.primitives.0.mode", 4.5, "meshes[0].primitives[0].mode: is 4.5; allowed a whole number from 0 to 6"),
    ("meshes.0.primitives", {}, "meshes[0].primitives: is {}; allowed a list"),
    ("meshes", [{"primitives": []}] * 5000, "meshes: has 5000 entries; allowed at most 4096"),
    ("accessors", [{}] * 200_000, "accessors: has 200000 entries; allowed at most 131072"),
    ("buffers", [{"byteLength": 1}] * 17, "buffers: has 17 entries; allowed at most 16"),
])
def test_indices_strides_and_transforms_are_checked(tmp_path, field, value, needle):
    doc, blob = lens_glb(tmp_path)
    _set(doc, field, value)
    assert needle in refusal(tmp_path, join_glb(doc, blob))


@pytest.mark.parametrize("value,needle", [
    (np.float32(np.inf), "accessors[0]: holds numbers that are not finite"),
    (np.float32(1e30), "accessors[0]: holds 1e+30; allowed values within ±10000"),
])
def test_vertex_values_are_finite_and_of_a_lamps_size(tmp_path, value, needle):
    doc, blob = lens_glb(tmp_path)
    view = doc["bufferViews"][doc["accessors"][0]["bufferView"]]
    blob = bytearray(blob)
    blob[view.get("byteOffset", 0):view.get("byteOffset", 0) + 4] = np.float32(value).tobytes()
    assert needle in refusal(tmp_path, join_glb(doc, bytes(blob)))


def test_a_huge_json_chunk_is_refused_before_it_is_parsed(tmp_path):
    data = join_glb({"asset": {"version": "2.0"}, "extras": "x" * (17 * 1024 * 1024)})
    assert "lamp.glb: has 17825" in refusal(tmp_path, data) and "bytes of glTF JSON; allowed at most" in \
        refusal(tmp_path, data)


def test_deeply_nested_json_is_one_line(tmp_path):
    text = b"[" * 100_000 + b"]" * 100_000
    data = struct.pack("<4sIIII", b"glTF", 2, 20 + len(text), len(text), JSON_CHUNK) + text
    assert "is not a readable glTF binary (RecursionError in its JSON)" in refusal(tmp_path, data)

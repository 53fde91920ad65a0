"""Hostile .glb files and free-form scene fields, generated: the answer is always the meshes, or a
``SceneError`` whose one line names the file (and the glTF path where one is at fault); never a
traceback, a numpy warning, a non-finite or absurd vertex, or a long wait (issue 21).

The default run takes seconds. ``LAMP_FUZZ_EXAMPLES=N`` multiplies every test's number of examples
by N for a long run, e.g. ``LAMP_FUZZ_EXAMPLES=50 pytest tests/freeform/test_fuzz_glb.py``.
"""

from __future__ import annotations

import copy
import json
import struct
import warnings

import numpy as np
import pytest
from glb_writer import write_glb
from helpers import fuzz
from hypothesis import given
from hypothesis import strategies as st
from test_glb_limits import join_glb, split_glb

from core_tracer.freeform import shapes
from core_tracer.freeform.gltf import read_glb
from core_tracer.freeform.meshes import MAX_COORDINATE_MM, check_lens_volume, check_mesh
from core_tracer.scene.reading import SceneError
from core_tracer.scene.validate import parse_scene


@pytest.fixture(scope="module")
def lens(tmp_path_factory) -> tuple[dict, bytes, bytes]:
    """(JSON document, BIN chunk, whole file) of a small valid .glb: a box lens under a transform."""
    folder = tmp_path_factory.mktemp("lens")
    write_glb(folder / "lens.glb", [shapes.box("Lens", (-20, 0, -20), (20, 3, 20))], translation=[0.01, 0, 0],
              rotation=[0, 0.258819, 0, 0.965926], scale=[1, 2, 1])
    data = (folder / "lens.glb").read_bytes()
    return (*split_glb(data), data)


def answer(tmp_path, data: bytes) -> dict | None:
    """Read ``data`` as lamp.glb: the meshes (each checked as a lens would be), or None after a
    one-line ``SceneError`` naming the file. Any other exception or any warning fails the test."""
    path = tmp_path / "lamp.glb"
    path.write_bytes(data)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        try:
            meshes = read_glb(path)
        except SceneError as e:
            text = str(e)
            assert "\n" not in text and text.startswith(str(path)), text
            return None
        for mesh in meshes.values():
            assert np.isfinite(mesh.vertices).all() and np.abs(mesh.vertices).max(initial=0) <= MAX_COORDINATE_MM
            try:
                check_mesh(mesh)
                check_lens_volume(mesh)
            except SceneError as e:
                assert "\n" not in str(e)
    return meshes


JSON_LEAF = st.one_of(st.none(), st.booleans(), st.integers(-2**70, 2**70), st.sampled_from([10**400, -1, 0, 1, 3]),
                      st.floats(allow_nan=True), st.text(max_size=8))
JSON_VALUE = st.recursive(JSON_LEAF, lambda kids: st.one_of(st.lists(kids, max_size=5),
                                                            st.dictionaries(st.text(max_size=8), kids, max_size=4)),
                          max_leaves=12)


def paths(node, prefix=()) -> list[tuple]:
    """Every place in a JSON document (object keys and list indices), leaves and branches."""
    out = [prefix] if prefix else []
    if isinstance(node, dict):
        for key, value in node.items():
            out += paths(value, (*prefix, key))
    elif isinstance(node, list):
        for i, value in enumerate(node):
            out += paths(value, (*prefix, i))
    return out


@pytest.mark.slow
@fuzz(120)
@given(data=st.data())
def test_any_value_anywhere_in_the_gltf_json(tmp_path, lens, data):
    doc, blob = copy.deepcopy(lens[0]), lens[1]
    for _ in range(data.draw(st.integers(1, 3))):
        where = data.draw(st.sampled_from(paths(doc) + [("nodes", 0, "mesh"), ("bufferViews", 0, "byteStride"),
                                                         ("nodes", 0, "children"), ("nodes", 0, "matrix")]))
        node = doc
        try:
            for step in where[:-1]:
                node = node[step]
            node[where[-1]] = data.draw(JSON_VALUE)
        except (KeyError, IndexError, TypeError):
            continue
    answer(tmp_path, join_glb(doc, blob))


@pytest.mark.slow
@fuzz(80)
@given(data=st.data())
def test_numbers_at_their_edges_in_transforms_and_vertices(tmp_path, lens, data):
    doc, blob = copy.deepcopy(lens[0]), lens[1]
    edge = st.sampled_from([0.0, -0.0, 1e-320, 1e-30, 1e3, 1e6, 1.0000001e6, 1e7, 1e30, 3e38, 1e103, 1e308,
                            float("nan"), float("inf"), -1e103])
    key, size = data.draw(st.sampled_from([("translation", 3), ("rotation", 4), ("scale", 3), ("matrix", 16)]))
    doc["nodes"][0].pop("matrix", None)
    doc["nodes"][0][key] = data.draw(st.lists(edge, min_size=size, max_size=size))
    raw = bytearray(blob)
    for _ in range(data.draw(st.integers(0, 3))):  # vertices of the lens at the edges too
        at = data.draw(st.integers(0, 35)) * 4
        with np.errstate(over="ignore"):  # 1e308 as float32 is inf, as meant
            raw[at:at + 4] = np.float32(data.draw(edge)).tobytes()
    answer(tmp_path, join_glb(doc, bytes(raw)))


@pytest.mark.slow
@fuzz(150)
@given(data=st.data())
def test_damaged_bytes(tmp_path, lens, data):
    *_, good = lens
    raw = bytearray(good)
    how = data.draw(st.sampled_from(["flip", "cut", "splice", "chunks"]))
    if how == "flip":
        for _ in range(data.draw(st.integers(1, 8))):
            at = data.draw(st.integers(0, len(raw) - 1))
            raw[at] = data.draw(st.integers(0, 255))
    elif how == "cut":
        raw = raw[:data.draw(st.integers(0, len(raw)))]
        raw[8:12] = struct.pack("<I", len(raw))[:max(0, min(4, len(raw) - 8))]
    elif how == "splice":
        at = data.draw(st.integers(12, len(raw)))
        raw[at:at] = data.draw(st.binary(max_size=64))
    else:  # extra chunks, of any type and length field
        for _ in range(data.draw(st.integers(1, 20))):
            size = data.draw(st.sampled_from([0, 4, 8, 2**31]))
            raw += struct.pack("<II", size, data.draw(st.integers(0, 2**32 - 1)))
            raw += bytes(min(size, 8))
        raw[8:12] = struct.pack("<I", len(raw))
    answer(tmp_path, bytes(raw))


@fuzz(60)
@given(text=st.binary(max_size=200))
def test_any_json_chunk(tmp_path, text):
    text += b" " * (-len(text) % 4)
    answer(tmp_path, struct.pack("<4sIIII", b"glTF", 2, 20 + len(text), len(text), 0x4E4F534A) + text)


DESIGN = {"schema": "lamp-scene/2", "lamps": [{}], "image": {"width": 8, "height": 8},
          "freeform": {"mesh_file": "lamp.glb", "parts": [{"object": "Lens", "role": "lens"}]}}


@pytest.mark.slow
@fuzz(150)
@given(data=st.data())
def test_any_value_in_the_freeform_section(data):
    doc = copy.deepcopy(DESIGN)
    where = data.draw(st.sampled_from([("freeform",), ("freeform", "mesh_file"), ("freeform", "parts"),
                                       ("freeform", "parts", 0), ("freeform", "parts", 0, "object"),
                                       ("freeform", "parts", 0, "role"), ("freeform", "parts", 0, "lens"),
                                       ("freeform", "parts", 0, "lens", "ior"),
                                       ("freeform", "parts", 0, "lens", "absorption"), ("freeform", "extra")]))
    node = doc
    for step in where[:-1]:
        node = node.setdefault(step, {}) if isinstance(node, dict) else node[step]
    node[where[-1]] = data.draw(JSON_VALUE)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        try:
            parse_scene(json.loads(json.dumps(doc)))
        except SceneError as e:
            assert "\n" not in str(e) and str(e)

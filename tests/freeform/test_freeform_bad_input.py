"""Every user's mistake in a free-form design is one line naming the object and what to fix."""

from __future__ import annotations

import json
import struct
import subprocess
import sys

import numpy as np
import pytest
from glb_writer import write_glb
from helpers import ROOT, run_cli
from needs import require

from core_tracer.freeform import load, render_passes, shapes
from core_tracer.freeform.meshes import MAX_TRIANGLES_PER_MESH, MeshData
from core_tracer.scene.reading import SceneError
from core_tracer.scene.validate import parse_scene

pytestmark = pytest.mark.slow

require("embreex")


def design(parts: list[dict]) -> dict:
    return {"schema": "lamp-scene/2", "lamps": [{}], "image": {"width": 8, "height": 8},
            "freeform": {"mesh_file": "lamp.glb", "parts": parts}}


def lens_error(mesh: MeshData, *more: tuple[MeshData, str]) -> str:
    parts = [{"object": mesh.name, "role": "lens"}] + [{"object": m.name, "role": r} for m, r in more]
    meshes = {mesh.name: mesh, **{m.name: m for m, _ in more}}
    with pytest.raises(SceneError) as err:
        render_passes(parse_scene(design(parts)), meshes)
    return one_line(err.value)


def one_line(error: Exception) -> str:
    text = str(error)
    assert "\n" not in text and text
    return text


def slab(name="Lens", lo=(-20, 0, -20), hi=(20, 3, 20)) -> MeshData:
    return shapes.box(name, lo, hi)


def test_open_lens_mesh():
    m = slab()
    text = lens_error(MeshData("Lens", m.vertices, m.triangles[:-1]))
    assert text.startswith('mesh "Lens": is not closed (3 open or non-manifold edges)') and "fill the holes" in text


def test_flipped_lens_normals():
    m = slab()
    text = lens_error(MeshData("Lens", m.vertices, m.triangles[:, ::-1].copy()))
    assert text.startswith('mesh "Lens": has its normals pointing inward') and "Recalculate Outside" in text


@pytest.mark.parametrize("double_sided", [False, True])
def test_lens_with_no_volume(double_sided):
    v = np.array([[0, 0, 0], [10, 0, 0], [10, 0, 10], [0, 0, 10]], float)
    t = np.array([[0, 1, 2], [0, 2, 3]] + ([[0, 2, 1], [0, 3, 2]] if double_sided else []), np.int32)
    text = lens_error(MeshData("Plane", v, t))
    assert text.startswith('mesh "Plane": encloses no volume') and "Solidify" in text


def test_overlapping_lens_volumes():
    text = lens_error(slab("Left", (-20, 0, -20), (5, 3, 20)), (slab("Right", (0, 0, -20), (20, 3, 20)), "lens"))
    assert text.startswith('lens "Left": overlaps lens "Right"')


def test_touching_lenses_are_fine():
    scene = parse_scene(design([{"object": "Left", "role": "lens"}, {"object": "Right", "role": "lens"}]))
    meshes = {m.name: m for m in (slab("Left", (-20, 0, -20), (0, 3, 20)), slab("Right", (0, 0, -20), (20, 3, 20)))}
    assert render_passes(scene, meshes).image.shape == (8, 8, 3)


@pytest.mark.parametrize("part,needles", [
    ({"object": "Lens", "role": "lens", "lens": {"ior": 5}},
     ("freeform.parts[0].lens.ior: 5 is out of range; allowed [1, 3]",)),
    ({"object": "Lens", "role": "lens", "lens": {"absorption": [0, 0]}},
     ("freeform.parts[0].lens.absorption", "expected a list of 3 numbers")),
    ({"object": "Lens", "role": "lens", "lens": {"absorption": [0, 0, 0], "transmitted_color": [1, 0.5, 0.5]}},
     ("freeform.parts[0].lens.absorption", "cannot be given with transmitted_color")),
    ({"object": "Lens", "role": "bulb", "bulb": {"intensity": [1, 1, -1]}},
     ("freeform.parts[0].bulb.intensity[2]: -1 is out of range",)),
    ({"object": "Lens", "role": "reflector", "lens": {"ior": 1.5}},
     ('freeform.parts[0].lens: is not a value of role "reflector"; allowed only the key "reflector"',)),
    ({"role": "lens"}, ("freeform.parts[0].object: is required",)),
    ({"object": "Lens"}, ("freeform.parts[0].role: is required", '"lens"', '"body"')),
    ({"object": "Lens", "role": "glass"}, ('freeform.parts[0].role: "glass" is not allowed', '"side_wall"')),
])
def test_role_values_missing_or_out_of_range(part, needles):
    with pytest.raises(SceneError) as err:
        parse_scene(design([part]))
    text = one_line(err.value)
    for needle in needles:
        assert needle in text


def test_object_not_in_the_mesh_file():
    scene = parse_scene(design([{"object": "Lense", "role": "lens"}]))
    with pytest.raises(SceneError) as err:
        render_passes(scene, {"Lens": slab()})
    assert one_line(err.value) == 'freeform.parts[0].object: "Lense" is not a mesh of lamp.glb; allowed one of "Lens"'


def test_each_mesh_once():
    with pytest.raises(SceneError, match=r"parts\[1\].object: \"Lens\" is already given in freeform.parts\[0\]"):
        parse_scene(design([{"object": "Lens", "role": "lens"}, {"object": "Lens", "role": "body"}]))


@pytest.mark.parametrize("name", ["../lamp.glb", "sub/lamp.glb", "lamp.obj", ".glb", "C:lamp.glb", ""])
def test_mesh_file_is_a_plain_name(name):
    doc = design([{"object": "Lens", "role": "lens"}])
    doc["freeform"]["mesh_file"] = name
    with pytest.raises(SceneError) as err:
        parse_scene(doc)
    assert one_line(err.value).startswith("freeform.mesh_file:") and "without folders" in str(err.value)


def test_huge_mesh_is_refused_before_any_work():
    # 2,000,001 triangles of three vertices: refused by count before a normal is computed.
    m = MeshData("Huge", np.zeros((3, 3)), np.zeros((MAX_TRIANGLES_PER_MESH + 1, 3), np.int32))
    scene = parse_scene(design([{"object": "Huge", "role": "body"}]))
    with pytest.raises(SceneError) as err:
        render_passes(scene, {"Huge": m})
    assert one_line(err.value) == (f'mesh "Huge": has {MAX_TRIANGLES_PER_MESH + 1} triangles; allowed at most '
                                   f"{MAX_TRIANGLES_PER_MESH} (decimate it, or apply fewer subdivision levels)")


def test_mesh_with_bad_indices_or_numbers():
    m = slab()
    with pytest.raises(SceneError, match='mesh "Lens": has triangle indices outside 0..7'):
        render_passes(parse_scene(design([{"object": "Lens", "role": "lens"}])),
                      {"Lens": MeshData("Lens", m.vertices, m.triangles + 1)})
    v = m.vertices.copy()
    v[0, 0] = np.nan
    with pytest.raises(SceneError, match='mesh "Lens": has vertices that are not finite'):
        render_passes(parse_scene(design([{"object": "Lens", "role": "lens"}])),
                      {"Lens": MeshData("Lens", v, m.triangles)})


def glb_with_json(text: bytes) -> bytes:
    """A GLB container with a correct header holding ``text`` as its JSON chunk."""
    text += b" " * (-len(text) % 4)
    return struct.pack("<4sIIII", b"glTF", 2, 20 + len(text), len(text), 0x4E4F534A) + text


def write_pair(folder, glb: bytes | None) -> str:
    path = folder / "design.json"
    path.write_text(json.dumps(design([{"object": "Lens", "role": "lens"}])))
    if glb is not None:
        (folder / "lamp.glb").write_bytes(glb)
    return str(path)


def good_glb(folder) -> bytes:
    write_glb(folder / "good.glb", [slab()])
    return (folder / "good.glb").read_bytes()


@pytest.mark.parametrize("case,needles", [
    ("missing", ('freeform.mesh_file: "lamp.glb" is missing',)),
    ("not-gltf", ("is not a glTF binary",)),
    ("garbage", ("is glTF binary version 50462976; allowed version 2",)),
    ("truncated", ("says it is", "bytes but is 300: the file is cut or corrupt")),
    ("bad-json", ("is not a readable glTF binary",)),
    ("accessor-out", ("an accessor reaches outside the file's data",)),
    ("draco", ("needs KHR_draco_mesh_compression", "export without Draco compression")),
])
def test_missing_or_corrupt_glb(tmp_path, case, needles):
    data = {"missing": None, "not-gltf": b"PK\x03\x04 a zip file", "garbage": b"glTF" + bytes(range(256)) * 4,
            "truncated": good_glb(tmp_path)[:300], "bad-json": glb_with_json(b'{"asset": [nope'),
            "accessor-out": glb_with_json(json.dumps({
                "asset": {"version": "2.0"}, "nodes": [{"name": "Lens", "mesh": 0}],
                "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
                "accessors": [{"bufferView": 0, "componentType": 5126, "count": 10**9, "type": "VEC3"}],
                "bufferViews": [{"buffer": 0, "byteLength": 36}], "buffers": [{"byteLength": 36}]}).encode()),
            "draco": glb_with_json(json.dumps({"asset": {"version": "2.0"}, "extensionsUsed": [
                "KHR_draco_mesh_compression"], "extensionsRequired": ["KHR_draco_mesh_compression"]}).encode())}[case]
    path = write_pair(tmp_path, data)
    with pytest.raises(SceneError) as err:
        load(path)
    text = one_line(err.value)
    assert "design.json" in text or "lamp.glb" in text
    for needle in needles:
        assert needle in text
    proc = run_cli("render", path, "-o", tmp_path / "out.exr")
    assert proc.returncode == 2 and len(proc.stderr.strip().splitlines()) == 1 and "Traceback" not in proc.stderr


def test_cli_names_a_bad_lens_in_one_line(tmp_path):
    m = slab()
    write_glb(tmp_path / "lamp.glb", [MeshData("Lens", m.vertices, m.triangles[:, ::-1].copy())])
    path = write_pair(tmp_path, None)
    proc = run_cli("render", path, "-o", tmp_path / "out.exr")
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.count("\n") == 1 and 'mesh "Lens": has its normals pointing inward' in proc.stderr
    assert not (tmp_path / "out.exr").exists()


def test_without_embreex_the_feature_says_so_and_the_rest_works():
    code = """
import sys
sys.modules["embreex"] = None  # as if no wheel existed for this platform
import numpy as np
import core_tracer.freeform as ff
from core_tracer import render, load_scene
from core_tracer.scene.reading import SceneError
ok, reason = ff.available()
print(ok, reason)
scene = load_scene("presets/paper-baseline.json")
print(render(scene, 8, 8).shape)
doc = {"schema": "lamp-scene/2", "lamps": [{}], "freeform": {"mesh_file": "a.glb",
       "parts": [{"object": "A", "role": "body"}]}}
from core_tracer.scene.validate import parse_scene
try:
    from core_tracer.freeform.shapes import box
    ff.render_passes(parse_scene(doc), {"A": box("A", (0, 0, 0), (1, 1, 1))})
except SceneError as e:
    print("error:", e)
"""
    proc = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    assert lines[0].startswith("False free-form rendering needs the embreex package")
    assert lines[1] == "(8, 8, 3)"
    assert lines[2].startswith("error: freeform: free-form rendering needs the embreex package")

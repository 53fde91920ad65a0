"""The .glb + JSON pair: reading glTF into model millimetres, ``load``, the CLI render, and the
lamp-scene/1 → /2 migration."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from glb_writer import write_glb
from helpers import PARAMETRIC_PRESETS, PRESETS, run_cli

from core_tracer.freeform import load, render_passes, shapes
from core_tracer.freeform.gltf import read_glb
from core_tracer.images.imageio import read_image
from core_tracer.library.presets import builtin_library, digest
from core_tracer.library.shipping import check_shipped_thumbnails
from core_tracer.scene import spec as S
from core_tracer.scene.reading import SceneError, read_json, scene_to_json
from core_tracer.scene.validate import load_scene, parse_scene


def lamp_meshes():
    f, R, rim = 18.0, 45.0, 4.0
    vy = rim + R * R / (4 * f)
    return [shapes.box("Lens", (-50, 0, -50), (50, 3, 50)), shapes.paraboloid_dish("Reflector", f, R, vy, 24, 48),
            shapes.uv_sphere("Bulb", (0, vy - f, 0), 8, 24), shapes.cylinder("Socket", (0, 0), 5, vy - f, vy + 1),
            shapes.box("Body", (-110, 0, -60), (-50, 80, 60))]


DESIGN = {"schema": "lamp-scene/2", "name": "Mesh lamp", "lamps": [{}], "image": {"width": 48, "height": 32},
          "freeform": {"mesh_file": "lamp.glb", "parts": [
              {"object": "Lens", "role": "lens", "lens": {"transmitted_color": [0.9, 0.05, 0.05]}},
              {"object": "Reflector", "role": "reflector"}, {"object": "Bulb", "role": "bulb"},
              {"object": "Socket", "role": "socket"}, {"object": "Body", "role": "body"}]}}


def write_design(folder, design=DESIGN, meshes=None, **transform) -> str:
    write_glb(folder / design["freeform"]["mesh_file"], meshes or lamp_meshes(), **transform)
    path = folder / "design.json"
    path.write_text(json.dumps(design))
    return str(path)


def test_glb_round_trip_gives_model_millimetres_and_normals(tmp_path):
    original = {m.name: m for m in lamp_meshes()}
    # A node rotated 30° about glTF's Y (the model's z) and moved: the reader applies it.
    q = (0.0, math.sin(math.pi / 12), 0.0, math.cos(math.pi / 12))
    write_glb(tmp_path / "m.glb", list(original.values()), translation=[0.01, 0.02, -0.03], rotation=q,
              scale=[1.0, 1.0, 1.0])
    meshes = read_glb(tmp_path / "m.glb")
    assert set(meshes) == set(original)
    for name, mesh in meshes.items():
        src = original[name]
        expected = src.vertices[src.triangles].reshape(-1, 3)  # the writer splits vertices per corner
        np.testing.assert_allclose(mesh.vertices, expected, atol=1e-3)  # float32 metres: µm
        if src.corner_normals is None:
            continue
        np.testing.assert_allclose(mesh.corner_normals, src.corner_normals, atol=1e-5)


def test_glb_axes_are_blenders_export_convention(tmp_path):
    # A glTF point (x, y, z) m is the model's (1000 x, -1000 z, 1000 y) mm.
    tri = shapes.box("B", (0, 0, 0), (1, 1, 1))
    write_glb(tmp_path / "b.glb", [tri])
    from core_tracer.freeform.gltf import GLTF_TO_MODEL
    np.testing.assert_allclose(GLTF_TO_MODEL @ [0.001, 0.002, 0.003], [1.0, -3.0, 2.0])
    assert abs(np.linalg.det(GLTF_TO_MODEL / 1000.0) - 1.0) < 1e-12  # a rotation: windings keep


def test_load_renders_the_same_as_the_meshes_in_memory(tmp_path):
    path = write_design(tmp_path)
    scene, meshes = load(path)
    assert scene["freeform"]["parts"][1]["reflector"]["reflectance"] == 0.8  # the parametric default
    from_file = render_passes(scene, meshes).image
    direct = render_passes(parse_scene(DESIGN), {m.name: m for m in lamp_meshes()}).image
    # The file holds float32 metres: the geometry differs by µm, so pixels agree but not bit for bit.
    assert np.abs(from_file - direct).max() < 1e-3 * max(1.0, float(direct.max()))
    assert from_file.max() > 0.1  # the lamp is seen


@pytest.mark.slow
def test_cli_renders_the_pair_as_the_api(tmp_path):
    path = write_design(tmp_path)
    out = tmp_path / "out.exr"
    proc = run_cli("render", path, "-o", out)
    assert proc.returncode == 0, proc.stderr
    image, stored = read_image(str(out))
    assert stored["freeform"] == parse_scene(DESIGN)["freeform"]  # the EXR header holds the design
    scene, meshes = load(path)
    np.testing.assert_array_equal(image, render_passes(scene, meshes).image)


@pytest.mark.slow
def test_lamp_scene_1_presets_load_as_2_and_keep_their_thumbnails():
    old = [path for path in PARAMETRIC_PRESETS if read_json(path)["schema"] == "lamp-scene/1"]
    assert len(old) >= 21  # the paper-mode presets written before /2; the photometric ones are /2 from the start
    for path in old:
        raw = read_json(path)  # the files are not rewritten
        scene = load_scene(path)
        assert scene["schema"] == S.SCHEMA == "lamp-scene/2"
        assert "freeform" not in scene
        # The same design as the /1 document read as /2 directly.
        assert scene == parse_scene({**raw, "schema": "lamp-scene/2"})
    assert check_shipped_thumbnails(builtin_library()).ok


def test_migrated_design_hashes_as_its_lamp_scene_1_document():
    raw = read_json(PRESETS / "paper-baseline.json")
    assert digest(parse_scene(raw)) == digest(parse_scene({**raw, "schema": "lamp-scene/2"}))
    with_freeform = parse_scene(DESIGN)
    assert digest(with_freeform) != digest({k: v for k, v in with_freeform.items() if k != "freeform"})


def test_freeform_document_round_trips():
    scene = parse_scene(DESIGN)
    again = parse_scene(json.loads(scene_to_json(scene)))
    assert again == scene
    assert again["freeform"]["parts"][0]["lens"]["transmitted_color"] == [0.9, 0.05, 0.05]


def test_freeform_is_not_part_of_lamp_scene_1():
    doc = {**DESIGN, "schema": "lamp-scene/1"}
    with pytest.raises(SceneError, match="freeform: unknown key"):
        parse_scene(doc)


@pytest.mark.slow
def test_cli_validates_the_pair(tmp_path):
    path = write_design(tmp_path)
    proc = run_cli("validate", path)
    assert proc.returncode == 0, proc.stderr
    triangles = sum(len(m.triangles) for m in lamp_meshes())
    assert f'valid lamp-scene/2, "Mesh lamp", 5 free-form parts ({triangles} triangles)' in proc.stdout


@pytest.mark.slow
def test_a_free_form_preset_is_listed_and_gets_its_thumbnail(tmp_path):
    from core_tracer.library.presets import Library, list_library, make_thumbnail

    folder = tmp_path / "team"
    folder.mkdir()
    write_design(folder)
    entries, warnings = list_library(Library("Team", str(folder), writable=True))
    assert not warnings and [e.name for e in entries] == ["Mesh lamp"]
    png = make_thumbnail(entries[0], tmp_path / "thumb.png", 24)
    image, _ = read_image(png)
    assert image.shape == (24, 24, 3) and image.max() > 0.05  # the lamp is seen
    (folder / "lamp.glb").unlink()
    entries, warnings = list_library(Library("Team", str(folder), writable=True))
    assert not entries and 'freeform.mesh_file: "lamp.glb" is missing' in str(warnings[0])

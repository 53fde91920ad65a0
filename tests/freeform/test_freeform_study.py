"""Studies of a free-form design (issue 32 item 1): what a study may vary (the parts' values under
their roles and the scene's fields, never the meshes nor the parametric lamps a free-form design does
not trace); each variant rendered on the design's meshes in this process, in the local pool and on a
real local Dask cluster whose workers are sent the .glb's bytes by their SHA-256."""

from __future__ import annotations

import copy
import shutil

import numpy as np
import pytest
from helpers import run_cli
from test_freeform_files import DESIGN, lamp_meshes, write_design

from core_tracer.cli.study import _with_curves
from core_tracer.cluster import engine
from core_tracer.cluster.cells import MESH_FILE, Inputs, make_cell
from core_tracer.freeform import render_passes
from core_tracer.freeform.gltf import read_glb
from core_tracer.images import glare
from core_tracer.images.imageio import read_image, write_image
from core_tracer.optimise import search, spec, storage
from core_tracer.optimise import trials as T
from core_tracer.scene.reading import SceneError
from core_tracer.scene.validate import parse_scene
from core_tracer.study import definition as st
from core_tracer.study import on_cluster as dask_study
from core_tracer.study import run as study_run
from core_tracer.study.parameters import study_parameters

SIZE = (24, 20)
RED, BLUE = [0.9, 0.05, 0.05], [0.05, 0.1, 0.9]
COLOURS = {"parameter": "freeform.parts[].lens.transmitted_color", "values": [RED, BLUE]}


def lens_study(size=SIZE) -> st.Study:
    return st.Study.build(DESIGN, [COLOURS], size)


def refused(parameter: str, base: dict = DESIGN) -> str:
    with pytest.raises(SceneError) as err:
        st.Study.build(base, [{"parameter": parameter, "values": [1.4, 1.5]}], SIZE)
    return str(err.value)


def test_a_study_varies_a_free_form_parts_values_and_not_its_meshes_nor_the_lamps_it_does_not_trace():
    study = lens_study()
    assert [v.scene["freeform"]["parts"][0]["lens"]["transmitted_color"] for v in study.variants] == [RED, BLUE]
    assert study.variants[1].scene["freeform"]["parts"][1:] == study.base["freeform"]["parts"][1:]
    names = study_parameters()
    assert "freeform.parts[].lens.filter" in names and "freeform.parts[].bulb.flux_lm" in names
    assert not any(p.endswith((".object", ".role", "mesh_file")) for p in study_parameters())
    assert refused("lens.ior").startswith("lens.ior: is a field of the parametric lamps, which a free-form design")
    assert refused("lamps[0].lens.ior").startswith("lamps[0].lens.ior: is a field of the parametric lamps")
    assert refused("freeform.parts[1].lens.ior").startswith("freeform.parts[1].lens.ior: part 1 is a reflector")
    assert "part index 7 does not exist" in refused("freeform.parts[7].lens.ior")
    assert "is not a value of a free-form part" in refused("freeform.parts[0].object")
    no_side_wall = refused("freeform.parts[].side_wall.color")
    assert "the base design has no side_wall part" in no_side_wall
    from helpers import baseline_doc

    assert "the base design has no freeform section" in refused("freeform.parts[].lens.ior", baseline_doc())
    one = st.Study.build(DESIGN, [{"parameter": "freeform.parts[0].lens.ior", "values": [1.4, 1.6]},
                                  {"parameter": "camera.fov_deg", "values": [20.0, 30.0]}], SIZE)
    assert len(one) == 4
    with pytest.raises(SceneError, match="sets what freeform.parts"):  # the same field by two names
        st.Study.build(DESIGN, [{"parameter": "freeform.parts[0].lens.ior", "values": [1.4, 1.6]},
                                {"parameter": "freeform.parts[].lens.ior", "values": [1.5, 1.55]}], SIZE)


def direct(folder, study: st.Study) -> list[np.ndarray]:
    """Each variant rendered on the meshes read here, as the free-form tracer's own API renders it."""
    meshes = read_glb(folder / "lamp.glb")
    return [glare.apply(render_passes(v.scene, meshes, *study.size, threads=1).image, v.scene)
            for v in study.variants]


@pytest.mark.slow
def test_a_free_form_study_renders_each_variant_on_its_meshes_here_and_in_the_local_pool(tmp_path):
    document = write_design(tmp_path)
    study = lens_study()
    runnable = _with_curves(study, document)  # as the command line: the .glb by its full path beside the file
    assert all(v.scene["freeform"]["mesh_file"] == str(tmp_path / "lamp.glb") for v in runnable.variants)
    expected = direct(tmp_path, study)
    here = study_run.run_study(runnable, 0)
    pool = study_run.run_study(runnable, 1)
    for a, b, c in zip(expected, here, pool, strict=True):
        np.testing.assert_array_equal(a, b)
        np.testing.assert_array_equal(a, c)
    red, blue = (image.reshape(-1, 3).sum(axis=0) for image in here)
    assert red[0] / red[2] > 2 * blue[0] / blue[2]  # the lens colour varied reaches the image


@pytest.mark.slow
def test_the_study_command_writes_a_free_form_designs_sheet(tmp_path):
    document = write_design(tmp_path)
    sheet = tmp_path / "sheet.png"
    done = run_cli("study", document, "--vary", "freeform.parts[].lens.transmitted_color=0.9/0.05/0.05,0.05/0.1/0.9",
                   "--size", "24x20", "--engine", "processes", "--workers", "1", "-o", sheet,
                   "--save-variants", tmp_path / "variants")
    assert done.returncode == 0, done.stderr
    image, _ = read_image(sheet)
    assert image.shape[2] >= 3 and image.max() > 0
    # A kept variant is a free-form design with its meshes beside it: it renders as the cell showed it.
    assert sorted(p.name for p in (tmp_path / "variants").iterdir()) == ["lamp.glb", "variant-00.json",
                                                                          "variant-01.json"]
    done = run_cli("render", tmp_path / "variants" / "variant-01.json", "-o", tmp_path / "blue.exr")
    assert done.returncode == 0, done.stderr
    blue, _ = read_image(tmp_path / "blue.exr")
    expected = direct(tmp_path, lens_study())[1]
    assert blue.shape == expected.shape and np.abs(blue - expected).max() < 1e-3 * max(expected.max(), 1e-6)
    done = run_cli("study", document, "--vary", "lens.ior=1.4,1.5", "--size", "24x20", "-o", sheet)
    assert done.returncode != 0 and "is a field of the parametric lamps" in done.stderr
    assert "Traceback" not in done.stderr


@pytest.fixture(scope="module")
def client():
    with engine.connect(workers=2, memory_limit=engine.worker_memory([])) as c:
        yield c


@pytest.mark.slow
def test_the_mesh_file_travels_with_the_cells_to_workers_that_cannot_see_the_design(client, tmp_path):
    """The cells carry the .glb's bytes named by their SHA-256: the study renders on a local cluster
    after the design's folder is renamed, as in this process before; the key is the file's content."""
    folder = tmp_path / "design"
    folder.mkdir()
    study = lens_study()
    runnable = _with_curves(study, write_design(folder))
    here = study_run.run_study(runnable, 0)
    cells, inputs = dask_study.study_cells(runnable)
    assert all([keys for keys, _digest, _data in c.curves] == [MESH_FILE] for c in cells)
    moved = tmp_path / "elsewhere"
    shutil.move(folder, moved)  # neither this process nor a worker sees the design's folder now
    images, count = engine.run_cells(client, cells, inputs, None)
    assert count.rendered == 2
    for a, b in zip(here, images, strict=True):
        np.testing.assert_array_equal(a, b)
    # The same bytes in another folder are the same cell; other meshes, another cell.
    again = _with_curves(study, moved / "design.json").variants[0].scene
    assert make_cell(again, *SIZE, Inputs()).key == cells[0].key
    other = tmp_path / "other"
    other.mkdir()
    meshes = lamp_meshes()
    write_design(other, meshes=meshes, translation=[0.0, 0.001, 0.0])
    changed = _with_curves(study, other / "design.json").variants[0].scene
    assert make_cell(changed, *SIZE, Inputs()).key != cells[0].key
    assert make_cell(copy.deepcopy(again), SIZE[0] + 2, SIZE[1], Inputs()).key != cells[0].key


# ---------------------------------------------------------------------------------------------
# Optimisation


def optimisation(folder, trials: int = 4) -> spec.Optimisation:
    """The lens's red (``transmitted_color[0]``) for the look of a reference rendered at 0.9 (SSIM)."""
    document = write_design(folder)
    reference = copy.deepcopy(DESIGN)
    reference["image"] = {"width": SIZE[0], "height": SIZE[1]}
    scene = parse_scene(reference)
    meshes = read_glb(folder / "lamp.glb")
    write_image(folder / "ref.exr", glare.apply(render_passes(scene, meshes, *SIZE).image, scene))
    doc = {"schema": spec.SCHEMA, "base": "design.json",
           "parameters": [{"parameter": "freeform.parts[0].lens.transmitted_color[0]", "range": [0.1, 0.95]}],
           "objectives": [{"measure": "ssim", "goal": "maximise", "reference": "ref.exr"}],
           "size": list(SIZE), "trials": trials, "seed": 3, "storage": "sqlite:///opt.db"}
    assert document == str(folder / "design.json")
    return spec.from_doc(doc, str(folder))


@pytest.mark.slow
def test_an_optimisation_varies_a_free_form_parts_values_here_and_on_a_local_cluster(client, tmp_path):
    opt = optimisation(tmp_path)
    outcome = search.run(opt, None, None)
    done = storage.finished_trials(outcome.study)
    assert outcome.rendered == 4 and len(done) == 4
    reds = [t.user_attrs["design"]["freeform.parts[0].lens.transmitted_color[0]"] for t in done]
    assert len(set(reds)) == 4
    # Each trial's score is its design's render on the meshes: the task is the render.
    best = storage.best(opt, outcome.study)[0]
    scene = opt.traced(opt.scene_of(best.user_attrs["design"]))
    image, mask = T.render_trial(make_cell(scene, *SIZE, Inputs()))
    assert search.measure(opt, scene, image, mask)[0] == pytest.approx(best.values, abs=0)
    assert best.values[0] > min(t.values[0] for t in done)  # the red varied reaches the image
    # Two more trials as tasks on the cluster, their .glb sent with them.
    more = search.run(spec.Optimisation(**{**opt.__dict__, "trials": 6}), client, None, parallel=2)
    assert more.rendered == 2 and len(storage.finished_trials(more.study)) == 6


@pytest.mark.slow
def test_an_optimisation_of_a_free_form_design_refuses_the_parametric_lamps_measures(tmp_path):
    opt = optimisation(tmp_path)
    doc = {**opt.doc, "objectives": [{"measure": "lens_thickness", "goal": "minimise"}]}
    with pytest.raises(SceneError) as err:
        spec.from_doc(doc, str(tmp_path))
    assert str(err.value).startswith("objectives[0].measure: lens_thickness is measured on the parametric lamps")
    doc = {**opt.doc, "parameters": [{"parameter": "lens.ior", "range": [1.4, 1.6]}]}
    with pytest.raises(SceneError, match=r"^parameters\[0\].parameter: lens.ior: is a field of the parametric"):
        spec.from_doc(doc, str(tmp_path))

"""Studies on Dask: cells and their keys, a real local cluster (2 workers x 1 thread) against the
in-process study, the cache (re-run, extension), a worker killed mid-study, cancel."""

from __future__ import annotations

import copy
import os
import signal
import time

import numpy as np
import pytest
from helpers import baseline_doc

from core_tracer.cluster import engine
from core_tracer.cluster.cache import CellCache
from core_tracer.cluster.cells import Cell, Inputs, make_cell, render_cell
from core_tracer.study import definition as st
from core_tracer.study import on_cluster as dask_study
from core_tracer.study import run as study_run

SIZE = (24, 24)


def three_by_three(size=SIZE, heights=(0.5, 1.0, 2.0)) -> st.Study:
    return st.Study.build(baseline_doc(), [{"parameter": "lens.ior", "values": [1.45, 1.52, 1.6]},
                                           {"parameter": "cuts.height", "values": list(heights)}], size)


@pytest.fixture(scope="module")
def client():
    with engine.connect(workers=2, memory_limit=engine.worker_memory([])) as c:
        yield c


def test_a_cell_key_is_its_content_not_its_names(tmp_path):
    scene = three_by_three().variants[0].scene
    key = Cell(scene, 24, 24).key
    assert Cell(copy.deepcopy(scene), 24, 24).key == key
    assert Cell(scene, 24, 32).key != key
    other = copy.deepcopy(scene)
    other["lamps"][0]["lens"]["ior"] = 1.5
    assert Cell(other, 24, 24).key != key
    # The same image bytes under two file names are one input and give one key; other bytes another.
    inputs = Inputs()
    a, b, c = tmp_path / "a.hdr", tmp_path / "b.hdr", tmp_path / "c.hdr"
    a.write_bytes(b"#?RADIANCE one")
    b.write_bytes(b"#?RADIANCE one")
    c.write_bytes(b"#?RADIANCE two")
    cells = []
    for path in (a, b, c):
        s = copy.deepcopy(scene)
        s["environment"] = {**s["environment"], "world": "file", "file": str(path)}
        cells.append(make_cell(s, 24, 24, inputs))
    assert cells[0].key == cells[1].key != cells[2].key
    assert len(inputs.data) == 2


@pytest.mark.slow
def test_a_local_cluster_renders_a_3x3_study_bit_for_bit_as_this_process(client, tmp_path):
    study = three_by_three()
    here = study_run.run_study(study, 0)
    images, count = engine.run_cells(client, *dask_study.study_cells(study), CellCache(tmp_path))
    assert (count.rendered, count.from_cache) == (9, 0)
    assert all(np.array_equal(a, b) for a, b in zip(here, images, strict=True))
    workers = client.scheduler_info()["workers"].values()
    assert len(workers) == 2 and {w["memory_limit"] for w in workers} == {engine.worker_memory([])}
    assert {w["nthreads"] for w in workers} == {1}


@pytest.mark.slow
def test_a_rerun_renders_nothing_and_an_extension_only_its_new_cells(client, tmp_path):
    cache = CellCache(tmp_path)
    first = three_by_three(heights=(0.5, 1.0))
    _, count = engine.run_cells(client, *dask_study.study_cells(first), cache)
    assert (count.rendered, count.from_cache) == (6, 0)
    again, count = engine.run_cells(client, *dask_study.study_cells(first), cache)
    assert (count.rendered, count.from_cache) == (0, 6)
    extended = three_by_three(heights=(0.5, 1.0, 2.0))  # one more value of axis 2: one more row
    images, count = engine.run_cells(client, *dask_study.study_cells(extended), cache)
    assert (count.rendered, count.from_cache) == (3, 6)
    here = study_run.run_study(extended, 0)
    assert all(np.array_equal(a, b) for a, b in zip(here, images, strict=True))
    # A damaged cache file is rendered again, not trusted.
    key = dask_study.study_cells(extended)[0][0].key
    with open(cache.path(key), "r+b") as f:
        f.truncate(40)
    images, count = engine.run_cells(client, *dask_study.study_cells(extended), cache)
    assert (count.rendered, count.from_cache) == (1, 8)
    assert np.array_equal(images[0], here[0])


@pytest.mark.slow
def test_the_environment_image_travels_with_the_task(client, tmp_path, monkeypatch):
    doc = baseline_doc()
    doc["environment"] = {"world": "night", "strength": 1.0}
    study = st.Study.build(doc, [{"parameter": "lens.ior", "values": [1.45, 1.6]}], (20, 20))
    cells, inputs = dask_study.study_cells(study)
    assert cells[0].environment is not None and len(inputs.data) == 1
    here = study_run.run_study(study, 0)
    images, count = engine.run_cells(client, cells, inputs, None)
    assert count.rendered == 2
    assert all(np.array_equal(a, b) for a, b in zip(here, images, strict=True))
    # The task does not render a scene whose image it was not given.
    with pytest.raises(ValueError, match="not sent"):
        render_cell(cells[0], None)


@pytest.mark.slow
def test_a_worker_killed_mid_study_loses_nothing(tmp_path):
    """SIGKILL one worker process of a real local cluster while it renders: the scheduler runs its
    tasks again on the restarted worker and the images equal a run without the fault, bit for bit."""
    doc = baseline_doc()
    doc["image"] = {"samples": 4}
    study = st.Study.build(doc, [{"parameter": "lens.ior", "values": [1.45, 1.5, 1.55, 1.6]},
                                 {"parameter": "cuts.height", "values": [0.5, 2.0]}], (96, 96))
    here = study_run.run_study(study, 0)
    killed: list[int] = []
    with engine.connect(workers=2, memory_limit=engine.worker_memory([])) as client:
        pids = client.run(os.getpid)

        def progress(done: int, total: int) -> None:
            if killed or done == total:
                return
            busy = [a for a, tasks in client.processing().items() if tasks]
            if busy:
                killed.append(pids[busy[0]])
                os.kill(pids[busy[0]], signal.SIGKILL)

        start = time.monotonic()
        images, count = engine.run_cells(client, *dask_study.study_cells(study), CellCache(tmp_path),
                                         progress=progress)
        seconds = time.monotonic() - start
        after = set(client.run(os.getpid).values())

        def lost(dask_scheduler) -> int:  # renders the scheduler took back from the dead worker
            return sum(1 for entry in dask_scheduler.transition_log
                       if entry[0].startswith("lamp-cell-") and entry[1] == "processing"
                       and entry[2] in ("released", "waiting"))

        taken_back = client.run_on_scheduler(lost)
    assert killed and killed[0] not in after  # a worker was killed while it rendered, and replaced
    assert taken_back >= 1  # and its render ran again
    assert count.rendered == len(study) == 8
    assert all(np.array_equal(a, b) for a, b in zip(here, images, strict=True))
    print(f"fault run: {seconds:.1f} s, killed pid {killed[0]}, {taken_back} render(s) run again")


@pytest.mark.slow
def test_cancel_stops_every_task_and_returns_nothing(client, tmp_path):
    study = three_by_three(size=(64, 64))
    cache = CellCache(tmp_path)
    seen = []

    def should_stop() -> bool:
        return bool(seen)

    def progress(done: int, total: int) -> None:
        if done:
            seen.append(done)

    with pytest.raises(engine.Cancelled):
        engine.run_cells(client, *dask_study.study_cells(study), cache, progress=progress,
                         should_stop=should_stop)
    deadline = time.monotonic() + 10
    while client.processing() and any(client.processing().values()) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not any(client.processing().values())  # nothing left running on the workers
    # what finished before the cancel is kept: a resumed study renders only the rest
    kept = sum(cache.get(c.key) is not None for c in dask_study.study_cells(study)[0])
    assert 1 <= kept < 9


def test_the_scheduler_address_comes_from_the_option_or_dasks_variable(monkeypatch):
    monkeypatch.delenv(engine.SCHEDULER_VARIABLE, raising=False)
    assert engine.scheduler_address(None) is None
    assert engine.scheduler_address("tcp://node:8786") == "tcp://node:8786"
    monkeypatch.setenv(engine.SCHEDULER_VARIABLE, "tcp://studio:8786")
    assert engine.scheduler_address(None) == "tcp://studio:8786"
    assert engine.scheduler_address("local") is None  # "local" forces a local cluster


def test_a_workers_memory_limit_is_the_largest_cells_budget():
    from core_tracer import budget

    small, big = (Cell(three_by_three().variants[0].scene, w, w) for w in (64, 1024))
    assert engine.worker_memory([small, big]) == (budget.render_bytes(1024, 1024, False, "exr") + engine.DASK_BYTES
                                                  + engine.KEPT_FREED_BYTES)
    assert engine.worker_memory([small]) < engine.worker_memory([small, big]) <= budget.MEMORY_BUDGET



@pytest.mark.slow
def test_a_large_cell_is_split_into_runs_of_bands_and_is_the_same_image(client, tmp_path, monkeypatch):
    """A cell above BAND_TASK_RAYS is several tasks, each a run of its bands of rows; the assembled
    image (glare applied to the whole) equals the whole render, bit for bit."""
    from core_tracer.cluster import cells as cells_module

    doc = baseline_doc()
    doc["glare"] = {"on": True}
    study = st.Study.build(doc, [{"parameter": "lens.ior", "values": [1.5]}], (512, 400))  # bands of 128 rows
    cells, inputs = dask_study.study_cells(study)
    monkeypatch.setattr(cells_module, "BAND_TASK_RAYS", 512 * 128)  # a band a task
    groups = cells_module.band_groups(cells[0])
    assert len(groups) >= 3 and [b for g in groups for b in g] == sorted(b for g in groups for b in g)
    images, count = engine.run_cells(client, cells, inputs, CellCache(tmp_path))
    assert count.band_tasks == len(groups) and count.rendered == 1
    whole = render_cell(cells[0])
    assert np.array_equal(images[0], whole)


def test_the_cache_keeps_the_cells_used_last_within_its_size(tmp_path):
    cache = CellCache(tmp_path)
    image = np.zeros((8, 8, 3), np.float32)
    for k in range(5):
        cache.put(f"{k:02d}" * 32, image)
        path = cache.path(f"{k:02d}" * 32)
        os.utime(path, (1000 + k, 1000 + k))  # put in this order, a second apart
    assert cache.get("00" * 32) is not None  # reading the oldest marks it used
    size = os.path.getsize(cache.path("00" * 32))
    assert cache.prune(2 * size) == 3 * size
    kept = [k for k in range(5) if cache.get(f"{k:02d}" * 32) is not None]
    assert kept == [0, 4]


@pytest.mark.slow
def test_the_measured_curves_travel_with_the_task_to_a_worker_that_cannot_see_the_design(client, tmp_path):
    """A photometric study whose lens filter is a measured curve beside its design: the cells carry the
    curve's bytes (named by their SHA-256, not by the folder), so the study renders on the cluster after
    the design's folder is renamed, as it rendered in this process before (issue 32, item 4)."""
    import dataclasses
    import json
    import shutil

    from helpers import PRESETS

    from core_tracer.photometry import materials
    from core_tracer.scene.beside import spectrum_files, with_curves_at

    folder = tmp_path / "design"
    folder.mkdir()
    curve = materials.FILTERS["amber"].spectrum()
    (folder / "amber.csv").write_text("nm,t\n" + "".join(f"{a:g},{b:.8f}\n" for a, b in
                                                          zip(curve.wavelengths_nm, curve.values, strict=True)))
    doc = json.loads((PRESETS / "photometric-stop-lamp.json").read_text())
    doc["lamps"][0]["lens"].update(filter="file", filter_file="amber.csv")
    study = st.Study.build(doc, [{"parameter": "lens.filter_thickness", "values": [2.0, 4.0]}], (20, 20))
    document = folder / "stop.json"

    def traced(scene: dict, beside: object) -> dict:  # as ``study`` on the command line (cli.study._with_curves)
        return with_curves_at(scene, spectrum_files(beside, scene))

    runnable = dataclasses.replace(study, variants=tuple(dataclasses.replace(v, scene=traced(v.scene, document))
                                                         for v in study.variants))
    here = study_run.run_study(runnable, 0)
    cells, inputs = dask_study.study_cells(runnable)
    assert all(len(c.curves) == 1 for c in cells)
    moved = tmp_path / "elsewhere"
    shutil.move(folder, moved)  # neither this process nor a worker sees the design's folder now
    assert not (folder / "amber.csv").exists()
    images, count = engine.run_cells(client, cells, inputs, None)
    assert count.rendered == 2
    assert all(np.array_equal(a, b) for a, b in zip(here, images, strict=True))
    assert not np.array_equal(images[0], images[1])  # the thickness reaches the filter read from the file
    # The cell's key is its content: the same curve from another folder is the same cell.
    shutil.move(moved, folder.parent / "third")
    again = traced(study.variants[0].scene, folder.parent / "third" / "stop.json")
    assert make_cell(again, 20, 20, Inputs()).key == cells[0].key

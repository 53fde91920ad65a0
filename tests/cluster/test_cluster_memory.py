"""A study's variants are sent only to workers whose memory limit holds a variant's render
(core_tracer/budget.py, plus Dask's own share), checked before anything is sent: a real local
cluster whose worker is given too little is refused in one line naming it and both figures."""

from __future__ import annotations

import pytest
from distributed import get_task_stream
from helpers import baseline_doc, small_and_large_worker

from core_tracer import budget
from core_tracer.cluster import engine
from core_tracer.cluster.cells import Inputs, make_cell
from core_tracer.scene.reading import SceneError
from core_tracer.scene.validate import parse_scene


@pytest.mark.slow
def test_a_study_on_workers_too_small_is_refused_before_any_task(tmp_path):
    cells = [make_cell(parse_scene(baseline_doc()), 24, 24, Inputs())]
    need = engine.cell_bytes(cells[0])
    with engine.connect(workers=1, memory_limit=200 * 2**20) as client:
        address = next(iter(client.scheduler_info()["workers"]))
        with pytest.raises(SceneError) as e:
            engine.run_cells(client, cells, Inputs())
        # nothing reached the worker: no task was ever sent
        assert client.run_on_scheduler(lambda dask_scheduler: len(dask_scheduler.tasks)) == 0
    assert e.value.path == "--scheduler" and "\n" not in e.value.message
    assert e.value.message.startswith(f"worker {address} has a memory limit of 200 MB; a variant needs about "
                                      f"{engine.megabytes(need + engine.DASK_BYTES)} there")
    assert need >= budget.BASE_BYTES


@pytest.mark.slow
def test_workers_that_fit_take_every_variant_as_before():
    cells = [make_cell(parse_scene(baseline_doc()), 24, 24, Inputs())]
    with engine.connect(workers=1, memory_limit=engine.worker_memory(cells)) as client:
        assert engine.fitting_workers(client, engine.cell_bytes(cells[0])) is None
        images, count = engine.run_cells(client, cells, Inputs())
    assert count.rendered == 1 and images[0].shape == (24, 24, 3)


@pytest.mark.slow
def test_variants_go_only_to_the_workers_whose_memory_holds_them():
    """One worker too small (200 MB) and one started beside it as a studio starts a node
    (`dask worker --memory-limit 2GiB`): every variant renders on the large one, and the count says so."""
    doc = baseline_doc()
    cells = []
    for height in (0.5, 1.0, 2.0):
        doc["lamps"][0]["cuts"]["height"] = height
        cells.append(make_cell(parse_scene(doc), 24, 24, Inputs()))
    with small_and_large_worker() as (client, small, large):
        with get_task_stream(client) as stream:
            images, count = engine.run_cells(client, cells, Inputs())
        ran_on = {t["worker"] for t in stream.data if str(t["key"]).startswith("lamp-cell-")}
    assert count.workers == [large] and ran_on == {large}, (count.workers, ran_on)
    assert count.rendered == 3 and all(image.shape == (24, 24, 3) for image in images)

"""A design study rendered on Dask: each variant a cell (``cells``), the cache first (``cache``).

``run_study(study, scheduler=...)`` is ``study.run.run_study``'s counterpart: the same images, in
variant order, plus a ``RunCount`` (how many rendered, how many came from the cache). When the
cache holds every variant no cluster is started at all.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ..study.definition import Study
from . import engine
from .cache import CellCache
from .cells import Inputs, make_cell


def study_cells(study: Study) -> tuple[list, Inputs]:
    inputs = Inputs()
    width, height = study.size
    return [make_cell(v.scene, width, height, inputs) for v in study.variants], inputs


def run_study(study: Study, scheduler: str | None = None, workers: int | None = None, *,
              cache: CellCache | None = None, environment: int = 0,
              progress: Callable[[int, int], None] | None = None,
              should_stop: Callable[[], bool] | None = None,
              on_start: Callable[[object], None] | None = None) -> tuple[list[np.ndarray], engine.RunCount]:
    """Every variant's image and the run's count. ``scheduler`` as ``engine.connect`` takes it;
    ``workers`` sizes a local cluster; ``environment`` is the largest world's bytes (for a local
    worker's memory limit); ``on_start(client)`` once the cluster is up."""
    cells, inputs = study_cells(study)
    if cache is not None:
        missing = [c for c in cells if cache.get(c.key) is None]
        if not missing:
            return engine.run_cells(None, cells, inputs, cache, progress=progress, should_stop=should_stop)
    limit = engine.worker_memory(cells, environment)
    with engine.connect(scheduler, workers=min(workers or engine.default_workers(), len(cells)),
                        memory_limit=limit) as client:
        if on_start is not None:
            on_start(client)
        return engine.run_cells(client, cells, inputs, cache, progress=progress, should_stop=should_stop)

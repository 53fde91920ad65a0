"""A design study rendered as cells on Dask or the local worker pool (``local_pool``): each variant
a cell (``cells``), the cache first (``cache``).

``run_study(study, scheduler=...)`` is ``study.run.run_study``'s counterpart: the same images, in
variant order, plus a ``RunCount`` (how many rendered, how many came from the cache). When the
cache holds every variant no cluster is started at all. ``DaskStudyRun`` is the same as a
non-blocking object for Blender's modal operator.
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Callable

import numpy as np

from ..cluster import engine, local_pool
from ..cluster.cache import CellCache
from ..cluster.cells import Inputs, make_cell
from .definition import Study


def study_cells(study: Study) -> tuple[list, Inputs]:
    inputs = Inputs()
    width, height = study.size
    return [make_cell(v.scene, width, height, inputs) for v in study.variants], inputs


def run_study(study: Study, scheduler: str | None = None, workers: int | None = None, *,
              cache: CellCache | None = None, environment: int = 0,
              progress: Callable[[int, int], None] | None = None,
              should_stop: Callable[[], bool] | None = None,
              on_start: Callable[[object], None] | None = None,
              dask: bool = False) -> tuple[list[np.ndarray], engine.RunCount]:
    """Every variant's image and the run's count. ``scheduler`` as ``local_pool.connect`` takes it:
    Dask for a scheduler's address, "local" or ``dask``, else the local worker pool; ``workers``
    sizes a local cluster or pool; ``environment`` is the largest world's bytes (for a local
    worker's memory limit); ``on_start(client)`` once the cluster is up."""
    cells, inputs = study_cells(study)
    if cache is not None:
        missing = [c for c in cells if cache.get(c.key, (c.width, c.height)) is None]
        if not missing:
            return engine.run_cells(None, cells, inputs, cache, progress=progress, should_stop=should_stop)
    limit = engine.worker_memory(cells, environment)
    with local_pool.connect(scheduler, workers=min(workers or engine.default_workers(), len(cells)),
                            memory_limit=limit, dask=dask, should_stop=should_stop) as client:
        if on_start is not None:
            on_start(client)
        return engine.run_cells(client, cells, inputs, cache, progress=progress, should_stop=should_stop)


class DaskStudyRun:
    """A study on Dask as a non-blocking object, with ``study.run.StudyRun``'s interface (``start``,
    ``poll``, ``cancel``, ``close``, ``done``, ``total``, ``fraction``, ``images``): Blender's Study
    panel drives it from a timer when a scheduler address is given."""

    def __init__(self, study: Study, scheduler: str | None = None, workers: int | None = None,
                 cache: CellCache | None = None, environment: int = 0):
        self.study, self.scheduler, self.workers, self.cache = study, scheduler, workers, cache
        self.environment = environment
        self._stack = contextlib.ExitStack()
        self._run: engine.CellRun | None = None
        self.client = None

    @property
    def total(self) -> int:
        return len(self.study)

    @property
    def done(self) -> int:
        return self._run.done if self._run is not None else 0

    @property
    def fraction(self) -> float:
        return self.done / self.total

    @property
    def images(self) -> list:
        return list(self._run.images) if self._run is not None else [None] * self.total

    @property
    def count(self) -> engine.RunCount:
        return self._run.count if self._run is not None else engine.RunCount(cells=self.total)

    def start(self) -> None:
        cells, inputs = study_cells(self.study)
        try:
            if self.cache is not None and all(self.cache.get(c.key, (c.width, c.height)) is not None for c in cells):
                self._run = engine.CellRun(None, cells, inputs, self.cache)
                return
            limit = engine.worker_memory(cells, self.environment)
            self.client = self._stack.enter_context(engine.connect(
                self.scheduler, workers=min(self.workers or engine.default_workers(), len(cells)),
                memory_limit=limit))
            self._run = engine.CellRun(self.client, cells, inputs, self.cache)
            self._run.submit()
        except BaseException:
            self.close()
            raise

    def poll(self, timeout: float = 0.0) -> bool:
        if self._run is None:
            raise RuntimeError("poll() before start()")
        finished = self._run.poll()
        if not finished and timeout > 0:
            time.sleep(min(timeout, engine.POLL))
        return finished

    def cancel(self) -> None:
        if self._run is not None:
            self._run.cancel()
        self.close()

    def close(self) -> None:
        if self._run is not None:
            self._run.release()
        self._stack.close()

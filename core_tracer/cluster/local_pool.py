"""The local worker pool: a study's cells and an optimisation's trials on this machine's cores,
without Dask.

A Dask local cluster starts a scheduler, and a nanny and a worker process per core, each importing
``distributed`` before it takes a task: 5-14 s on a loaded 2-core machine (issue 34), more than a
16-variant study at 128 px takes to render. The pool is a ``concurrent.futures`` process pool whose
workers are forked from this process on Linux, so they start with numpy and the tracer already
imported, in milliseconds (elsewhere, where forking a process that holds threads is unsafe, they
are spawned). Dask stays for a studio's scheduler (``--scheduler tcp://...``, ``$DASK_SCHEDULER_ADDRESS``)
and when asked for by name (``--scheduler local``, a study's ``--engine dask``).

``LocalPool`` answers the part of ``distributed.Client`` that ``engine.CellRun`` and
``optimise.search.run`` use (``submit``, ``scatter``, ``cancel``, ``scheduler_info``, ``close``,
``local``), so both run on either unchanged: the cell cache, band tasks, progress and refusals are
theirs. A task's stop flag (``cells.stop_flag``) is the pool's shared event: ``cancel`` sets it,
so running renders end at their next band, then stops the workers. Workers ignore Ctrl-C and run in
a session of their own, as the project's other worker processes do (``engine``'s preload says why).
"""

from __future__ import annotations

import concurrent.futures
import contextlib
import ctypes
import ctypes.util
import multiprocessing
import os
import signal
import sys
from collections.abc import Callable, Iterator
from dataclasses import dataclass

from .. import budget, processes
from . import engine, pool_worker


def dask_wanted(scheduler: str | None) -> bool:
    """Whether a run goes to Dask: a scheduler's address (given, or ``$DASK_SCHEDULER_ADDRESS``), or
    a local Dask cluster asked for by name ("local")."""
    named = scheduler if scheduler is not None else os.environ.get(engine.SCHEDULER_VARIABLE)
    return named == engine.LOCAL or engine.scheduler_address(scheduler) is not None


@contextlib.contextmanager
def connect(scheduler: str | None = None, workers: int | None = None, memory_limit: int | None = None,
            dask: bool = False, should_stop: Callable[[], bool] | None = None) -> Iterator:
    """``engine.connect`` when Dask is wanted (``dask``, or ``dask_wanted(scheduler)``; ``should_stop``
    ends its wait for a scheduler), else a ``LocalPool`` of ``workers`` processes, which has nothing
    to wait for; closed on leaving."""
    if dask or dask_wanted(scheduler):
        with engine.connect(scheduler, workers=workers, memory_limit=memory_limit, should_stop=should_stop) as client:
            yield client
        return
    pool = LocalPool(workers, memory_limit)
    try:
        yield pool
    finally:
        pool.close()


@dataclass
class PoolInfo:
    """What the pool runs, in the words a Dask cluster's ``engine.Local`` uses."""

    workers: int
    memory_limit: int

    def describe(self, live: bool = True) -> str:
        return (f"local worker pool: {self.workers} worker process{'es' if self.workers != 1 else ''} x 1 thread, "
                f"{budget.gib(self.memory_limit)} each")


class Scattered:
    """Data sent with every task that names it (a local pool has no store to keep it in)."""

    def __init__(self, data) -> None:
        self.data = data

    def release(self) -> None:
        self.data = None


class PoolFuture:
    """A task's ``concurrent.futures.Future`` as Dask's ``Future`` reads (``status``, ``release``)."""

    def __init__(self, future: concurrent.futures.Future) -> None:
        self.future = future

    def done(self) -> bool:
        return self.future.done()

    @property
    def status(self) -> str:
        if not self.future.done():
            return "pending"
        if self.future.cancelled():
            return "cancelled"
        return "error" if self.future.exception() is not None else "finished"

    def result(self, timeout: float | None = None):
        return self.future.result(timeout)

    def exception(self, timeout: float | None = None):
        return self.future.exception(timeout)

    def release(self) -> None:
        pass


class LocalPool:
    """``workers`` processes (default one per core) with one thread each, started at once."""

    def __init__(self, workers: int | None = None, memory_limit: int | None = None) -> None:
        count = workers or engine.default_workers()
        self.local = PoolInfo(count, memory_limit or budget.MEMORY_BUDGET)
        context = multiprocessing.get_context("fork" if sys.platform.startswith("linux") else "spawn")
        self.stop = context.Event()
        self.executor = concurrent.futures.ProcessPoolExecutor(count, mp_context=context, initializer=_start_worker,
                                                               initargs=(self.stop, os.getpid()))
        self.cancelled = False

    def submit(self, function: Callable, *args, key: str | None = None, pure: bool = False, workers=None,
               allow_other_workers: bool = False) -> PoolFuture:
        """``function(*args)`` in a worker (a ``Scattered`` argument as its data). Dask's placement
        arguments are accepted and mean nothing here: every worker is this machine's."""
        args = tuple(a.data if isinstance(a, Scattered) else a for a in args)
        return PoolFuture(self.executor.submit(function, *args))

    def scatter(self, data, hash: bool = False) -> Scattered:  # noqa: A002 (Dask's keyword)
        return Scattered(data)

    def scheduler_info(self) -> dict:
        """No worker listed: ``engine.fitting_workers`` sends tasks anywhere (the run's memory was
        checked against this machine's budget before it started)."""
        return {"workers": {}}

    def cancel(self, futures, force: bool = True) -> None:
        """Stop every task: running renders at their next band, the queued ones at once; then the
        workers themselves (a task that does not poll the flag, a light tracing, would run on)."""
        self.cancelled = True
        self.stop.set()
        for f in futures:
            f.future.cancel()
        self._stop_workers()

    def close(self) -> None:
        if self.cancelled:
            self._stop_workers()
        self.executor.shutdown(wait=True, cancel_futures=True)

    def _stop_workers(self) -> None:
        # The executor has no public way to end its workers before Python 3.14 (terminate_workers);
        # its process table is the only handle on them.
        for process in list(getattr(self.executor, "_processes", {}).values()):
            with contextlib.suppress(Exception):
                process.terminate()
        for process in list(getattr(self.executor, "_processes", {}).values()):
            with contextlib.suppress(Exception):
                process.join(timeout=5)

    def __enter__(self) -> LocalPool:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


# glibc's mallopt parameters (malloc.h), set to processes._KEEP_FREED_MEMORY's values: a forked
# worker's allocator was set up by its parent, so the environment variables would come too late.
M_TRIM_THRESHOLD, M_MMAP_THRESHOLD = -1, -3
PR_SET_PDEATHSIG = 1  # prctl option (linux/prctl.h)


def _start_worker(stop, parent: int) -> None:
    """A pool worker's set-up: the stop event; Ctrl-C ignored and a session of its own (the command
    stops its workers itself); SIGTERM ends it (the parent's handler came with the fork), and so
    does its parent's death; freed memory kept mapped; numpy's own threads at one, the workers
    being the parallelism."""
    pool_worker.stop = stop
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    if hasattr(os, "setsid"):
        with contextlib.suppress(OSError):
            os.setsid()
    os.environ.update(processes._SINGLE_THREAD)
    if sys.platform.startswith("linux"):
        with contextlib.suppress(OSError, AttributeError):
            libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
            # A forked worker holds both ends of its task queue, so it would wait on it for ever if
            # the command were killed (SIGKILL: no cleanup runs): the kernel ends it with its parent.
            libc.prctl(PR_SET_PDEATHSIG, signal.SIGKILL)
            if os.getppid() != parent:  # the parent died before the line above
                os._exit(1)
            keep = processes._KEEP_FREED_MEMORY
            libc.mallopt(M_MMAP_THRESHOLD, int(keep["MALLOC_MMAP_THRESHOLD_"]))
            libc.mallopt(M_TRIM_THRESHOLD, int(keep["MALLOC_TRIM_THRESHOLD_"]))

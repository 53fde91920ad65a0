"""The Dask client that runs cells: on a scheduler's cluster, or on a local cluster by default.

``connect(scheduler)`` gives a ``distributed.Client``: to ``scheduler`` (``tcp://host:8786``), else to
``$DASK_SCHEDULER_ADDRESS``, else to a ``LocalCluster`` on this machine of ``workers`` processes
(default one per core) with one thread each, each worker's memory limited to what the largest
cell's render is budgeted (``worker_memory``): Dask pauses, then restarts, a worker above it.

``run_cells(client, cells, ...)`` renders the cells the cache does not hold, one Dask task per
distinct key, and returns every image in order with a ``RunCount``. A worker lost mid-task (killed,
out of memory, its machine gone) is replaced and its tasks run again elsewhere by the scheduler;
the images are the same bit for bit, since a render depends only on its cell. Cancelling sets the
run's stop event, which running renders poll between bands, and cancels every task.

Bounds (issue 33): an address is checked before use (``check_address``); reaching a scheduler takes at
most ``connect_seconds()`` whatever the peer does and ends at once on Ctrl-C or SIGTERM
(``client_within``); a local cluster has at most ``max_workers()`` processes (``check_workers``).
"""

from __future__ import annotations

import contextlib
import importlib.util
import logging
import os
import shutil
import tempfile
import time
import uuid
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass

import numpy as np

from .. import budget, processes
from . import cells as cells_module
from .cache import CellCache
from .cells import Cell, Inputs, assemble, band_groups, render_bands, render_cell

SCHEDULER_VARIABLE = "DASK_SCHEDULER_ADDRESS"  # Dask's own name for it
LOCAL = "local"
CONNECT_TIMEOUT = "20s"
SCRATCH_PREFIX = "lamp-dask-"
LOCAL_WORKER = "LAMP_LOCAL_WORKER"  # set in a local cluster's workers (preload.py reads it)
POLL = 0.05  # seconds between looks at the tasks and at the caller's should_stop
PRELOAD = os.path.join(os.path.dirname(os.path.abspath(__file__)), "preload.py")
# A Dask worker process beyond the render's own figure (budget.BASE_BYTES counts the interpreter,
# numpy and the tracer): distributed, tornado and the task's result held until fetched; a worker
# measured 93 MB RSS idle after a 256 px render with its allocator trimming
# (benchmarks/bench_cluster.py prints it); rounded up.
DASK_BYTES = 192 * 2**20
# What the allocator may keep mapped after a render (its trim threshold, processes._KEEP_FREED_MEMORY):
# counted as budget.WORKER_BYTES counts it for a band worker.
KEPT_FREED_BYTES = int(processes._KEEP_FREED_MEMORY["MALLOC_TRIM_THRESHOLD_"])


class Cancelled(Exception):
    """The run was cancelled: every task is cancelled and nothing is returned."""


class TaskError(RuntimeError):
    """A render task failed on a worker (a tracer bug or a broken worker installation)."""


def available() -> bool:
    """Whether Dask's ``distributed`` is installed here."""
    return importlib.util.find_spec("distributed") is not None


def scheduler_address(given: str | None) -> str | None:
    """The scheduler to use: ``given``, else ``$DASK_SCHEDULER_ADDRESS``; None (or "local") for a
    local cluster. The address is checked before use (``check_address``)."""
    address = given if given is not None else os.environ.get(SCHEDULER_VARIABLE) or None
    if address in (None, "", LOCAL):
        return None
    return check_address(address, "--scheduler" if given is not None else SCHEDULER_VARIABLE)


SCHEMES = ("tcp", "tls")
MAX_ADDRESS = 255


def check_address(address: str, where: str = "--scheduler") -> str:
    """``tcp://HOST:PORT``, ``tls://HOST:PORT`` or ``HOST:PORT`` (a name, IPv4 or [IPv6] host, port 1 to
    65535), as Dask takes it; anything else is a one-line ``SceneError`` naming ``where`` (issue 33:
    14 of 24 malformed forms gave a 40-line traceback from inside Dask)."""
    import ipaddress
    import re
    from urllib.parse import urlsplit

    from ..scene.reading import SceneError
    from ..scene.safe_text import printable

    allowed = "allowed tcp://HOST:PORT (or tls://, or HOST:PORT) with a port from 1 to 65535, or local"
    shown = printable(address, 80)
    if len(address) > MAX_ADDRESS or not address.isprintable() or any(c.isspace() for c in address):
        raise SceneError(where, f"{shown!r} is not a scheduler address; {allowed}")
    text = address if "://" in address else f"tcp://{address}"
    try:
        parts = urlsplit(text)
        host, port = parts.hostname, parts.port
    except ValueError:
        raise SceneError(where, f"{shown!r} is not a scheduler address; {allowed}") from None
    if parts.scheme not in SCHEMES or parts.path not in ("", "/") or parts.query or parts.fragment or \
            parts.username is not None or not host or port is None or not 1 <= port <= 65535:
        raise SceneError(where, f"{shown!r} is not a scheduler address; {allowed}")
    try:
        ipaddress.ip_address(host)
    except ValueError:
        if not re.fullmatch(r"(?=.{1,253}$)[A-Za-z0-9]([A-Za-z0-9-]{0,61}[A-Za-z0-9])?"
                            r"(\.[A-Za-z0-9]([A-Za-z0-9-]{0,61}[A-Za-z0-9])?)*\.?", host):
            raise SceneError(where, f"{shown!r} has a host that is not a name or an IP address; {allowed}") from None
    return f"{parts.scheme}://{parts.netloc}"


def default_workers() -> int:
    return max(1, os.cpu_count() or 1)


def max_workers() -> int:
    """The most worker processes this machine runs for one command: ``WORKERS_PER_CORE`` a core, and
    no more than ``budget.MEMORY_BUDGET`` holds at a band worker's figure (``budget.WORKER_BYTES``)."""
    return max(1, min(WORKERS_PER_CORE * default_workers(), budget.MEMORY_BUDGET // budget.WORKER_BYTES))


WORKERS_PER_CORE = 4


def check_workers(workers: int | None, where: str = "--workers") -> None:
    """``--workers`` from 0 (this process) to ``max_workers()`` (issue 33: 100000 grew memory until killed)."""
    from ..scene.reading import SceneError

    most = max_workers()
    if workers is not None and not 0 <= workers <= most:
        raise SceneError(where, f"{workers} is out of range; allowed 0 (this process) to {most} on this machine "
                                f"({default_workers()} cores, {budget.gib(budget.MEMORY_BUDGET)} of memory)")


def cell_bytes(cell: Cell, environment: int = 0) -> int:
    """The budget of one cell's render (``budget.render_bytes``, no passes, glare as the scene says)."""
    glare = bool((cell.scene.get("glare") or {}).get("on", False))
    return budget.render_bytes(cell.width, cell.height, False, "exr", glare, environment)


def worker_memory(cells: Sequence[Cell], environment: int = 0) -> int:
    """A local worker's memory limit: the largest cell's budget, Dask's own share and the freed memory
    its allocator keeps, at most the project's ``MEMORY_BUDGET``."""
    need = max((cell_bytes(c, environment) for c in cells), default=budget.BASE_BYTES)
    return min(budget.MEMORY_BUDGET, need + DASK_BYTES + KEPT_FREED_BYTES)


def megabytes(n: int) -> str:
    return f"{n / 2**20:.0f} MB"


def fitting_workers(client, need: int, what: str = "a render") -> list[str] | None:
    """Before tasks are sent: the workers whose memory limit (the scheduler's ``memory_limit``; 0 or
    none: unlimited) holds ``what``'s estimated peak, ``need`` bytes (``budget``), plus a Dask
    worker's own share (``DASK_BYTES``). None when every worker fits (tasks go anywhere); the list
    when only some do (tasks are sent to those alone); a one-line ``SceneError`` naming the largest
    worker and both figures when none does. A cluster with no worker yet is left to Dask."""
    from ..scene.reading import SceneError

    workers = client.scheduler_info().get("workers", {})
    want = need + DASK_BYTES
    fit, small = [], []
    for address, info in sorted(workers.items()):
        limit = int(info.get("memory_limit") or 0)
        (fit if limit == 0 or limit >= want else small).append((address, limit))
    if not small:
        return None
    if not fit:
        address, limit = max(small, key=lambda item: item[1])
        others = f" (and {len(small) - 1} smaller)" if len(small) > 1 else ""
        raise SceneError("--scheduler", f"worker {address} has a memory limit of {megabytes(limit)}{others}; {what} "
                                        f"needs about {megabytes(want)} there ({megabytes(need)} for the render, "
                                        f"{megabytes(DASK_BYTES)} for Dask); allowed workers started with "
                                        f"--memory-limit {megabytes(want)} or more")
    return [address for address, _ in fit]


@dataclass
class Local:
    """What a local cluster started: its processes, threads and memory limit per worker."""

    workers: int
    threads: int
    memory_limit: int
    dashboard: str

    def describe(self, live: bool = True) -> str:
        """The cluster in words; its dashboard's address only while it runs (``live``): a summary
        written after the cluster has stopped would give a link to nothing."""
        dashboard = f", dashboard {self.dashboard}" if live else ""
        return (f"local Dask cluster: {self.workers} worker process{'es' if self.workers != 1 else ''} x "
                f"{self.threads} thread, {budget.gib(self.memory_limit)} each{dashboard}")


class Unreachable(OSError):
    """The scheduler at an address did not answer as a Dask scheduler in time; the message says why."""


CONNECT_SECONDS = 20.0  # the most a connection may take, whatever the peer does
HANDSHAKE_GRACE = 2.0  # beyond Dask's own connect timeout, for its handshake


def connect_seconds() -> float:
    """Dask's connect timeout (``distributed.comm.timeouts.connect``), at most ``CONNECT_SECONDS``, plus
    ``HANDSHAKE_GRACE``."""
    import dask
    from dask.utils import parse_timedelta

    try:
        seconds = float(parse_timedelta(dask.config.get("distributed.comm.timeouts.connect", CONNECT_TIMEOUT)))
    except (ValueError, TypeError, KeyError):
        seconds = CONNECT_SECONDS
    return min(max(seconds, 0.1), CONNECT_SECONDS) + HANDSHAKE_GRACE


def client_within(address: str, seconds: float, should_stop: Callable[[], bool] | None = None):
    """A ``distributed.Client`` to ``address``, or ``Unreachable`` once ``seconds`` have passed, whatever
    the peer does (a server that accepts and never answers held Dask's own ``Client`` for good,
    issue 33), or ``Cancelled`` as soon as ``should_stop()``. The client is made on a daemon thread
    the caller never waits on past the deadline; one that arrives after it is closed there."""
    import threading

    from distributed import Client

    box: dict = {}
    lock = threading.Lock()

    def make() -> None:
        try:
            client = Client(address, timeout=f"{seconds}s")
        except BaseException as e:  # noqa: BLE001 (handed to the caller's thread)
            box["error"] = e
            return
        with lock:
            if box.get("abandoned"):
                with contextlib.suppress(Exception):
                    client.close(timeout=1)
                return
            box["client"] = client

    thread = threading.Thread(target=make, name="lamp-connect", daemon=True)
    thread.start()
    deadline = time.monotonic() + seconds
    try:
        while thread.is_alive():
            if should_stop is not None and should_stop():
                raise Cancelled()
            if time.monotonic() > deadline:
                raise Unreachable(f"no answer from {address} as a Dask scheduler within {seconds:.0f} s")
            thread.join(POLL)
    except BaseException:
        with lock:
            box["abandoned"] = True
            client = box.pop("client", None)
        if client is not None:
            with contextlib.suppress(Exception):
                client.close(timeout=1)
        raise
    if "error" in box:
        e = box["error"]
        if isinstance(e, (OSError, TimeoutError, ValueError, TypeError)):
            raise Unreachable(f"cannot reach {address} ({type(e).__name__}: {str(e)[:200]})") from None
        raise e
    return box["client"]


@contextlib.contextmanager
def connect(scheduler: str | None = None, workers: int | None = None, memory_limit: int | None = None,
            dashboard: str | None = ":0", should_stop: Callable[[], bool] | None = None) -> Iterator:
    """A ``distributed.Client`` (its ``.local`` is a ``Local`` for a local cluster, else None); closed,
    and a local cluster stopped with its processes, on leaving. A scheduler's address is checked
    first (``check_address``); reaching it takes at most ``connect_seconds()`` (``Unreachable``), and
    ``should_stop()`` ends the wait (``Cancelled``)."""
    import dask
    from distributed import Client, LocalCluster

    address = scheduler_address(scheduler)
    if address is not None:
        client = client_within(address, connect_seconds(), should_stop)
        client.local = None
        try:
            yield client
        finally:
            client.close()
        return
    count = workers or default_workers()
    check_workers(count)
    limit = memory_limit or budget.MEMORY_BUDGET
    # The workers' scratch space is the run's own, removed however the run ends (Dask's default
    # <temp>/dask-scratch-space would outlive it).
    scratch = tempfile.mkdtemp(prefix=SCRATCH_PREFIX)
    try:
        # The scheduler's scratch space too; and the workers keep freed memory mapped from their start
        # (preload.py says why; it sets the same in a worker that is already running).
        keep = {f"distributed.nanny.pre-spawn-environ.{k}": int(v) for k, v in processes._KEEP_FREED_MEMORY.items()}
        with dask.config.set({"temporary-directory": scratch, **keep}):
            cluster = LocalCluster(n_workers=count, threads_per_worker=1, processes=True, memory_limit=limit,
                                   dashboard_address=dashboard, preload=[PRELOAD], silence_logs=logging.ERROR,
                                   local_directory=scratch, env={LOCAL_WORKER: "1"})
        try:
            client = Client(cluster)
            client.local = Local(count, 1, limit, client.dashboard_link or "off")
            try:
                yield client
            finally:
                client.close()
        finally:
            cluster.close()
    finally:
        shutil.rmtree(scratch, ignore_errors=True)


@dataclass
class RunCount:
    cells: int = 0
    rendered: int = 0  # tasks run (one per distinct key the cache lacked)
    from_cache: int = 0  # cells whose image the cache held
    task_bytes: int = 0  # the pickled size of the largest task (the cell and its arguments)
    band_tasks: int = 0  # tasks that traced runs of a large cell's bands
    workers: list[str] | None = None  # the workers tasks went to when only some had the memory (None: any)


class CellRun(processes.ImagesInOrder):
    """The cells of one run as a non-blocking object (Blender's modal operators drive it from a
    timer): the cache is read when it is made, ``submit()`` sends the rest as tasks, ``poll()``
    takes in what finished and says whether every image is in, ``cancel()`` stops every task."""

    def __init__(self, client, cells: Sequence[Cell], inputs: Inputs, cache: CellCache | None = None):
        self.client, self.cells, self.inputs, self.cache = client, list(cells), inputs, cache
        self.count = RunCount(cells=len(cells))
        self.images: list[np.ndarray | None] = [None] * len(cells)
        self.wanted: dict[str, list[int]] = {}
        for i, cell in enumerate(self.cells):
            key = cell.key
            image = cache.get(key, (cell.width, cell.height)) if cache is not None else None
            if image is not None:
                self.images[i] = image
                self.count.from_cache += 1
            else:
                self.wanted.setdefault(key, []).append(i)
        self.stop_name = f"lamp-stop-{uuid.uuid4().hex}"
        self.futures: dict = {}  # future -> (key, part): part None for a whole cell, else its run of bands
        self.parts: dict[str, list] = {}  # key -> the rows of each run of bands of a large cell
        self.pending: set = set()
        self.sent: dict = {}
        self.workers: list[str] | None = None  # where tasks went when only some workers' memory fits

    @property
    def finished(self) -> bool:
        return self.done == self.total

    def submit(self) -> None:
        """Send one task per key the cache lacked, and each environment image they need once, to the
        workers whose memory holds the largest cell's render (``fitting_workers``)."""
        if not self.wanted:
            return
        need = max(cell_bytes(self.cells[ix[0]]) for ix in self.wanted.values())
        self.workers = self.count.workers = fitting_workers(self.client, need, "a variant")
        needed = {self.cells[ix[0]].environment for ix in self.wanted.values()} - {None}
        self.sent = {d: self.client.scatter(self.inputs.data[d], hash=False) for d in needed}
        for key, indices in self.wanted.items():
            cell = self.cells[indices[0]]
            env = self.sent.get(cell.environment) if cell.environment is not None else None
            groups = band_groups(cell) if cell.width * cell.height * _samples(cell) >= cells_module.BAND_TASK_RAYS \
                else [None]
            if len(groups) == 1:
                future = self.client.submit(render_cell, cell, env, self.stop_name, key=f"lamp-cell-{key}",
                                            pure=False, workers=self.workers, allow_other_workers=False)
                self.futures[future] = (key, None)
                continue
            self.parts[key] = [None] * len(groups)
            self.count.band_tasks += len(groups)
            for g, bands in enumerate(groups):
                future = self.client.submit(render_bands, cell, bands, env, self.stop_name,
                                            key=f"lamp-bands-{key}-{g}", pure=False, workers=self.workers,
                                            allow_other_workers=False)
                self.futures[future] = (key, g)
        self.pending = set(self.futures)
        if self.wanted:
            self.count.task_bytes = max(_task_bytes(self.cells[ix[0]]) for ix in self.wanted.values())

    def poll(self) -> bool:
        """Take in the finished tasks (each image kept in the cache); True once every image is in.
        Raises ``TaskError`` if a task failed."""
        for future in [f for f in self.pending if f.done()]:
            self.pending.discard(future)
            if future.status != "finished":
                raise TaskError(f"render task failed: {_error_text(future)}")
            result = future.result()
            key, part = self.futures[future]
            future.release()
            if part is not None:  # one run of a large cell's bands
                self.parts[key][part] = result
                if any(p is None for p in self.parts[key]):
                    continue
                result = assemble(self.cells[self.wanted[key][0]], self.parts.pop(key))
            if self.cache is not None:
                self.cache.put(key, result)
            for i in self.wanted[key]:
                self.images[i] = result
            self.count.rendered += 1
        return self.finished

    def cancel(self) -> None:
        """Stop every task: running renders at their next band (the run's stop event), the rest at once."""
        if self.futures and self.client is not None:
            from distributed import Event

            with contextlib.suppress(Exception):
                Event(self.stop_name, client=self.client).set()
            with contextlib.suppress(Exception):
                self.client.cancel(list(self.futures), force=True)
        self.pending = set()
        self.release()

    def release(self) -> None:
        for f in self.sent.values():
            with contextlib.suppress(Exception):
                f.release()
        self.sent = {}


def run_cells(client, cells: Sequence[Cell], inputs: Inputs, cache: CellCache | None = None, *,
              progress: Callable[[int, int], None] | None = None,
              should_stop: Callable[[], bool] | None = None) -> tuple[list[np.ndarray], RunCount]:
    """Every cell's image, in order: from ``cache`` where it holds the key, else rendered as a task
    (and then kept in ``cache``). ``progress(done, total)`` as cells arrive; ``should_stop()``
    polled every ``POLL`` seconds: True cancels every task and raises ``Cancelled``."""
    run = CellRun(client, cells, inputs, cache)
    if progress is not None:
        progress(run.done, run.total)
    if run.finished:
        return run.images, run.count  # type: ignore[return-value]
    try:
        run.submit()
        reported = run.done
        while True:
            if should_stop is not None and should_stop():
                raise Cancelled()
            finished = run.poll()
            if progress is not None and run.done != reported:
                reported = run.done
                progress(run.done, run.total)
            if finished:
                return run.images, run.count  # type: ignore[return-value]
            time.sleep(POLL)
    except BaseException:
        run.cancel()
        raise
    finally:
        run.release()
        if cache is not None:
            cache.prune()


def _samples(cell: Cell) -> int:
    return int(cell.scene["image"].get("samples", 1) or 1)


def _error_text(future) -> str:
    try:
        e = future.exception(timeout=5)
    except Exception as other:  # the future itself could not say (cancelled, lost)
        return f"{type(other).__name__}: {other}"
    return f"{type(e).__name__}: {e}"


def _task_bytes(cell: Cell) -> int:
    import pickle

    return len(pickle.dumps(cell, protocol=pickle.HIGHEST_PROTOCOL))

"""A render's bands traced in worker processes: the tracer without the interpreter lock.

Why processes: the wavefront makes many numpy calls per generation, and between them each thread
needs the interpreter. On two cores two threads of one render spend 24-37 % more CPU than one
thread does alone (the day preset at 16 samples, the viewport's three-quarter view), so they give
1.3-1.5x; two processes give 1.9x (benchmarks/bench_viewport.py, benchmarks/bench_samples.py).

A ``BandPool`` keeps its worker processes (``band_worker``) for the life of the interpreter, so a
render pays only for sending its scene (a few kilobytes) and receiving its rows. It serves one
render at a time: a render that finds it busy, starting, or broken runs its bands on threads
instead, the same image bit for bit. The bands are handed out one at a time as workers ask for
them and come back in order; ``should_stop()`` is polled every few milliseconds, and a stopped
render's workers stop within a generation. A worker that dies (killed, out of memory) breaks the
pool: the render finishes on threads, and ``shared()`` starts a new pool for the next.
"""

from __future__ import annotations

import atexit
import contextlib
import mmap
import os
import queue
import struct
import subprocess
import tempfile
import threading
import time
from collections import deque
from collections.abc import Callable, Iterator

from .. import budget, processes
from .band_worker import read_message, write_message
from .engine.schedule import BandImage, InOrder, RenderCancelled, short_switch_interval

POLL_SECONDS = 0.002  # how often a render in the pool polls should_stop() while no band arrives
LEASE_WAIT = 0.25  # seconds a render waits for the pool to finish stopping the render before it
READY_WAIT = 2.0  # seconds a heavy render waits for a starting pool's workers (about 0.2 s)
HEAVY_RAYS = budget.POOL_RAYS  # eye rays (pixels x samples) from which a render waits for a starting pool
DRAIN_SECONDS = 10.0  # a stopped render's workers report idle within this, or the pool is broken
CLOSE_SECONDS = 2.0  # workers get this long to exit when the pool closes, then are killed
_SERIAL = struct.Struct("<I")


class BandWorkerError(RuntimeError):
    """A worker process failed while tracing a band (a tracer bug, never a user's mistake); the
    message holds the worker's traceback."""


class BandPool:
    """``workers`` band worker processes, started at once (they are ready about 0.2 s later)."""

    def __init__(self, workers: int | None = None, python: str | None = None):
        self.size = max(1, workers or os.cpu_count() or 1)
        self.broken: str | None = None  # why the pool no longer serves renders
        self.renders = 0  # renders whose bands the workers traced (tests and benchmarks read it)
        self._lease = threading.Lock()
        self._messages: queue.SimpleQueue = queue.SimpleQueue()
        self._ready = [threading.Event() for _ in range(self.size)]
        self._starting = threading.Lock()
        self._started = 0  # workers that reported ready
        self._serial = 0
        self._processes: list[subprocess.Popen] = []
        fd, self._flag_path = _new_flag_file()
        with os.fdopen(fd, "wb") as f:
            f.write(bytes(_SERIAL.size))
        with open(self._flag_path, "r+b") as f:
            self._flag = mmap.mmap(f.fileno(), _SERIAL.size)
        try:
            for slot in range(self.size):
                process = subprocess.Popen(processes.worker_command("raytrace.band_worker", self._flag_path,
                                                                    python=python),
                                           stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                           cwd=processes.PACKAGE_ROOT, env=processes.worker_environment(),
                                           start_new_session=os.name == "posix")  # Ctrl-C reaches this process only
                self._processes.append(process)
                threading.Thread(target=self._read, args=(slot, process.stdout), daemon=True,
                                 name=f"Lamp Tracer band worker {slot}").start()
        except BaseException:
            self.close()
            raise

    # -- life cycle ---------------------------------------------------------------------------

    def _read(self, slot: int, stream) -> None:
        while (message := read_message(stream)) is not None:
            if message[0] == "ready":
                with self._starting:
                    self._started += 1
                    if self._started == self.size:
                        self._forget_flag_file()  # before anyone can see the pool ready
                self._ready[slot].set()
            else:
                self._messages.put((slot, message))
        if self.broken is None:
            code = self._processes[slot].poll()
            self.broken = f"band worker {slot} ended unexpectedly" + (f" (exit code {code})" if code is not None
                                                                       else "")
        self._ready[slot].set()  # nobody waits for a worker that is gone
        self._messages.put((slot, None))

    def _forget_flag_file(self) -> None:
        """Every worker has mapped the flag: its file can go (POSIX; elsewhere at ``close``)."""
        if os.name == "posix":
            with contextlib.suppress(OSError):
                os.unlink(self._flag_path)

    def ready(self, timeout: float = 0.0) -> bool:
        """Whether every worker is up (waiting up to ``timeout`` seconds for them) and none failed."""
        deadline = time.monotonic() + timeout
        for event in self._ready:
            if not event.wait(max(0.0, deadline - time.monotonic())):
                return False
        return self.broken is None

    def close(self) -> None:
        """End the workers (end of input, then kill after ``CLOSE_SECONDS``); idempotent."""
        if self.broken is None:
            self.broken = "closed"
        if not self._flag.closed:
            _SERIAL.pack_into(self._flag, 0, 0)  # a worker still tracing stops within a generation
        for process in self._processes:
            with contextlib.suppress(OSError):
                process.stdin.close()
        deadline = time.monotonic() + CLOSE_SECONDS
        for process in self._processes:
            try:
                process.wait(max(0.0, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait()
        with contextlib.suppress(ValueError):
            self._flag.close()
        with contextlib.suppress(OSError):
            os.unlink(self._flag_path)

    def process_ids(self) -> list[int]:
        return [process.pid for process in self._processes]

    # -- rendering ----------------------------------------------------------------------------

    def traced_bands(self, scene: dict, width: int, height: int, options: dict, bands: list[tuple[int, int]],
                     workers: int, should_stop: Callable[[], bool],
                     fallback: Callable[[list[tuple[int, int]]], Iterator[tuple[int, int, BandImage]]],
                     ) -> Iterator[tuple[int, int, BandImage]]:
        """The ``bands`` of the render (``engine.make_context``'s arguments, and ``keep_passes`` in
        ``options``) traced by ``workers`` of the pool's processes, yielded in order as (y0, y1,
        band); ``fallback(bands)`` traces them instead (or the rest of them, if a worker dies)
        when the pool cannot take the render. Raises ``RenderCancelled`` once ``should_stop()``."""
        heavy = width * height * int(options.get("samples") or 1) >= HEAVY_RAYS
        if not self._lease.acquire(timeout=LEASE_WAIT):
            yield from fallback(bands)
            return
        try:
            usable = self.ready(READY_WAIT if heavy else 0.0)
            if usable:
                self.renders += 1
                # A worker that asks for its next band waits for this thread's answer: with the
                # interface's thread running Python (Blender's), the interpreter's 5 ms switch
                # interval would be that wait.
                with short_switch_interval():
                    rest = yield from self._traced(scene, width, height, options, bands, min(workers, self.size),
                                                   should_stop)
        finally:
            self._lease.release()
        if not usable:
            yield from fallback(bands)
        elif rest:
            yield from fallback(rest)

    def _traced(self, scene: dict, width: int, height: int, options: dict, bands: list[tuple[int, int]],
                workers: int, should_stop: Callable[[], bool]):
        """The pool's part of ``traced_bands`` (the lease held); returns the bands left to trace
        elsewhere, empty unless a worker died."""
        self._serial = self._serial % 0xFFFFFFFF + 1
        serial = self._serial
        _SERIAL.pack_into(self._flag, 0, serial)
        slots = list(range(workers))
        queued = deque(enumerate(bands))
        in_order = InOrder(bands, should_stop)
        busy = set(slots)  # workers that have not reported the render's end
        try:
            for slot in slots:
                self._send(slot, ("render", serial, scene, width, height, options))
            while busy:
                try:
                    slot, message = self._messages.get(timeout=POLL_SECONDS)
                except queue.Empty:
                    if should_stop():
                        raise RenderCancelled("render cancelled") from None
                    continue
                if message is None:  # a worker died: the others stop, and the rest is traced elsewhere
                    self.close()
                    return bands[in_order.next_index:]
                kind, message_serial = message[0], message[1]
                if message_serial != serial:
                    continue
                if kind == "take":
                    job = None
                    if queued and not should_stop():
                        index, (y0, y1) = queued.popleft()
                        job = (index, y0, y1)
                    self._send(slot, ("job", job))
                elif kind == "band":
                    index, *fields = message[2:]
                    yield from in_order.add(index, BandImage(*fields))
                elif kind == "error":
                    raise BandWorkerError(f"a band worker failed:\n{message[2]}")
                elif kind == "idle":
                    busy.discard(slot)
            if should_stop():
                raise RenderCancelled("render cancelled")
            if in_order.next_index != len(bands):  # every worker ended, yet bands are missing: a tracer bug
                raise BandWorkerError(f"the band workers ended with {len(bands) - in_order.next_index} bands "
                                      "not traced")
            return []
        finally:
            self._stop(serial, busy)

    def _stop(self, serial: int, busy: set[int]) -> None:
        """End the render ``serial``: its workers stop within a generation, takes are answered
        with no more, and each busy worker is heard reporting idle (or the pool is broken)."""
        if self._flag.closed:  # the pool closed (a worker died): nothing left to stop
            return
        _SERIAL.pack_into(self._flag, 0, 0)
        deadline = time.monotonic() + DRAIN_SECONDS
        while busy and self.broken is None:
            try:
                slot, message = self._messages.get(timeout=max(0.0, deadline - time.monotonic()))
            except queue.Empty:
                self.broken = f"band workers did not stop within {DRAIN_SECONDS:g} s"
                self.close()
                return
            if message is None:
                self.close()
                return
            if message[1] != serial:
                continue
            if message[0] == "take":
                self._send(slot, ("job", None))
            elif message[0] == "idle":
                busy.discard(slot)

    def _send(self, slot: int, message) -> None:
        try:
            write_message(self._processes[slot].stdin, message)
        except (OSError, ValueError):  # the worker is gone: its reader reports it
            pass


FLAG_PREFIX = "lamp-bands-"  # <temp>/lamp-bands-<pid of the pool's process>-<random>


def _new_flag_file() -> tuple[int, str]:
    """A pool's flag file, named by this process; those of pools whose process was killed before
    their workers were up (SIGKILL: no cleanup ran) are removed first."""
    processes.remove_orphans(FLAG_PREFIX)
    return tempfile.mkstemp(prefix=f"{FLAG_PREFIX}{os.getpid()}-")


enabled = True  # False: ``shared()`` gives no pool, every render runs on threads (benchmarks compare)
_shared: BandPool | None = None
_shared_lock = threading.Lock()
RESTARTS = 3  # broken pools ``shared()`` replaces before it gives up (threads from then on)
_restarts = 0


def shared() -> BandPool | None:
    """The interpreter's band pool, started on the first call (its workers are ready about 0.2 s
    later) and replaced if it broke; None where workers cannot run (no Python interpreter to start,
    or ``RESTARTS`` pools broke): renders then use threads."""
    global _shared, _restarts
    with _shared_lock:
        if _shared is not None and _shared.broken is not None:
            _shared.close()
            _shared = None
            _restarts += 1
        if not enabled:
            return None
        if _shared is None and _restarts <= RESTARTS and processes.python_runs_workers():
            try:
                _shared = BandPool()
            except OSError:
                _restarts = RESTARTS + 1
        return _shared


def running_workers() -> int:
    """How many worker processes the interpreter's band pool holds now (0: none started, or broken),
    without starting one: other work counts their memory (``budget.WORKER_BYTES`` each)."""
    with _shared_lock:
        return _shared.size if _shared is not None and _shared.broken is None else 0


def shutdown() -> None:
    """Close the shared pool (the add-on's unregister, the interpreter's exit); ``shared()``
    starts a new one afterwards."""
    global _shared
    with _shared_lock:
        if _shared is not None:
            _shared.close()
            _shared = None


atexit.register(shutdown)

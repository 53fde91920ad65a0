"""Rendering a study in parallel: one worker process per core, progress and cancel.

``run_study(study)`` renders every variant and returns the images in variant order; it blocks,
calling ``progress(done, total)`` and polling ``should_stop()``. ``StudyRun`` is the same work as
a non-blocking object for event loops (Blender's modal operators): ``start()``, then ``poll()``
from a timer until it returns True, ``cancel()`` at any time.

Workers are separate Python processes (``worker.py``), started with the interpreter that
runs this code (``sys.executable``: the venv's python for the CLI and the tests, Blender's own
Python inside Blender) in isolated mode (``-I``: no user site-packages, no PYTHON* variables),
with the folder that holds ``core_tracer`` put first on their path. Jobs go over stdin as JSON;
images come back as ``.npy`` files in a private temporary folder, removed when the run ends
however it ends. Worker numpy runs single-threaded (OMP/BLAS threads = 1); each worker's
renders use ``threads`` band threads (default: the cores left over per worker, so 1 when there
are as many workers as cores).
"""

from __future__ import annotations

import contextlib
import json
import os
import queue
import shutil
import subprocess
import tempfile
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from .. import processes
from ..freeform.traced import render_scene
from ..images import glare
from ..raytrace.engine import RenderCancelled
from .definition import Study

TERMINATE_TIMEOUT = 3.0  # seconds a worker gets to exit after terminate() before kill()

workers_started = 0  # how many worker processes this interpreter has started (tests read it)


class Cancelled(Exception):
    """The study was cancelled: its workers are gone and nothing was written."""

    def __init__(self, message: str = "study cancelled"):
        super().__init__(message)


class StudyError(RuntimeError):
    """A worker failed (a tracer bug or a broken installation, never a user's mistake)."""


FOLDER_PREFIX = "lamp-study-"  # <temp>/lamp-study-<pid of the run's process>-<random>


def remove_orphaned_folders(temp: str | None = None) -> list[str]:
    """Remove the temporary folders of studies whose process is gone (killed with SIGKILL, or by a
    power cut: no cleanup could run); returns them (``processes.remove_orphans``)."""
    return processes.remove_orphans(FOLDER_PREFIX, temp)


def default_workers() -> int:
    return max(1, os.cpu_count() or 1)


def worker_command(python: str | None = None) -> list[str]:
    """The command line of one worker process."""
    return processes.worker_command("study.worker", python=python)


@dataclass
class _Worker:
    process: subprocess.Popen
    log_path: str
    reader: threading.Thread
    job: int | None = None  # the variant being rendered
    closed: bool = False  # stdin closed: no more jobs


@dataclass
class StudyRun(processes.ImagesInOrder):
    """One run of a study over worker processes, driven by ``poll()``."""

    study: Study
    workers: int | None = None
    threads: int | None = None
    python: str | None = None  # the interpreter for the workers; sys.executable by default
    images: list[np.ndarray | None] = field(init=False)
    seconds: list[float | None] = field(init=False)
    _fraction: dict[int, float] = field(init=False, default_factory=dict)
    _pending: list[int] = field(init=False, default_factory=list)
    _pool: list[_Worker] = field(init=False, default_factory=list)
    _messages: queue.Queue = field(init=False, default_factory=queue.Queue)
    _folder: str | None = field(init=False, default=None)
    _finished: bool = field(init=False, default=False)

    def __post_init__(self) -> None:
        self.images = [None] * len(self.study)
        self.seconds = [None] * len(self.study)
        if self.workers is not None and self.workers < 1:
            raise ValueError(f"workers must be at least 1, got {self.workers}")

    # -- state --------------------------------------------------------------------------------

    @property
    def fraction(self) -> float:
        """Progress in [0, 1], counting the parts of the renders under way."""
        return (self.done + sum(self._fraction.values())) / self.total

    @property
    def finished(self) -> bool:
        return self._finished

    def process_ids(self) -> list[int]:
        return [w.process.pid for w in self._pool]

    # -- life cycle ---------------------------------------------------------------------------

    def start(self) -> None:
        global workers_started
        if self._pool or self._folder:
            raise RuntimeError("a StudyRun starts once")
        count = min(self.workers or default_workers(), self.total)
        if self.threads is None:
            self.threads = max(1, default_workers() // count)
        remove_orphaned_folders()
        self._folder = tempfile.mkdtemp(prefix=f"{FOLDER_PREFIX}{os.getpid()}-")
        self._pending = list(range(self.total))
        try:
            for k in range(count):
                log_path = os.path.join(self._folder, f"worker-{k}.log")
                with open(log_path, "wb") as log:
                    process = subprocess.Popen(worker_command(self.python), stdin=subprocess.PIPE,
                                               stdout=subprocess.PIPE, stderr=log, cwd=processes.PACKAGE_ROOT,
                                               env=processes.worker_environment(),
                                               # a terminal's Ctrl-C reaches this process only; it stops them
                                               start_new_session=os.name == "posix")
                workers_started += 1
                reader = threading.Thread(target=self._read, args=(k, process.stdout), daemon=True)
                worker = _Worker(process, log_path, reader)
                self._pool.append(worker)
                reader.start()
                self._dispatch(worker)
        except BaseException:
            self.close()
            raise

    def _read(self, k: int, stream) -> None:
        for line in stream:
            self._messages.put((k, line))
        self._messages.put((k, None))

    def _dispatch(self, worker: _Worker) -> None:
        if worker.closed:
            return
        if not self._pending:
            worker.closed = True
            with contextlib.suppress(OSError):
                worker.process.stdin.close()
            return
        index = self._pending.pop(0)
        worker.job = index
        v = self.study.variants[index]
        width, height = self.study.size
        job = {"index": index, "scene": v.scene, "width": width, "height": height, "threads": self.threads,
               "out": os.path.join(self._folder, f"variant-{index:02d}.npy")}
        try:
            worker.process.stdin.write((json.dumps(job) + "\n").encode("utf-8"))
            worker.process.stdin.flush()
        except OSError:  # the worker is gone (its end of the pipe is closed)
            raise self._failure(worker, "stopped unexpectedly") from None

    def poll(self, timeout: float = 0.0) -> bool:
        """Handle what the workers reported, waiting up to ``timeout`` seconds for the first
        message; True once every image is in. Raises ``StudyError`` if a worker failed."""
        if self._finished:
            return True
        if not self._pool:
            raise RuntimeError("poll() before start()")
        try:
            k, line = self._messages.get(timeout=timeout) if timeout > 0 else self._messages.get_nowait()
        except queue.Empty:
            return False
        while True:
            self._handle(k, line)
            try:
                k, line = self._messages.get_nowait()
            except queue.Empty:
                break
        if self.done == self.total:
            self._finish()
        return self._finished

    def _handle(self, k: int, line: bytes | None) -> None:
        worker = self._pool[k]
        if line is None:
            if worker.job is not None or not worker.closed:
                raise self._failure(worker, "stopped unexpectedly")
            return
        message = json.loads(line)
        index = message["index"]
        if "error" in message:
            raise self._failure(worker, f"failed on variant {index}: {message['error']}")
        if "progress" in message:
            self._fraction[index] = min(float(message["progress"]), 1.0)
            return
        out = os.path.join(self._folder, f"variant-{index:02d}.npy")
        self.images[index] = np.load(out)
        os.unlink(out)
        self.seconds[index] = float(message.get("seconds", 0.0))
        self._fraction.pop(index, None)
        worker.job = None
        self._dispatch(worker)

    def _failure(self, worker: _Worker, what: str) -> StudyError:
        self._stop_workers()  # every worker has exited now, so the log is complete
        lines: list[str] = []
        with contextlib.suppress(OSError):
            with open(worker.log_path, "rb") as f:
                lines = f.read()[-4000:].decode("utf-8", "replace").strip().splitlines()
        detail = f" ({lines[-1].strip()})" if lines else ""
        self.close()
        return StudyError(f"study worker {what}{detail}")

    def _finish(self) -> None:
        for worker in self._pool:
            with contextlib.suppress(subprocess.TimeoutExpired):
                worker.process.wait(timeout=TERMINATE_TIMEOUT)
        self._finished = True
        self.close()

    def cancel(self) -> None:
        """Stop every worker now and remove the temporary files; the images are dropped."""
        self.images = [None] * self.total
        self.close()

    def close(self) -> None:
        """Stop the workers that still run (terminate, then kill) and remove the temporary folder."""
        self._stop_workers()
        if self._folder is not None:
            shutil.rmtree(self._folder, ignore_errors=True)
            self._folder = None

    def _stop_workers(self) -> None:
        for worker in self._pool:
            with contextlib.suppress(OSError):
                if worker.process.stdin and not worker.process.stdin.closed:
                    worker.process.stdin.close()
            if worker.process.poll() is None:
                worker.process.terminate()
        deadline = time.monotonic() + TERMINATE_TIMEOUT
        for worker in self._pool:
            try:
                worker.process.wait(timeout=max(0.0, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                worker.process.kill()
                worker.process.wait()
            worker.reader.join(timeout=1.0)
            with contextlib.suppress(OSError):
                worker.process.stdout.close()

    def __enter__(self) -> StudyRun:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def run_study(study: Study, workers: int | None = None, *, threads: int | None = None,
              progress: Callable[[int, int], None] | None = None,
              should_stop: Callable[[], bool] | None = None,
              on_start: Callable[[StudyRun], None] | None = None) -> list[np.ndarray]:
    """Render every variant of ``study``; the images (H, W, 3 float32) in variant order.

    ``workers`` processes (default: one per core). ``workers=0`` renders in this process, one
    variant after the other (no subprocesses; for comparison and for debugging).
    ``progress(done, total)`` is called as variants finish; ``should_stop()`` is polled about
    every 50 ms and a True answer stops the workers and raises ``Cancelled``. ``on_start`` gets
    the ``StudyRun`` once its workers run (tests use it to see the process ids).
    """
    if workers == 0:
        return _run_here(study, threads, progress, should_stop)
    run = StudyRun(study, workers, threads)
    try:
        run.start()
        if on_start is not None:
            on_start(run)
        reported = -1
        while True:
            if should_stop is not None and should_stop():
                raise Cancelled()
            try:
                finished = run.poll(timeout=0.05)
            except StudyError:
                if should_stop is not None and should_stop():
                    raise Cancelled() from None  # a worker stopped because the user cancelled
                raise
            if progress is not None and run.done != reported:
                reported = run.done
                progress(run.done, run.total)
            if finished:
                return list(run.images)  # type: ignore[arg-type]
    finally:
        run.close()


def _run_here(study: Study, threads: int | None, progress, should_stop) -> list[np.ndarray]:
    width, height = study.size
    images = []
    if progress is not None:
        progress(0, len(study))
    for v in study.variants:
        try:
            image = render_scene(v.scene, width, height, should_stop=should_stop, threads=threads,
                                  keep_passes=False).image
            images.append(glare.apply(image, v.scene))
        except RenderCancelled:
            raise Cancelled() from None
        if progress is not None:
            progress(len(images), len(study))
    return images

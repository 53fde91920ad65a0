"""The viewport preview's stages: a coarse image first, then full resolution, then full resolution
with more samples per pixel (smooth edges), off the main thread.

One ``PreviewJob`` renders one view of one design: its stages in order, each a whole image at
1/divisor of the region's size and some samples per pixel (the refined stage uses the tracer's
adaptive sampling, so its samples go to edges, creases and bulb images). ``ProgressivePreview``
keeps the current job: ``restart`` cancels it (the tracer polls ``should_stop`` between bands,
so a stale job stops within a band) and starts the new one; each finished stage of the current
job is published as a ``Frame``. Stages run either on a worker thread (``start``, what the
engine does: numpy releases the GIL, so Blender's UI keeps running) or in the caller's thread
one at a time (``step``, what the tests do).

No ``bpy`` here: the engine reads Blender on the main thread and hands this module plain scene
dicts; the worker never touches Blender.
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass

import numpy as np

from ...core_tracer.raytrace import band_pool
from ...core_tracer.raytrace.engine import RenderCancelled, render_passes
from ...core_tracer.scene.reading import SceneError

# The coarse stage's pixel budget: 128x96, 1/8 of a 1024x768 region, renders the four-lamp preset
# in about 0.05 s on 2 idle cores (0.1 s on a loaded machine), the first image wanted within 0.1 s;
# 1/4 of that region takes 2-3 times as long (benchmarks/bench_viewport.py). A budget rather than
# a fixed fraction keeps the first image as quick in a full-screen 4K viewport.
COARSE_PIXELS = 128 * 96
# The refined stage's samples per pixel: as many as an F12 render with smooth edges takes; with
# adaptive sampling a 1024x768 region costs about 3 to 5 full-resolution stages
# (benchmarks/bench_viewport.py). Edits and view changes restart from the coarse stage as before.
REFINE_SAMPLES = 16


def coarse_divisor(width: int, height: int) -> int:
    """The smallest power of two, at least 2, that brings the region within ``COARSE_PIXELS``."""
    divisor = 2
    while (width / divisor) * (height / divisor) > COARSE_PIXELS:
        divisor *= 2
    return divisor


def stages_for(width: int, height: int) -> tuple[int, ...]:
    """The divisors of a region's one-sample stages: coarse, then full resolution."""
    return (coarse_divisor(width, height), 1)


def stage_plan(divisors: tuple[int, ...], refine_samples: int) -> tuple[tuple[int, int], ...]:
    """(divisor, samples per pixel) of each stage in order: the one-sample ``divisors``, then the
    full resolution at ``refine_samples`` when that is more than one."""
    plan = tuple((divisor, 1) for divisor in divisors)
    return plan + ((1, refine_samples),) if refine_samples > 1 else plan


@dataclass(frozen=True)
class Frame:
    """A finished stage: ``image`` (height, width, 3) float32 linear RGB, top row first."""

    generation: int  # which restart it belongs to
    stage: int  # index into the job's stages
    divisor: int  # the image is 1/divisor of the region's size
    image: np.ndarray
    samples: int = 1  # samples per pixel it was rendered with


def stage_size(width: int, height: int, divisor: int) -> tuple[int, int]:
    """The image size of a stage: the region's size over ``divisor``, rounded up (never 0)."""
    return max(1, math.ceil(width / divisor)), max(1, math.ceil(height / divisor))


class PreviewJob:
    """The stages of one view of one design, run in order until done or cancelled."""

    def __init__(self, scene: dict, width: int, height: int, generation: int,
                 divisors: tuple[int, ...] | None = None, threads: int | None = None,
                 refine_samples: int = REFINE_SAMPLES, renderer=None):
        self.scene = scene
        # render_passes' stand-in for a scene it does not trace itself (free-form parts,
        # lamp_addon.freeform_render), called with the same arguments
        self.renderer = renderer or render_passes
        self.width, self.height = width, height
        self.generation = generation
        self.stages = stage_plan(divisors if divisors is not None else stages_for(width, height), refine_samples)
        self.divisors = tuple(divisor for divisor, _ in self.stages)
        self.threads = threads
        self.next_stage = 0
        self._cancel = threading.Event()

    @property
    def done(self) -> bool:
        return self.next_stage >= len(self.divisors)

    @property
    def cancelled(self) -> bool:
        return self._cancel.is_set()

    def cancel(self) -> None:
        self._cancel.set()

    def run_next_stage(self) -> Frame | None:
        """Render the next stage; None when there is none left or the job was cancelled."""
        if self.done or self.cancelled:
            return None
        stage = self.next_stage
        divisor, samples = self.stages[stage]
        width, height = stage_size(self.width, self.height, divisor)
        try:
            result = self.renderer(self.scene, width, height, should_stop=self._cancel.is_set,
                                   threads=self.threads, keep_passes=False, samples=samples,
                                   pool=band_pool.shared())
        except RenderCancelled:
            return None
        self.next_stage += 1
        return Frame(self.generation, stage, divisor, result.image, samples)


class ProgressivePreview:
    """The current preview job and the newest frame it (or an earlier job) finished."""

    def __init__(self, divisors: tuple[int, ...] | None = None, threads: int | None = None,
                 refine_samples: int = REFINE_SAMPLES):
        self.divisors = divisors  # None: ``stages_for`` the region of each restart
        self.threads = threads
        self.refine_samples = refine_samples  # of the last stage; 1: no refined stage
        self.history: list[tuple[int, int]] = []  # (generation, stage) of each published frame
        self.error: str | None = None  # what stopped the last job, if it failed
        self._lock = threading.Lock()
        self._job: PreviewJob | None = None
        self._generation = 0
        self._frame: Frame | None = None
        self._news = False
        self._worker: threading.Thread | None = None

    def restart(self, scene: dict, width: int, height: int, renderer=None) -> None:
        """Cancel the running job and make a new one for ``scene`` seen in a region of this size
        (rendered by ``renderer`` when given, see ``PreviewJob``). The newest frame stays available
        until the new job's first stage replaces it."""
        with self._lock:
            if self._job is not None:
                self._job.cancel()
            self._generation += 1
            self._job = PreviewJob(scene, width, height, self._generation, self.divisors, self.threads,
                                   self.refine_samples, renderer)
            self.error = None

    def cancel(self) -> None:
        with self._lock:
            if self._job is not None:
                self._job.cancel()

    def step(self) -> bool:
        """Run the current job's next stage in the calling thread; False if nothing was left to do."""
        job = self._job
        if job is None:
            return False
        frame = job.run_next_stage()
        if frame is None:
            return False
        self.publish(job, frame)
        return True

    def start(self) -> None:
        """Run the current job's remaining stages on a worker thread."""
        job = self._job
        if job is None or job.done:
            return
        self._worker = threading.Thread(target=self._run, args=(job,), name="Lamp Tracer preview", daemon=True)
        self._worker.start()

    @property
    def job(self) -> PreviewJob | None:
        return self._job

    @property
    def generation(self) -> int:
        """The current job's generation: 0 before the first ``restart``, then 1, 2, ..."""
        return self._generation

    def busy(self) -> bool:
        """The current job has stages left, or its worker has yet to publish the last one."""
        job = self._job
        if job is None or job.cancelled or self.error is not None:
            return False
        return not job.done or (self._worker is not None and self._worker.is_alive())

    def wait(self, timeout: float | None = None) -> None:
        """Block until the worker started last has finished (benchmarks and tests; never the UI)."""
        if self._worker is not None:
            self._worker.join(timeout)

    def frame(self) -> Frame | None:
        """The newest published frame (possibly of an earlier view, until the new one has a stage)."""
        return self._frame

    def take_news(self) -> bool:
        """True once after each published frame: the main thread's signal to redraw."""
        with self._lock:
            news, self._news = self._news, False
        return news

    def _run(self, job: PreviewJob) -> None:
        try:
            while not job.done and not job.cancelled:
                frame = job.run_next_stage()
                if frame is not None:
                    self.publish(job, frame)
        except Exception as e:  # noqa: BLE001 (shown in the viewport instead of lost on a thread)
            with self._lock:
                if job is self._job:
                    # A user's mistake (a free-form part's mesh the tracer refuses) in its own words.
                    self.error = str(e) if isinstance(e, SceneError) else f"{type(e).__name__}: {e}"
                    self._news = True

    def publish(self, job: PreviewJob, frame: Frame) -> None:
        """Show ``frame``, unless its job is no longer the current one."""
        with self._lock:
            if job is not self._job or job.cancelled:
                return  # a stale view: never shown
            self._frame = frame
            self.history.append((frame.generation, frame.stage))
            self._news = True

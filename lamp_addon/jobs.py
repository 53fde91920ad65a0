"""Long jobs from the interface: one base for the modal operators (render, compare, study).

Each job runs off the main thread (a worker thread, worker processes, Blender's render job) while a
modal operator polls it on a window-manager timer every ``POLL_SECONDS``: the interface keeps
responding, the progress shows in the status bar, Esc cancels. ``ModalJob`` is that operator's
skeleton; a subclass says how to start, poll, cancel and describe its work.

One run at a time, per kind of job: ``claim`` records the run under a key (the operator's idname),
``running`` answers the operators' ``poll`` (so a script cannot start a second run either), ``release``
frees it on every exit path. Called from a script or in background mode, where there are no windows,
the operators run synchronously.
"""

from __future__ import annotations

from . import reports

POLL_SECONDS = 0.2  # how often a modal job looks at its work

_runs: dict[str, object] = {}  # key -> the run under way: the one registry of running jobs


class JobBusy(Exception):
    """Another run of the same kind is under way."""


def running(key: str) -> object | None:
    """The run under way for ``key``, or None."""
    return _runs.get(key)


def claim(key: str, run: object, busy_message: str) -> None:
    """Record ``run`` as the one run of ``key``; raises ``JobBusy(busy_message)`` if another is under way."""
    current = _runs.get(key)
    if current is not None and current is not run:
        raise JobBusy(busy_message)
    _runs[key] = run


def release(key: str, run: object | None = None) -> None:
    """Forget the run of ``key`` (only if it is ``run``, when given)."""
    if run is None or _runs.get(key) is run:
        _runs.pop(key, None)


class ModalJob:
    """Mixin for a ``bpy.types.Operator`` whose ``invoke`` starts work that ends later.

    The subclass starts its work in ``invoke`` and hands it to ``begin_modal``; then it provides
    ``step`` (on each timer tick: None while the work goes on, else the operator's result, after
    calling ``end_modal``), ``escape`` (what Esc does: the modal return value), ``abandon`` (stop the
    work when Blender ends the operator: file load, quit), ``status`` (the status-bar text) and
    ``fraction`` (done so far, 0..1, or None when unknown)."""

    bl_options = {"REGISTER"}  # the work changes no data by itself (a job that builds objects says so)
    job_key = ""  # the key the run is claimed under (``key``): empty for the operator's idname
    busy_message = "A job of this kind is running (Esc cancels it)"
    settings = ""  # the scene's property that holds the job's settings, which ``poll`` wants

    @classmethod
    def key(cls) -> str:
        """The key a run of this kind is claimed under: ``job_key``, else the operator's idname."""
        return cls.job_key or cls.bl_idname

    @classmethod
    def poll(cls, context):
        """A scene with the job's settings, nothing in the way (``refusal``), no run of this kind under way."""
        scene = context.scene
        if scene is None or (cls.settings and not hasattr(scene, cls.settings)):
            cls.poll_message_set("No scene")
            return False
        why = cls.refusal(context)
        if why:
            cls.poll_message_set(why)
            return False
        return cls.poll_not_running()

    @classmethod
    def refusal(cls, context) -> str | None:
        """Why the job cannot start in this scene (the poll message), or None."""
        return None

    @classmethod
    def poll_not_running(cls) -> bool:
        """For ``poll``: False, saying why, while a run of this kind is under way."""
        if running(cls.key()) is not None:
            cls.poll_message_set(cls.busy_message)
            return False
        return True

    def begin_modal(self, context, run: object) -> set[str]:
        """Claim the run, add the timer and the modal handler, start the progress display."""
        claim(self.key(), run, self.busy_message)
        self._job_run = run
        wm = context.window_manager
        self._job_timer = wm.event_timer_add(POLL_SECONDS, window=context.window)
        wm.modal_handler_add(self)
        wm.progress_begin(0, 100)
        self._show_status(context)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        if event.type == "ESC" and event.value == "PRESS":
            outcome = self.escape(context)
            if "RUNNING_MODAL" in outcome:
                self._show_status(context)
            return outcome
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        outcome = self.step(context)
        if outcome is None:
            self._show_status(context)
            return {"PASS_THROUGH"}
        return outcome

    def cancel(self, context):
        # Blender ends the operator (file load, quit): stop the work and clean up.
        self.abandon(context)
        self.end_modal(context)

    def end_modal(self, context) -> None:
        """Remove the timer, end the progress display, clear the status text, release the run.
        Every exit path calls it; calling it again does nothing."""
        timer = getattr(self, "_job_timer", None)
        if timer is None:
            return
        self._job_timer = None
        wm = context.window_manager
        wm.event_timer_remove(timer)
        wm.progress_end()
        if context.workspace is not None:
            context.workspace.status_text_set(None)
        release(self.key(), self._job_run)

    def _show_status(self, context) -> None:
        fraction = self.fraction()
        if fraction is not None:
            context.window_manager.progress_update(int(100 * fraction))
        if context.workspace is not None:
            context.workspace.status_text_set(self.status())

    # What a subclass provides

    def step(self, context) -> set[str] | None:  # pragma: no cover - every job overrides it
        raise NotImplementedError

    cancelled_message = "Cancelled"  # what the default ``escape`` reports

    def escape(self, context) -> set[str]:
        """Esc: stop the work now, end the modal and say so (jobs whose work stops later override it)."""
        self.abandon(context)
        self.end_modal(context)
        reports.say(self, "WARNING", self.cancelled_message)
        return {"CANCELLED"}

    def abandon(self, context) -> None:  # pragma: no cover - every job overrides it
        raise NotImplementedError

    def status(self) -> str:  # pragma: no cover - every job overrides it
        raise NotImplementedError

    def fraction(self) -> float | None:
        """Done so far (0..1): the run's own ``fraction`` when it keeps one, else None (unknown)."""
        return getattr(getattr(self, "_job_run", None), "fraction", None)

"""Auto Build: the lamp's objects follow the design while the designer edits it.

An edit only notes the scene and the time (``design_edited``, called by every design property's update
callback) and makes sure one timer is running; the timer builds, never the callback, so a drag that
changes a value sixty times a second is not sixty builds. The timer builds at most every
``TICK_SECONDS``. A lens whose cuts need more quads than a preview has
(``design.parts.PREVIEW_CUT_QUADS``: a deep cut's 190,000 faces take 1-4 s, its preview 0.03-0.25 s)
is built as a preview while the edits go on; once they have stopped for ``SETTLE_SECONDS`` the full
lens is made in a worker thread (``design.parts.make_lenses``, no Blender data touched) and copied
into Blender when it is ready, so the UI does not freeze for it. Every other build is done at once in
full. Only what an edit changed is rebuilt (unchanged meshes are kept), so most edits of the
four-lamp preset take 0.01-0.2 s; ``benchmarks/bench_build.py`` measures them.

Auto Build is on by default: a designer expects the lamp in the viewport to be the lamp in the panel
(an "out of date" lamp that Cycles still renders is the surprise it removes), and it changes only the
add-on's own objects, keeping the designer's edits to them. Scripts are unaffected: timers do not run
while a background script runs, so they build with ``bpy.ops.lamp.build``.

Undo: a build in the timer is no undo step of its own (it belongs to the edit that caused it, and is
saved with the next step). After Undo or Redo restores an earlier design, the timer rebuilds at once
so that the objects match it again (``undo_post``/``redo_post``): Ctrl+Z takes back the design and
the objects together, as after the Build operator.
"""

from __future__ import annotations

import copy
import math
import time
from concurrent.futures import Future, ThreadPoolExecutor

import bpy
from bpy.app.handlers import persistent

from ...core_tracer.scene.reading import SceneError
from . import builder, parts, properties, root

TICK_SECONDS = 0.1
SETTLE_SECONDS = 0.5

_edits: dict[str, float] = {}  # scene name -> time.monotonic() of its last design edit
_jobs: dict[str, tuple[str, Future]] = {}  # scene name -> (design digest, its full lenses being made)
_pool: ThreadPoolExecutor | None = None


def design_edited(bl_scene: bpy.types.Scene) -> None:
    """Schedule a build of ``bl_scene`` (cheap: called on every step of a drag)."""
    design = getattr(bl_scene, "lamp_design", None)
    if design is None or not design.auto_build:
        return
    _schedule(bl_scene.name, time.monotonic())


def pending() -> list[str]:
    """Names of the scenes waiting for a build."""
    return list(_edits)


def _schedule(scene_name: str, edited: float) -> None:
    _edits[scene_name] = edited
    if not bpy.app.timers.is_registered(tick):
        bpy.app.timers.register(tick, first_interval=TICK_SECONDS)


def tick(now: float | None = None) -> float | None:
    """The timer: bring every scene with pending edits up to date, with a preview lens while the edits go
    on, in full once they have stopped. Returns the seconds to the next call, or None when done."""
    now = time.monotonic() if now is None else now
    for name, edited in list(_edits.items()):
        bl_scene = bpy.data.scenes.get(name)
        if bl_scene is None or not bl_scene.lamp_design.auto_build:
            del _edits[name]
            continue
        if _part_being_edited(bl_scene) or bpy.app.is_job_running("RENDER"):
            continue  # a mesh open in Edit Mode, or a render (Compare, F12) reading the objects: wait
        if _step(bl_scene, settled=now - edited >= SETTLE_SECONDS):
            del _edits[name]
    return TICK_SECONDS if _edits else None


def _step(bl_scene: bpy.types.Scene, settled: bool) -> bool:
    """One step toward objects that show the design; True when nothing is left to do."""
    try:
        scene = properties.design_to_scene(bl_scene)
    except SceneError:
        return True  # an invalid design is not built; the panel says why, the next edit tries again
    if not scene["lamps"]:
        return True  # nothing to build (as the Build operator: "Add a lamp first")
    status = builder.build_status(bl_scene, scene)
    if status == builder.UP_TO_DATE:
        return True
    if status != builder.PREVIEW and not builder.build_lamp(bl_scene, scene, preview=True).preview:
        return True  # every lens was light: the quick build was the full one
    if not settled:
        return False  # a preview shows this design; the full lenses when the edits stop
    return _full_lenses(bl_scene, scene)


def _full_lenses(bl_scene: bpy.types.Scene, scene: dict) -> bool:
    """Make the full lenses in the worker thread, then build with them; True once built."""
    digest = builder.design_digest(scene)
    job = _jobs.get(bl_scene.name)
    if job is not None and not job[1].done():
        return False
    if job is not None and job[0] == digest:
        del _jobs[bl_scene.name]
        error = job[1].exception()
        if error is not None:  # out of memory, say: keep the preview, say so once, stop trying
            print(f"Lamp Styling: Auto Build could not make the full lens ({error!r}); the preview stays "
                  "until Build Lamp")
            return True
        builder.build_lamp(bl_scene, scene)  # the lenses are made: this copies them into Blender
        return True
    _jobs[bl_scene.name] = (digest, _worker().submit(parts.make_lenses, copy.deepcopy(scene)))
    return False


def _worker() -> ThreadPoolExecutor:
    global _pool
    if _pool is None:
        _pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="lamp-lenses")
    return _pool


def _part_being_edited(bl_scene: bpy.types.Scene) -> bool:
    return any(obj.mode != "OBJECT" for obj in bl_scene.objects if obj.get(root.PART_KEY))


@persistent
def _after_undo(*_args) -> None:
    """Bring the objects in line with the design an undo or redo restored, at full quality."""
    for bl_scene in bpy.data.scenes:
        design = getattr(bl_scene, "lamp_design", None)
        if design is not None and design.auto_build and root.find_root(bl_scene) is not None:
            _schedule(bl_scene.name, -math.inf)


@persistent
def _after_load(*_args) -> None:
    _edits.clear()  # scene names of the file that was open before
    _jobs.clear()


_HANDLERS = (
    (bpy.app.handlers.undo_post, _after_undo),
    (bpy.app.handlers.redo_post, _after_undo),
    (bpy.app.handlers.load_post, _after_load),
)


def register() -> None:
    properties.EDIT_LISTENERS.append(design_edited)
    for handlers, handler in _HANDLERS:
        handlers.append(handler)


def unregister() -> None:
    for handlers, handler in _HANDLERS:
        if handler in handlers:
            handlers.remove(handler)
    if design_edited in properties.EDIT_LISTENERS:
        properties.EDIT_LISTENERS.remove(design_edited)
    if bpy.app.timers.is_registered(tick):
        bpy.app.timers.unregister(tick)
    _edits.clear()
    _jobs.clear()
    global _pool
    if _pool is not None:
        _pool.shutdown(wait=False, cancel_futures=True)  # a lens being made is finished and dropped
        _pool = None

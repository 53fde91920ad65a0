# SPDX-License-Identifier: GPL-3.0-or-later
"""The Light Panel: switch the design's functions on and off and change bulb fluxes without rendering
(``core_tracer.measures.states``; Speos calls its version the Light Panel).

``Render Light States`` walks the design once, keeping the light of its surroundings and of each lamp
apart (``core_tracer.measures.states.one_walk``; its bands on the band pool's workers, as F12's; a modal
job on a thread: progress in the status bar, Esc cancels); each state then has a switch and a level (lm for a
photometric bulb, a scale for a paper bulb and the surroundings) whose change re-weights the held
passes into the "Lamp Light Panel" image at once (the time shows in the panel). The passes live in
memory for this session, keyed by scene; a change to the design makes them stale, which the panel
says in one line. Nothing here changes the design, except ``Apply to Design`` (undoable).
"""

from __future__ import annotations

import json
import threading
import time

import bpy
import numpy as np
from bpy.props import BoolProperty, CollectionProperty, FloatProperty, StringProperty

from ...core_tracer.images import glare
from ...core_tracer.raytrace import band_pool
from ...core_tracer.scene.reading import SceneError
from .. import image_view, jobs, reports
from ..design import properties as design_properties
from ..design.panels import ClosedSection
from ..render import photometric_display
from ..scene_settings import SceneSettings

IMAGE_NAME = "Lamp Light Panel"
_held: dict[str, dict] = {}  # scene name -> {"key": design JSON, "light": LightStates, "display", "ms"}


def _design_key(bl_scene) -> str:
    return json.dumps(design_properties.design_document(bl_scene), sort_keys=True)


def held(bl_scene) -> dict | None:
    """The passes held for ``bl_scene`` (None when none)."""
    return _held.get(bl_scene.name)


def stale(bl_scene) -> bool:
    entry = held(bl_scene)
    return entry is not None and entry["key"] != _design_key(bl_scene)


def _changed(self, context) -> None:
    if context is not None and context.scene is not None:
        refresh(context.scene)


class LAMP_PG_light_state(bpy.types.PropertyGroup):
    key: StringProperty(options=set())
    label: StringProperty(options=set())
    unit: StringProperty(options=set())
    on: BoolProperty(name="On", default=True, update=_changed, options=set(),
                     description="Whether this light is on in the Light Panel's image (the design is not changed)")
    level: FloatProperty(name="Level", default=1.0, min=0.0, max=1.0e5, soft_max=2000.0, update=_changed,
                         options=set(),
                         description="The bulb's luminous flux in lm (photometric), or a scale of its brightness "
                                     "(paper bulbs and the surroundings)")


class LAMP_PG_light_panel(SceneSettings, bpy.types.PropertyGroup):
    scene_attribute = "lamp_light_panel"
    scene_name = "Lamp Light Panel"
    scene_description = "Lighting states re-weighted without rendering"

    states: CollectionProperty(type=LAMP_PG_light_state)


def _weights(bl_scene, light) -> dict[str, float]:
    from ...core_tracer.measures import states as S

    items = {item.key: item for item in bl_scene.lamp_light_panel.states}
    on = {key: item.on for key, item in items.items()}
    level = {key: item.level for key, item in items.items()}
    return S.weights_for(light, on, level)


def refresh(bl_scene) -> float | None:
    """Re-weight the held passes into the Light Panel's image; returns the milliseconds it took (None
    when there is nothing current to re-weight)."""
    from ...core_tracer.measures import states as S

    entry = held(bl_scene)
    if entry is None or stale(bl_scene):
        return None
    start = time.perf_counter()
    light = entry["light"]
    rgb = S.relight(light, _weights(bl_scene, light), entry["buffer"])
    if entry["display"] is not None:
        rgb = entry["display"].linear(rgb)
    rgb = glare.apply(rgb, light.scene)
    image_view.show_as_render(IMAGE_NAME, rgb)
    entry["ms"] = 1000.0 * (time.perf_counter() - start)
    return entry["ms"]


def hold(bl_scene, light, design_key: str) -> None:
    """Keep ``light`` as the scene's passes, fill the panel's switches from its states, show it."""
    scene = light.scene
    display = photometric_display.for_scene(scene)
    _held[bl_scene.name] = {"key": design_key, "light": light, "display": display,
                            "buffer": np.empty_like(light.surroundings), "ms": None}
    items = bl_scene.lamp_light_panel.states
    items.clear()
    for state in light.states:
        item = items.add()
        item.key, item.label, item.unit = state.key, state.label, state.unit
        item["on"] = state.lit_in_design  # no update per item: one refresh below
        item["level"] = state.rendered
    refresh(bl_scene)


def forget_all() -> None:
    _held.clear()


class StatesRun:
    """``render_states`` (one walk, its bands on the band pool as F12's) on a thread, with its progress
    and a stop."""

    def __init__(self, scene: dict):
        self.scene = scene
        self.fraction = 0.0
        self.stage = "starting"
        self.result = None
        self.error: str | None = None
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._work, name="lamp-light-states", daemon=True)

    def _work(self) -> None:
        from ...core_tracer.measures import states as S
        from ...core_tracer.raytrace.engine import RenderCancelled

        def progress(done: int, total: int, label: str) -> None:
            self.fraction, self.stage = done / total, label

        try:
            self.result = S.render_states(self.scene, progress=progress, should_stop=self._stop.is_set,
                                          pool=band_pool.shared())
        except RenderCancelled:
            self.error = "cancelled"
        except SceneError as e:
            self.error = str(e)
        except MemoryError:
            self.error = "out of memory; allowed a smaller image (Camera & Image › Width, Height)"

    def start(self) -> None:
        self._thread.start()

    def done(self) -> bool:
        return not self._thread.is_alive()

    def cancel(self) -> None:
        self._stop.set()
        self._thread.join()


def _finish(operator, context, run: StatesRun, design_key: str, seconds: float) -> set[str]:
    if run.error is not None:
        return reports.cancelled(operator, f"Light states not rendered: {run.error}")
    hold(context.scene, run.result, design_key)
    entry = held(context.scene)
    image = bpy.data.images.get(IMAGE_NAME)
    if image is not None and context.window is not None:
        image_view.show_image(context, image)
    return reports.finished(operator, f"{len(run.result.states) - 1} light states in {seconds:.0f} s; switch them in "
                                      f"the Light Panel ({entry['ms']:.0f} ms a change)")


class LAMP_OT_light_states_render(jobs.ModalJob, bpy.types.Operator):
    """Render the design once, keeping the light of each bulb and filament (and of its surroundings) apart,
    so that the Light Panel switches functions and changes fluxes without rendering"""

    bl_idname = "lamp.light_states_render"
    bl_label = "Render Light States"

    busy_message = "Light states are being rendered (Esc cancels them)"
    cancelled_message = "Light states cancelled"
    settings = "lamp_light_panel"

    @classmethod
    def refusal(cls, context):
        return None if context.scene.lamp_design.lamps else "Add a lamp first"

    def _run(self, context) -> StatesRun:
        from ..freeform import geometry as freeform_geometry
        from .ops import measured_scene

        # the states switch the parametric lamps' bulbs (the command line relights an exported pair)
        freeform_geometry.refuse_parts("measured", "states")
        self._key = _design_key(context.scene)
        return StatesRun(measured_scene(context.scene))

    def execute(self, context):
        try:
            run = self._run(context)
        except SceneError as e:
            return reports.cancelled(self, str(e))
        start = time.perf_counter()
        run.start()
        run._thread.join()
        return _finish(self, context, run, self._key, time.perf_counter() - start)

    def invoke(self, context, event):
        if bpy.app.background or context.window is None:
            return self.execute(context)
        try:
            self._states = self._run(context)
        except SceneError as e:
            return reports.cancelled(self, str(e))
        self._start = time.perf_counter()
        self._states.start()
        return self.begin_modal(context, self._states)

    def step(self, context):
        if not self._states.done():
            return None
        self.end_modal(context)
        return _finish(self, context, self._states, self._key, time.perf_counter() - self._start)

    def abandon(self, context):
        self._states.cancel()

    def status(self) -> str:
        return f"Light states: {self._states.stage}, {100 * self._states.fraction:.0f}% (Esc to cancel)"


class LAMP_OT_light_states_apply(bpy.types.Operator):
    """Set the design's bulbs as the Light Panel has them: which lamps are on, which filament of a two-filament
    bulb, a bulb's flux (photometric) or brightness (paper)"""

    bl_idname = "lamp.light_states_apply"
    bl_label = "Apply to Design"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        if context.scene is None or held(context.scene) is None or stale(context.scene):
            cls.poll_message_set("Render the light states of this design first")
            return False
        return True

    def execute(self, context):
        light = held(context.scene)["light"]
        items = {item.key: item for item in context.scene.lamp_light_panel.states}
        changed = []  # what was kept another way, said in the report's one line
        for i, lamp in enumerate(context.scene.lamp_design.lamps):
            lit = [s for s in light.states if s.lamp == i and items[s.key].on]
            lamp.bulb.on = bool(lit)
            if lit:
                changed += _apply_bulb(lamp.bulb, lit, {s.key: items[s.key].level for s in lit})
        surroundings = items.get("surroundings")
        lost = []
        if surroundings is not None and not surroundings.on:
            lost.append("the surroundings off")
        elif surroundings is not None and abs(surroundings.level - 1.0) > 1e-9:
            lost.append(f"the surroundings x{surroundings.level:g}")
        text = "Applied the Light Panel's bulbs to the design"
        if changed:
            text += f"; {len(changed)} made Custom to keep {'its' if len(changed) == 1 else 'their'} level"
        if lost:
            text += f"; not kept: {', '.join(lost)}"
        more = changed + ([f"Not kept: {', '.join(lost)}; the Light panel sets the sun, sky and street light"]
                          if lost else [])
        return reports.finished(self, text, more)  # the one line last, what it counts in the Info editor


def _apply_bulb(bulb, lit: list, level: dict[str, float]) -> list[str]:
    """Set one lamp's ``bulb`` (its properties) to its lit states ``lit`` at ``level`` (state key ->
    lm or scale), keeping every level: a named bulb (P21/5W) whose filaments' levels are not the
    type's own, or with both filaments on, becomes a Custom bulb of the type's spectrum and the
    levels' sum (its light is linear in the flux: the same image). Returns what it changed beyond
    the switch, in words."""
    state = lit[0]
    if state.unit == "":  # paper: a scale of the bulb's intensity
        if abs(level[state.key] - 1.0) > 1e-9:
            bulb.intensity = [v * level[state.key] for v in bulb.intensity]
        return []
    if state.filament == "on" and bulb.type == "custom":  # a photometric custom bulb: its flux
        bulb.flux_lm = level[state.key]
        return []
    if len(lit) == 1 and abs(level[state.key] - state.rendered) <= 1e-6 * state.rendered:
        if state.filament in ("stop", "tail"):
            bulb.state = state.filament
        return []
    from ...core_tracer.photometry.sources import BULB_TYPES

    kind = BULB_TYPES[bulb.type]
    flux = sum(level.values())
    bulb.type = "custom"
    bulb.spectrum, bulb.flux_lm = kind.spectrum, flux
    filaments = " and ".join(f"{s.filament} {level[s.key]:g} lm" for s in lit)
    return [f"{state.label.split(' · ')[0]}: a Custom {kind.spectrum.replace('_', ' ')} bulb of {flux:g} lm "
            f"({filaments}; a {kind.name}'s flux is its filament's)"]


class LAMP_PT_light_panel(ClosedSection, bpy.types.Panel):
    bl_label = "Light Panel"
    bl_order = 23

    def draw(self, context):
        layout = self.layout
        layout.operator("lamp.light_states_render", icon="LIGHT")
        entry = held(context.scene)
        if entry is None:
            layout.label(text="Render the light states to switch lamps without rendering", icon="INFO")
            return
        if stale(context.scene):
            layout.label(text="The design changed since its light states: render them again", icon="ERROR")
            return
        col = layout.column(align=True)
        for item in context.scene.lamp_light_panel.states:
            row = col.row(align=True)
            row.prop(item, "on", text="")
            row.label(text=item.label)
            sub = row.row(align=True)
            sub.active = item.on
            sub.prop(item, "level", text="lm" if item.unit else "×")
        if entry["ms"] is not None:
            layout.label(text=f"Re-weighted in {entry['ms']:.0f} ms (image \"{IMAGE_NAME}\")")
        layout.operator("lamp.light_states_apply", icon="CHECKMARK")


@bpy.app.handlers.persistent  # kept across file loads, which it is for
def _forget_on_load(*_args) -> None:
    forget_all()


classes = (LAMP_PG_light_state, LAMP_PG_light_panel, LAMP_OT_light_states_render, LAMP_OT_light_states_apply,
           LAMP_PT_light_panel)

_register_classes, _unregister_classes = bpy.utils.register_classes_factory(classes)


def register() -> None:
    _register_classes()
    if _forget_on_load not in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.append(_forget_on_load)


def unregister() -> None:
    if _forget_on_load in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.remove(_forget_on_load)
    forget_all()
    _unregister_classes()

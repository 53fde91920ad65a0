"""Lighting states without re-rendering (issue 23 item 5; Speos calls its version the Light Panel).

Radiance is linear in each source. A design is rendered once with every bulb off (the *surroundings*:
sun, sky or environment, ambient, phantom light, the reflector's appearance constant of the paper mode)
and once per *state* with only that source lit: each lamp's bulb, and each filament of a two-filament
bulb (P21/5W, PY21/5W: tail and stop) on its own. A state's pass is its render minus the
surroundings', so that

    image = w₀ · surroundings + Σ_s w_s · pass_s

with w = 1 for what the design itself has lit reproduces the design's render, and switching a function
on or off or changing a bulb's flux is a weighted sum of arrays (``relight``: milliseconds at 512²)
instead of a render. A filament's weight is its flux over the flux it was rendered with (photometric),
or a scale of the bulb's intensity (paper). Both filaments of a P21/5W lit (tail and stop at once)
is their sum, as in the bulb.

What the passes keep fixed: every render uses the same rays (the seed, the samples, the pixel filter);
the tracer's cut-off is on a branch's attenuation, not its brightness, so it is the same in every
render; its adaptive sampling is off here (``ADAPTIVE_OFF``) because it chooses pixels by their
values. Glare is not linear (a threshold): the passes are without it, and a re-weighted image gets
glare, when the design has it on, after the sum (``images.glare``).

The file (``save``/``load``) is an .npz of float32 arrays with a JSON header: the scene rendered, the
states and their labels, the light model and bands, and the size.
"""

from __future__ import annotations

import copy
import io
import json
import zipfile
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..scene.led_array import LedArray, uses_leds
from ..scene.reading import SceneError

SURROUNDINGS = "surroundings"
FORMAT = "lamp-light-states/1"
ADAPTIVE_OFF = 0.0  # adaptive_threshold of render_passes: every pixel gets the scene's samples


@dataclass(frozen=True)
class State:
    """One source that can be switched and dimmed: a lamp's bulb (or one filament of it), or the
    surroundings. ``key``: ``lamps[0].stop``, ``lamps[1].on``, ``surroundings``."""

    key: str
    label: str
    lamp: int | None  # None: the surroundings
    filament: str  # "stop", "tail", "on" (a single-filament or custom bulb), "" (surroundings)
    rendered: float  # the flux (lm, photometric) or intensity scale (paper, 1) the pass was rendered with
    unit: str  # "lm" or "" (a scale)
    lit_in_design: bool  # whether the design itself has it lit


def _lamp_name(scene: dict, i: int) -> str:
    function = scene["lamps"][i].get("function", "")
    return f"Lamp {i + 1}" + (f" ({function.replace('_', ' ').title()})" if function not in ("", "custom") else "")


def states_of(scene: dict) -> list[State]:
    """The switchable sources of a normalised scene, the surroundings first."""
    photometric = scene.get("light_model", "paper") == "photometric"
    out = [State(SURROUNDINGS, "Surroundings (sun, sky, street light)", None, "", 1.0, "", True)]
    for i, lamp in enumerate(scene["lamps"]):
        bulb = lamp["bulb"]
        if uses_leds(lamp):  # the dies, switched by the lamp's bulb.on
            leds = LedArray.of(lamp["led"])
            rendered = float(lamp["led"]["flux_lm"]) * leds.count if photometric else 1.0
            out.append(State(f"lamps[{i}].on", f"{_lamp_name(scene, i)} · {leds.count} LEDs", i, "on", rendered,
                             "lm" if photometric else "", bool(bulb["on"])))
        elif photometric and bulb.get("type", "custom") != "custom":
            from ..photometry.sources import BULB_TYPES

            kind = BULB_TYPES[bulb["type"]]
            for filament, state in kind.states.items():
                label = f"{_lamp_name(scene, i)} · {bulb['type']} {filament}"
                out.append(State(f"lamps[{i}].{filament}", label, i, filament, state.flux_lm, "lm",
                                 bool(bulb["on"]) and bulb["state"] == filament))
        else:
            rendered = float(bulb["flux_lm"]) if photometric else 1.0
            out.append(State(f"lamps[{i}].on", f"{_lamp_name(scene, i)} · bulb", i, "on", rendered,
                             "lm" if photometric else "", bool(bulb["on"])))
    return out


def scene_for(scene: dict, state: State | None) -> dict:
    """The scene with only ``state`` lit (None: every bulb off), glare off."""
    out = copy.deepcopy(scene)
    out["glare"]["on"] = False
    for i, lamp in enumerate(out["lamps"]):
        bulb = lamp["bulb"]
        bulb["on"] = state is not None and state.lamp == i
        if bulb["on"] and state.filament in ("stop", "tail"):
            bulb["state"] = state.filament
    return out


@dataclass
class LightStates:
    """The passes of a design's sources and what they were rendered from."""

    scene: dict  # the scene as given (its own lit states are the default weights)
    states: list[State]
    surroundings: np.ndarray  # (H, W, 3) float32: everything with every bulb off
    passes: dict[str, np.ndarray]  # key -> (H, W, 3) float32: the light that state adds
    stats: dict  # light_model, bands

    def default_weights(self) -> dict[str, float]:
        return {s.key: 1.0 if s.lit_in_design else 0.0 for s in self.states}

    def state(self, key: str) -> State:
        for s in self.states:
            if s.key == key:
                return s
        raise SceneError(key, f"not a state of this design; allowed {', '.join(s.key for s in self.states)}")


def render_states(scene: dict, *, progress: Callable[[int, int, str], None] | None = None,
                  should_stop: Callable[[], bool] | None = None, threads: int | None = None) -> LightStates:
    """Render the surroundings and one pass per state of a normalised scene (parametric designs;
    ``freeform`` is refused in one line). ``progress(done, total, label)`` before each render."""
    from ..raytrace.engine import render_passes

    if "freeform" in scene:
        raise SceneError("freeform", "light states are for parametric designs so far; allowed a scene without "
                                     "a freeform section")
    states = states_of(scene)
    total = len(states)

    def one(state: State | None, k: int):
        if progress is not None:
            progress(k, total, state.label if state is not None else states[0].label)
        return render_passes(scene_for(scene, state), keep_passes=False, should_stop=should_stop,
                             threads=threads, adaptive_threshold=ADAPTIVE_OFF)

    base = one(None, 0)
    surroundings = base.image.astype(np.float32)
    passes = {}
    for k, state in enumerate(states[1:], start=1):
        lit = one(state, k).image.astype(np.float32)
        passes[state.key] = lit - surroundings
    stats = {"light_model": base.stats.get("light_model", "paper"), "bands": base.stats.get("bands")}
    return LightStates(copy.deepcopy(scene), states, surroundings, passes, stats)


def weights_for(light: LightStates, on: dict[str, bool] | None = None,
                level: dict[str, float] | None = None) -> dict[str, float]:
    """Each state's weight: the design's own lit states unless ``on`` says otherwise, times the
    level's ratio to what the pass was rendered with (``level``: lm for photometric bulbs, a scale
    for paper bulbs and the surroundings). Raises ``SceneError`` naming the state."""
    weights = light.default_weights()
    for key, value in (on or {}).items():
        light.state(key)
        weights[key] = 1.0 if value else 0.0
    for key, value in (level or {}).items():
        state = light.state(key)
        if not (np.isfinite(value) and 0.0 <= value <= 1.0e5):
            raise SceneError(key, f"{value} is out of range; allowed [0, 100000]{' lm' if state.unit else ''}")
        if weights[key] == 0.0 and key not in (on or {}):
            weights[key] = 1.0  # giving a level switches the state on
        weights[key] *= value / state.rendered if state.rendered > 0 else 0.0
    return weights


def relight(light: LightStates, weights: dict[str, float], out: np.ndarray | None = None) -> np.ndarray:
    """The image under ``weights`` (``weights_for``): a weighted sum of the passes, float32,
    written into ``out`` when given (no allocation: the Light Panel's redraw)."""
    if out is None:
        out = np.empty_like(light.surroundings)
    np.multiply(light.surroundings, np.float32(weights.get(SURROUNDINGS, 1.0)), out=out)
    for key, data in light.passes.items():
        w = weights.get(key, 0.0)
        if w:
            out += np.float32(w) * data if w != 1.0 else data
    return out


def with_glare(light: LightStates, image: np.ndarray) -> np.ndarray:
    """The design's glare on a re-weighted image (a threshold: after the sum), when it has glare on."""
    if not light.scene["glare"]["on"]:
        return image
    from ..images import glare

    return glare.apply(image, light.scene)


# ---------------------------------------------------------------------------------------------
# The file


def to_bytes(light: LightStates) -> bytes:
    header = {
        "format": FORMAT,
        "scene": light.scene,
        "stats": light.stats,
        "states": [s.__dict__ for s in light.states],
    }
    buffer = io.BytesIO()
    arrays = {"surroundings": light.surroundings, **{f"pass_{i}": light.passes[s.key]
                                                     for i, s in enumerate(light.states[1:])}}
    np.savez_compressed(buffer, header=np.frombuffer(json.dumps(header).encode("utf-8"), np.uint8), **arrays)
    return buffer.getvalue()


MAX_HEADER = 10_000_000


def from_bytes(data: bytes, name: str = "light states") -> LightStates:
    """Read a file ``to_bytes`` wrote; anything else raises ``SceneError`` naming it."""
    try:
        with np.load(io.BytesIO(data), allow_pickle=False) as npz:
            raw = npz["header"]
            if raw.dtype != np.uint8 or raw.size > MAX_HEADER:
                raise ValueError("bad header")
            header = json.loads(raw.tobytes().decode("utf-8"))
            if header.get("format") != FORMAT:
                raise ValueError("not a light-states file")
            states = [State(**s) for s in header["states"]]
            surroundings = npz["surroundings"]
            passes = {s.key: npz[f"pass_{i}"] for i, s in enumerate(states[1:])}
    except (OSError, ValueError, KeyError, TypeError, zipfile.BadZipFile, json.JSONDecodeError, UnicodeDecodeError):
        raise SceneError(name, f"is not a light-states file of this version; allowed a file written by "
                               f"'states' ({FORMAT})") from None
    shape = surroundings.shape
    if surroundings.dtype != np.float32 or len(shape) != 3 or shape[2] != 3 or \
            any(p.shape != shape or p.dtype != np.float32 for p in passes.values()):
        raise SceneError(name, "holds arrays of different shapes; allowed a file written by 'states'")
    return LightStates(header["scene"], states, surroundings, passes, header["stats"])

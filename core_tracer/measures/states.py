"""Lighting states without re-rendering (issue 23 item 5; Speos calls its version the Light Panel).

Radiance is linear in each source. A design is walked once with every bulb lit, each path's light
kept per source as it is added (``raytrace.engine.rays.BySource``): the *surroundings* (sun, sky or
environment, ambient, phantom light, the reflector's appearance constant of the paper mode) and each
lamp's bulb or LED dies. A *state* is a lamp's bulb, or each filament of a two-filament bulb (P21/5W,
PY21/5W: tail and stop) on its own; the filaments of one bulb share its sphere and spectrum, so a
filament's pass is the lamp's light times its flux over the flux walked (L ∝ Φ, L = Φ / (4π² r²)):

    pass_s = (Φ_s / Φ_walked) · L_lamp(s),   image = w₀ · surroundings + Σ_s w_s · pass_s

with w = 1 for what the design itself has lit reproduces the design's render, and switching a function
on or off or changing a bulb's flux is a weighted sum of arrays (``relight``: milliseconds at 512²)
instead of a render. A filament's weight is its flux over the flux it was rendered with (photometric),
or a scale of the bulb's intensity (paper). Both filaments of a P21/5W lit (tail and stop at once)
is their sum, as in the bulb.

A state's image equals a direct render of that state: the same rays (the seed, the samples, the
pixel filter) whose light is added in another order; the tracer's cut-off is on a branch's
attenuation, not its brightness, so it is the same whatever is lit; its adaptive sampling is off here
(``ADAPTIVE_OFF``) because it chooses pixels by their values (a direct render would choose others). A
free-form design (its own tracer) is still rendered once with every bulb off and once per state, its
pass that render minus the surroundings'. Glare is not linear (a threshold): the passes are without it,
and a re-weighted image gets glare, when the design has it on, after the sum (``images.glare``).

The file (``save``/``load``) is an .npz of float32 arrays with a JSON header: the scene rendered, the
states and their labels, the light model and bands, and the size.
"""

from __future__ import annotations

import copy
import dataclasses
import io
import json
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..scene.derived import lens_absorption
from ..scene.led_array import LedArray, die_count, uses_leds
from ..scene.messages import show_value
from ..scene.reading import SceneError

if TYPE_CHECKING:
    from ..freeform.design import DesignMeshes
    from ..raytrace.engine.schedule import BandsElsewhere

SURROUNDINGS = "surroundings"
FORMAT = "lamp-light-states/1"
ADAPTIVE_OFF = 0.0  # adaptive_threshold of render_passes: every pixel gets the scene's samples


@dataclass(frozen=True)
class State:
    """One source that can be switched and dimmed: a lamp's bulb (or one filament of it), or the
    surroundings. ``key``: the lamp's function, as a designer names it (``stop``, ``turn``,
    ``tail.stop_filament``: the other filament of a tail lamp's two-filament bulb; ``stop2``: the second
    stop lamp; ``lamp3``: a lamp with no function), or ``surroundings``. ``alias``: the key files
    written before had (``lamps[0].stop``, ``lamps[1].on``), still accepted."""

    key: str
    label: str
    lamp: int | None  # None: the surroundings
    filament: str  # "stop", "tail", "on" (a single-filament or custom bulb), "" (surroundings)
    rendered: float  # the flux (lm, photometric) or intensity scale (paper, 1) the pass was rendered with
    unit: str  # "lm" or "" (a scale)
    lit_in_design: bool  # whether the design itself has it lit
    alias: str = ""


# A paper lens's colour, seen through its thickness (linear RGB): clear when its weakest channel is at
# least half its strongest, amber when green is at least this share of red (the four-lamp preset's
# amber 0.13, its red 0.012), else red.
_AMBER_GREEN_SHARE = 0.05
# A red paper lamp whose bulb is at most this bright (the sum of its RGB intensity) is a tail lamp:
# the tail function's 8/7/6 (21) against the stop's 20/17.5/15 (``scene.functions``).
_TAIL_INTENSITY = 21.0


def _paper_function(lamp: dict) -> str:
    """What a "custom" lamp of a paper design is for, from its lens colour and bulb (as
    ``report.lamp_function`` says it from the filter and filament of a photometric one)."""
    t = lamp["lens"]["thickness"]
    red, green, blue = (math.exp(-a * t) for a in lens_absorption(lamp["lens"]))
    if min(red, green, blue) >= 0.5 * max(red, green, blue):
        return "reversing"
    if green >= _AMBER_GREEN_SHARE * red:
        return "turn"
    return "tail" if sum(lamp["bulb"]["intensity"]) <= _TAIL_INTENSITY else "stop"


def _function_of(scene: dict, lamp: dict) -> str | None:
    """What ``lamp`` is for: its ``function``; for a "custom" lamp, the one its lens and bulb say
    (photometric: ``report.lamp_function``, the measures' own rule, so a state and a report row
    agree; paper: ``_paper_function``). None for a function with no name here."""
    declared = lamp.get("function", "custom")
    if declared != "custom":
        return declared
    if scene.get("light_model", "paper") != "photometric":
        return _paper_function(lamp)
    from .report import lamp_function

    return lamp_function(lamp)


def lamp_names(scene: dict) -> list[tuple[str, str | None]]:
    """``(key, words)`` of each lamp by its function: ``("turn", "Turn")``; lamps sharing a function
    numbered (``stop1``, ``stop2``: "Stop 1", "Stop 2"); ``("lamp2", None)`` for a lamp with none."""
    functions = [_function_of(scene, lamp) for lamp in scene["lamps"]]
    out: list[tuple[str, str | None]] = []
    for i, function in enumerate(functions):
        if function is None:
            out.append((f"lamp{i + 1}", None))
            continue
        same = [j for j, f in enumerate(functions) if f == function]
        number = f"{same.index(i) + 1}" if len(same) > 1 else ""
        words = function.replace("_", " ").capitalize()
        out.append((f"{function}{number}", f"{words} {number}".strip()))
    return out


def sources(scene: dict) -> list[tuple[str, str, dict]]:
    """The bulbs of a normalised scene that can be switched, as (key prefix, name, bulb section): the
    lamps' bulbs, or a free-form design's bulb parts (its lamps are not traced). A ``State``'s
    ``lamp`` is an index into this list."""
    if "freeform" in scene:
        return [(f"freeform.parts[{i}]", part["object"], part["bulb"])
                for i, part in enumerate(scene["freeform"]["parts"]) if part["role"] == "bulb"]
    return [(f"lamps[{i}]", f"Lamp {i + 1}", lamp["bulb"]) for i, lamp in enumerate(scene["lamps"])]


def states_of(scene: dict) -> list[State]:
    """The switchable sources of a normalised scene, the surroundings first. A two-filament bulb's
    filament that makes the lamp's function (the tail filament of a tail lamp, the stop filament of
    any other) is the state named by the function; the other filament is named after it."""
    photometric = scene.get("light_model", "paper") == "photometric"
    out = [State(SURROUNDINGS, "Surroundings (sun, sky, street light)", None, "", 1.0, "", True)]
    if "freeform" in scene:  # its bulb parts, by the part: its lamps are not traced
        for i, (prefix, name, bulb) in enumerate(sources(scene)):
            if photometric and bulb.get("type", "custom") != "custom":
                from ..photometry.sources import BULB_TYPES

                for filament, state in BULB_TYPES[bulb["type"]].states.items():
                    out.append(State(f"{prefix}.{filament}", f"{name} · {bulb['type']} {filament}", i, filament,
                                     state.flux_lm, "lm", bool(bulb["on"]) and bulb["state"] == filament))
            else:
                rendered = float(bulb["flux_lm"]) if photometric else 1.0
                out.append(State(f"{prefix}.on", f"{name} · bulb", i, "on", rendered, "lm" if photometric else "",
                                 bool(bulb["on"])))
        return out
    for i, ((name, words), lamp) in enumerate(zip(lamp_names(scene), scene["lamps"], strict=True)):
        bulb = lamp["bulb"]
        leds = LedArray.of(lamp["led"]) if uses_leds(lamp) else None  # the dies, switched by bulb.on
        named = photometric and leds is None and bulb.get("type", "custom") != "custom"
        where = f"lamp {i + 1}" + (f", {bulb['type']}" if named else "") + (f", {die_count(lamp)} LEDs" if leds else "")
        label = f"{words} ({where})" if words else where[:1].upper() + where[1:]
        if named:
            from ..photometry.sources import BULB_TYPES

            kind = BULB_TYPES[bulb["type"]]
            own = "tail" if name.startswith("tail") and "tail" in kind.states else next(iter(kind.states))
            for filament, state in sorted(kind.states.items(), key=lambda item: item[0] != own):
                key = name if filament == own else f"{name}.{filament}_filament"
                out.append(State(key, label if filament == own else f"{label} · {filament} filament", i, filament,
                                 state.flux_lm, "lm", bool(bulb["on"]) and bulb["state"] == filament,
                                 f"lamps[{i}].{filament}"))
        else:
            flux = float(lamp["led"]["flux_lm"]) * die_count(lamp) if leds is not None else float(bulb["flux_lm"])
            rendered = flux if photometric else 1.0
            out.append(State(name, label, i, "on", rendered, "lm" if photometric else "", bool(bulb["on"]),
                             f"lamps[{i}].on"))
    return out


def lit_scene(scene: dict) -> dict:
    """The scene walked for the states (``render_states``): every bulb lit, each in its own filament
    state, glare off."""
    out = copy.deepcopy(scene)
    out["glare"]["on"] = False
    for _prefix, _name, bulb in sources(out):
        bulb["on"] = True
    return out


def walked_level(scene: dict, states: list[State], lamp: int) -> float:
    """What lamp ``lamp``'s light was walked with in ``lit_scene``: the flux (photometric) or scale
    (paper) of its state whose filament the bulb is in (a single-filament bulb's only state)."""
    bulb = sources(scene)[lamp][2]
    own = [s for s in states if s.lamp == lamp and s.filament in (bulb.get("state"), "on")]
    return (own or [s for s in states if s.lamp == lamp])[0].rendered


def scene_for(scene: dict, state: State | None) -> dict:
    """The scene with only ``state`` lit (None: every bulb off), glare off."""
    out = copy.deepcopy(scene)
    out["glare"]["on"] = False
    for i, (_prefix, _name, bulb) in enumerate(sources(out)):
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
        """The state of ``key``, or of the key files written before gave it (``lamps[0].stop``)."""
        for s in self.states:
            if key in (s.key, s.alias):
                return s
        raise SceneError(key, f"not a state of this design; allowed {', '.join(s.key for s in self.states)}")


def render_states(scene: dict, *, progress: Callable[[int, int, str], None] | None = None,
                  should_stop: Callable[[], bool] | None = None, threads: int | None = None,
                  meshes: DesignMeshes | None = None, recorded: dict | None = None,
                  pool: BandsElsewhere | None = None) -> LightStates:
    """The surroundings and one pass per state of a normalised scene: a parametric design's from one
    walk (``one_walk``), a free-form design's on its ``meshes`` by a render per state (its bulb parts
    the states). ``progress(done, total, label)`` as the work goes on (the walk's percent done of
    100, or the renders done). ``recorded`` is the scene the file keeps, when ``scene`` is traced with full paths
    (its curves). ``pool`` (``band_pool.shared()``) traces the walk's bands as a render's."""
    if "freeform" in scene and meshes is None:
        raise SceneError("freeform", "the design's meshes were not given; allowed a free-form design loaded with "
                                     "its .glb")
    if meshes is None:
        return one_walk(scene, progress=progress, should_stop=should_stop, threads=threads, recorded=recorded,
                        pool=pool)
    states = states_of(scene)
    total = len(states)

    def one(state: State | None, k: int):
        if progress is not None:
            progress(k, total, state.label if state is not None else states[0].label)
        # every sample of every pixel, as the free-form tracer always traces
        return meshes.render_passes(scene_for(scene, state), should_stop=should_stop, threads=threads)

    base = one(None, 0)
    surroundings = base.image.astype(np.float32)
    passes = {}
    for k, state in enumerate(states[1:], start=1):
        lit = one(state, k).image.astype(np.float32)
        passes[state.key] = lit - surroundings
    stats = {"light_model": base.stats.get("light_model", "paper"), "bands": base.stats.get("bands"),
             "band_edges_nm": base.stats.get("band_edges_nm")}
    return LightStates(copy.deepcopy(scene if recorded is None else recorded), states, surroundings, passes, stats)


def one_walk(scene: dict, *, progress: Callable[[int, int, str], None] | None = None,
             should_stop: Callable[[], bool] | None = None, threads: int | None = None,
             recorded: dict | None = None, pool: BandsElsewhere | None = None) -> LightStates:
    """``render_states`` of a parametric design: one walk of ``lit_scene`` keeping each source's light
    (``render_passes(by_source=True)``); each state's pass its lamp's light times Φ_s / Φ_walked."""
    from ..raytrace.engine import render_passes

    states = states_of(scene)
    label = f"{len(states) - 1} states and the surroundings"

    def walked(fraction: float) -> None:
        if progress is not None:
            progress(min(99, int(100 * fraction)), 100, label)

    walked(0.0)
    result = render_passes(lit_scene(scene), keep_passes=True, by_source=True, should_stop=should_stop,
                           threads=threads, adaptive_threshold=ADAPTIVE_OFF, progress=walked, pool=pool)
    passes = {}
    for state in states[1:]:
        light = result.passes[f"lamp{state.lamp}"]
        walked_with = walked_level(scene, states, state.lamp)
        if state.rendered == walked_with:
            passes[state.key] = light
        else:  # the bulb's other filament: L ∝ Φ
            ratio = state.rendered / walked_with if walked_with > 0 else 0.0
            passes[state.key] = light * np.float32(ratio)
    stats = {"light_model": result.stats.get("light_model", "paper"), "bands": result.stats.get("bands"),
             "band_edges_nm": result.stats.get("band_edges_nm")}
    return LightStates(copy.deepcopy(scene if recorded is None else recorded), states, result.passes["surroundings"],
                       passes, stats)


def weights_for(light: LightStates, on: dict[str, bool] | None = None,
                level: dict[str, float] | None = None) -> dict[str, float]:
    """Each state's weight: the design's own lit states unless ``on`` says otherwise, times the
    level's ratio to what the pass was rendered with (``level``: lm for photometric bulbs, a scale
    for paper bulbs and the surroundings). Raises ``SceneError`` naming the state."""
    weights = light.default_weights()
    switched = set()
    for key, value in (on or {}).items():
        state = light.state(key)
        weights[state.key] = 1.0 if value else 0.0
        switched.add(state.key)
    for key, value in (level or {}).items():
        state = light.state(key)
        if not (np.isfinite(value) and 0.0 <= value <= 1.0e5):
            raise SceneError(key, f"{value} is out of range; allowed [0, 100000]{' lm' if state.unit else ''}")
        if weights[state.key] == 0.0 and state.key not in switched:
            weights[state.key] = 1.0  # giving a level switches the state on
        weights[state.key] *= value / state.rendered if state.rendered > 0 else 0.0
    return weights


def relight(light: LightStates, weights: dict[str, float], out: np.ndarray | None = None) -> np.ndarray:
    """The image under ``weights`` (``weights_for``): a weighted sum of the passes, float32,
    written into ``out`` when given (no allocation: the Light Panel's redraw)."""
    if out is None:
        out = np.empty_like(light.surroundings)
    # An overflow gives inf, which the image writers refuse (imageio._finite): no warning on the way.
    with np.errstate(over="ignore", invalid="ignore"):
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
    """The file's bytes; a pass holding NaN or inf is refused (``SceneError``), never written."""
    for key, data in (("surroundings", light.surroundings), *light.passes.items()):
        if not np.isfinite(data).all():
            raise SceneError(key, "the render holds values that are not finite numbers; allowed finite images "
                                  "only (nothing was written)")
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
_NOT_OURS = f"allowed a file written by 'states' ({FORMAT})"


def file_bytes(width: int, height: int, count: int) -> int:
    """The inflated size of a light-states file's arrays: the surroundings and ``count`` passes."""
    return (count + 1) * width * height * 3 * 4


def from_bytes(data: bytes, name: str = "light states", *,
               beside: Callable[[dict], int] | None = None) -> LightStates:
    """Read a file ``to_bytes`` wrote, trusting nothing in it (issue 33): the zip directory's sizes are
    counted before anything is inflated (the arrays and ``beside(scene)``, the bytes the caller needs
    with them, at most the memory budget),
    the header's scene is validated again and its states must be the ones that scene has, and each
    array must be float32 of the scene's image size, finite. Anything else raises ``SceneError``
    naming the file and what is wrong."""
    from .. import arrays, budget
    from ..scene.validate import parse_scene

    limit = budget.MEMORY_BUDGET - budget.BASE_BYTES

    def bad(why: str) -> SceneError:
        return SceneError(name, f"is not a light-states file of this version ({why}); {_NOT_OURS}")

    try:
        sizes = arrays.npz_sizes(data, max_members=2 + 64, max_total=MAX_HEADER + limit)
        if "header" not in sizes or sizes["header"] > MAX_HEADER + arrays.MAX_NPY_HEADER:
            raise bad("it has no header, or one too large to be ours")
        raw = arrays.read_npz_member(data, "header", sizes["header"], dtype=np.uint8, shape=(None,))
        header = json.loads(raw.tobytes().decode("utf-8"))
    except arrays.BadArray as e:
        raise bad(f"{e}") from None
    except (ValueError, UnicodeDecodeError, RecursionError):
        raise bad("its header is not JSON") from None
    if not isinstance(header, dict) or header.get("format") != FORMAT:
        raise bad("its header names another format")
    try:
        scene = parse_scene(header.get("scene"))
    except SceneError as e:
        raise SceneError(name, f"its scene is not valid ({e.path}: {e.message}); {_NOT_OURS}") from None
    if "freeform" in scene:
        raise bad("its scene is a free-form design")
    states = _check_states(header.get("states"), states_of(scene), bad)
    stats = _checked_stats(header.get("stats"), scene, bad)
    width, height = scene["image"]["width"], scene["image"]["height"]
    expected = {"header", "surroundings", *(f"pass_{i}" for i in range(len(states) - 1))}
    if set(sizes) != expected:
        raise bad(f"it holds arrays {', '.join(sorted(set(sizes) ^ expected))} that its states do not match")
    need = budget.BASE_BYTES + file_bytes(width, height, len(states) - 1) + (beside(scene) if beside else 0)
    if need > budget.MEMORY_BUDGET:
        raise SceneError(name, f"its {len(states)} images of {width}x{height} px and the work on them need about "
                               f"{budget.gib(need)} of memory; allowed at most {budget.gib(budget.MEMORY_BUDGET)}")
    shape = (height, width, 3)
    try:
        surroundings = arrays.read_npz_member(data, "surroundings", sizes["surroundings"], dtype=np.float32,
                                              shape=shape)
        passes = {s.key: arrays.read_npz_member(data, f"pass_{i}", sizes[f"pass_{i}"], dtype=np.float32, shape=shape)
                  for i, s in enumerate(states[1:])}
    except arrays.BadArray as e:
        raise bad(f"{e}") from None
    return LightStates(scene, states, surroundings, passes, stats)


def _check_states(given: object, states: list[State], bad: Callable[[str], SceneError]) -> list[State]:
    """The header's states are those of its scene, rendered at the fluxes this version's bulbs have; returns
    them as the file names them (a file written before states were named by function keeps its keys,
    ``lamps[0].stop``, which are this version's aliases)."""
    if not isinstance(given, list) or len(given) != len(states):
        raise bad(f"its states do not match its scene's {len(states)} sources")
    earlier = all(isinstance(found, dict) and found.get("key") == (state.alias or state.key) and "alias" not in found
                  for found, state in zip(given, states, strict=True))
    if earlier:
        states = [dataclasses.replace(state, key=state.alias or state.key, alias="") for state in states]
    for found, state in zip(given, states, strict=True):
        if not isinstance(found, dict) or found.get("key") != state.key:
            raise bad(f"its states do not match its scene's sources (expected {state.key})")
        rendered = found.get("rendered")
        if type(rendered) not in (int, float) or abs(rendered) > 1e300 or \
                not math.isclose(rendered, state.rendered, rel_tol=1e-9):
            raise bad(f"state {state.key} was rendered at {show_value(rendered)}, not the {state.rendered:g} "
                      "this version renders")
    return states


def _checked_stats(given: object, scene: dict, bad: Callable[[str], SceneError]) -> dict:
    from ..photometry.bands import MAX_BANDS, Bands

    model = scene.get("light_model", "paper")
    if not isinstance(given, dict) or given.get("light_model") != model:
        raise bad(f"its stats do not say the scene's light model ({model})")
    bands = given.get("bands")
    if model != "photometric":
        return {"light_model": model, "bands": None, "band_edges_nm": None}
    if not (type(bands) is int and 1 <= bands <= MAX_BANDS):
        raise bad(f"its stats give {show_value(bands)} bands; allowed 1 to {MAX_BANDS}")
    # the bands' edges, nm (``raytrace.spectral_bands``); a file written before the scene chose its
    # bands has none: its K bands were uniform
    edges = given.get("band_edges_nm")
    if edges is None:
        edges = Bands.uniform(bands).edges_nm.tolist()
    if not (isinstance(edges, list) and len(edges) == bands + 1
            and all(type(e) in (int, float) and math.isfinite(e) for e in edges)
            and all(a < b for a, b in zip(edges, edges[1:], strict=False))):
        raise bad(f"its stats give band edges {show_value(edges)[:60]}; allowed {bands + 1} increasing wavelengths")
    return {"light_model": model, "bands": bands, "band_edges_nm": [float(e) for e in edges]}

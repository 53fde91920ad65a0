"""What a lamp is for (``lamps[].function``): the lens colour, bulb brightness and part names that
go with it.

Choosing a function is a starting point, not a constraint: it sets the fields below, and the
designer may change any of them afterwards. A lamp whose function is "custom" is set by hand.
The colours follow the automotive signal colours (red for tail, stop and rear fog, amber for
turn, white for reversing and position) as transmitted colours seen through the lens's own
thickness; a stop, turn or rear fog lamp is brighter than a tail lamp (by the four-lamp preset's
ratio, 2.5) and a position lamp dimmer. The red, amber and clear values and the tail, stop and
reversing bulbs are those of the four-lamp preset.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, field

from . import spec as S
from .derived import use_form


@dataclass(frozen=True)
class Lens:
    """A signal colour: its name and the lens fields that give it."""

    colour: str
    fields: dict = field(default_factory=dict)


_RED = Lens("red", {"transmitted_color": [0.94, 0.011, 0.008], "diffuse_color": [0.05, 0.0, 0.0],
                    "side_wall_color": [0.05, 0.02, 0.02]})
_AMBER = Lens("amber", {"transmitted_color": [0.92, 0.12, 0.005], "diffuse_color": [0.05, 0.02, 0.0],
                        "side_wall_color": [0.05, 0.02, 0.02]})
_CLEAR = Lens("clear", {"transmitted_color": [0.97, 0.97, 0.97], "diffuse_color": [0.03, 0.03, 0.03],
                        "side_wall_color": [0.03, 0.03, 0.03]})
_DIM, _BRIGHT, _WHITE = [8.0, 7.0, 6.0], [20.0, 17.5, 15.0], [8.0, 8.0, 8.0]

# function -> (lens, bulb intensity)
DEFAULTS: dict[str, tuple[Lens, list[float]]] = {
    "tail": (_RED, _DIM),
    "stop": (_RED, _BRIGHT),
    "turn": (_AMBER, _BRIGHT),
    "reversing": (_CLEAR, _WHITE),
    "position": (_CLEAR, [4.0, 4.0, 4.0]),
    "fog": (_RED, _BRIGHT),
}
assert set(DEFAULTS) | {"custom"} == set(S.LAMP_FUNCTIONS)


def describe(function: str) -> str:
    """What choosing ``function`` sets, in words ("Red lens, bulb intensity 20/17.5/15"), for a tooltip."""
    if function not in DEFAULTS:
        return "Set the lens colour and the bulb yourself"
    lens, intensity = DEFAULTS[function]
    return f"{lens.colour.capitalize()} lens, bulb intensity {'/'.join(f'{x:g}' for x in intensity)}"


def apply_function(lamp: dict, function: str) -> None:
    """Set ``function`` and its defaults on a normalised lamp (in place): the lens colour as a
    transmitted colour seen through the lens's thickness, its surface colours, the bulb's
    intensity. "custom" changes nothing but the function."""
    lamp["function"] = function
    if function not in DEFAULTS:
        return
    look, intensity = DEFAULTS[function]
    lens = lamp["lens"]
    use_form(lens, S.LENS, "transmitted_color")
    lens.update(copy.deepcopy(look.fields))
    lens["reference_thickness"] = lens["thickness"]
    lamp["bulb"]["intensity"] = list(intensity)


def lamp_label(lamps: list[dict], index: int) -> str:
    """The name a lamp's parts carry ("Stop" in "Stop Lens"): its function, numbered when two
    lamps share it; "Lamp 2" for a custom lamp."""
    function = lamps[index].get("function", "custom")
    if function == "custom":
        return f"Lamp {index + 1}"
    same = [i for i, lamp in enumerate(lamps) if lamp.get("function", "custom") == function]
    name = function.capitalize()
    return name if len(same) == 1 else f"{name} {same.index(index) + 1}"


def suggested_values(path: str) -> list:
    """The values the lamp functions give the lamp field ``path`` (``lens.transmitted_color``,
    ``bulb.intensity``), each once in function order: a study's first guess for a vector."""
    part, _, key = path.partition(".")
    out: list = []
    for look, intensity in DEFAULTS.values():
        value = look.fields.get(key) if part == "lens" else intensity if path == "bulb.intensity" else None
        if value is not None and value not in out:
            out.append(list(value))
    return out

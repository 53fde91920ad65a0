"""A design's measures by name: one number each from a ``measures.json`` (``report.Measures.as_dict``).

A name is ``<group>.<figure>``, optionally ``@<function>`` (tail, stop, turn, reversing) for that
function alone; without it the design's worst function counts (the lowest of a figure where higher
is better, the highest where lower is better). A figure a design does not have (no lit lens, no such
function) is NaN.

- ``homogeneity.lmin_lmax``, ``homogeneity.lmin_lmean`` (higher is better), ``homogeneity.cv``,
  ``homogeneity.dark_fraction`` (lower is better): the lit lens from H-V (``homogeneity``);
- ``grid.min_margin``: the smallest margin of every regulation row, as a fraction of its limit
  (negative where a point fails); ``grid.pass``: 1 if every row passes, else 0; ``grid.failed``:
  the number of failed rows;
- ``intensity.hv_cd``: the luminous intensity at H-V in cd;
- ``colour.distance_outside``: 0 inside the function's UN R48 §2.29 region, else the xy distance to
  its nearest edge.

Studies put these under the cells of a contact sheet and sort and filter by them; an optimiser can
score by the same names.
"""

from __future__ import annotations

import math
from collections.abc import Callable

from ..scene.reading import SceneError
from ..scene.safe_text import show_key
from .functions import FUNCTIONS

# The functions' names: checking a name imports no numpy (a study file is checked before anything heavy loads).
FUNCTION_NAMES = tuple(FUNCTIONS)


def _rows(measured: dict, function: str | None) -> list[dict]:
    if function is None:
        return measured["rows"]
    keys = set(FUNCTIONS[function][:2])
    if function in ("stop", "tail"):
        keys |= {"R148 stop/position 5:1", "FMVSS stop/taillamp"}
    return [r for r in measured["rows"] if r["function"] in keys]


def _homogeneity(figure: str) -> Callable[[dict, str], float]:
    return lambda measured, function: measured["homogeneity"].get(function, {}).get(figure, math.nan)


def _hv_cd(measured: dict, function: str) -> float:
    for h, v, cd, _err in measured["intensities_cd"].get(function, ()):
        if h == 0 and v == 0:
            return cd
    return math.nan


def _colour_distance(measured: dict, function: str) -> float:
    from . import colour

    found = measured["functions"].get(function, {}).get("colour")
    if not found:
        return math.nan
    return colour.distance_outside(found["xy"], colour.REGIONS["UN R48 §2.29"][found["required"]])


def _finite(values) -> list[float]:
    return [v for v in values if v is not None and math.isfinite(v)]


# name -> (per function value, True when higher is better, unit)
_PER_FUNCTION: dict[str, tuple[Callable[[dict, str], float], bool, str]] = {
    "homogeneity.lmin_lmax": (_homogeneity("lmin_over_lmax"), True, ""),
    "homogeneity.lmin_lmean": (_homogeneity("lmin_over_lmean"), True, ""),
    "homogeneity.cv": (_homogeneity("cv"), False, ""),
    "homogeneity.dark_fraction": (_homogeneity("dark_fraction"), False, ""),
    "intensity.hv_cd": (_hv_cd, True, "cd"),
    "colour.distance_outside": (_colour_distance, False, ""),
}
# name -> (value of the rows, unit): the grid's figures, from the rows of one function or all
_OF_ROWS: dict[str, tuple[Callable[[list[dict]], float], str]] = {
    "grid.min_margin": (lambda rows: min(_finite(r["margin"] for r in rows), default=math.nan), ""),
    "grid.pass": (lambda rows: float(all(r["passed"] for r in rows)) if rows else math.nan, ""),
    "grid.failed": (lambda rows: float(sum(not r["passed"] for r in rows)), ""),
}
NAMES: tuple[str, ...] = tuple(sorted((*_PER_FUNCTION, *_OF_ROWS)))


def allowed_text() -> str:
    return (f"allowed {', '.join(NAMES)}, each optionally followed by @function "
            f"({', '.join(FUNCTION_NAMES)})")


def check_name(name, where: str) -> str:
    """``name`` if it names a measure, else a ``SceneError`` at ``where`` listing the allowed names."""
    base, _, function = str(name).partition("@")
    if not isinstance(name, str) or base not in NAMES or (function and function not in FUNCTION_NAMES):
        raise SceneError(where, f"{show_key(str(name))} is not a measure; {allowed_text()}")
    return name


def unit(name: str) -> str:
    base = name.partition("@")[0]
    return _PER_FUNCTION[base][2] if base in _PER_FUNCTION else _OF_ROWS[base][1]


def value(measured: dict, name: str) -> float:
    """The figure ``name`` (checked with ``check_name``) of ``measured`` (a measures.json dict)."""
    base, _, function = name.partition("@")
    if base in _OF_ROWS:
        return _OF_ROWS[base][0](_rows(measured, function or None))
    of_function, higher_better, _unit = _PER_FUNCTION[base]
    functions = [function] if function else list(measured["functions"])
    values = _finite(of_function(measured, f) for f in functions)
    if not values:
        return math.nan
    return min(values) if higher_better else max(values)


def values(measured: dict, names) -> dict[str, float]:
    return {name: value(measured, name) for name in names}

"""The regulation grid: a lamp function's test points and limits (``data/regulation_data.json``, every
value cited to its document, table and page) checked against simulated intensities.

A homologation laboratory's measurement of a built lamp decides approval; this is the check of a
design before one exists. The directions are the regulations' (H, V) (``directions``).

What each rule means (the data file's ``functions``):

- UN R148 (01 series): the minimum at H-V ("Reference axis", §4.8.3.1 (a)); at every point of the
  function's Annex 3 figure at least the H-V minimum times the percentage, "rounded down to three
  significant digits" (§4.8.3.1 (c), Annex 3 §1.1 as amended by Supplement 6), or the figure's own cd
  for the reversing lamp; the maximum "in no direction where the lamp is visible" (§4.8.3.1 (b)),
  checked here over every direction measured (the grid and the field sweep the caller measured); a
  variable-intensity category (R2, S2, S4, 2b) is also held to its steady category's maximum at
  night (§4.8.3.4.2). Not checked: the fields of geometric visibility (Annex 2) and the rule between
  grid points (Annex 3 §1.2).
- FMVSS 108: each test point of the 19-point grid (Tables VII-IX) or of Table XII, in groups.
  "floor-60" (Tables VII, IX): every point at least 60 % of its minimum, and a point under its
  minimum passes only if its group's sum meets the group's minimum; "group-alternative" (Tables VIII,
  XII): a point under its minimum passes if its group's sum meets the group's minimum. Maxima as
  printed per point, or over the test point range. SAE J585 (tail), J586 (stop) and J588 (turn) are
  the SAE texts these tables came from; their texts were not found, so FMVSS 108's own tables stand
  for them here.
- Ratios: R148 §4.8.3.5, stop and position lit together over position alone at least 5:1 within
  ±10° H and ±5° V, where the position lamp is reciprocally incorporated with the stop lamp; FMVSS
  108 Table IX, the stop lamp at least 3× or 5× the taillamp it is optically combined with, point by
  point.

``Row`` is one line of the verdict: the point, what is required, the simulated value and its
standard error, the margin (the share by which the value clears the limit; negative fails) and the
verdict.
"""

from __future__ import annotations

import functools
import json
import math
from collections.abc import Callable, Mapping
from dataclasses import asdict, dataclass
from importlib import resources

Direction = tuple[float, float]
Measured = Mapping[Direction, tuple[float, float]]  # (H, V) -> (cd, standard error)

FIELD_SWEEP = [(float(h), float(v)) for h in range(-20, 25, 5) for v in range(-10, 15, 5)]  # for the maxima


@functools.cache
def data() -> dict:
    """The regulation tables (``data/regulation_data.json``)."""
    with resources.files(__package__).joinpath("data", "regulation_data.json").open(encoding="utf-8") as f:
        return json.load(f)


def function_keys() -> list[str]:
    return list(data()["functions"])


def function(key: str) -> dict:
    functions = data()["functions"]
    if key not in functions:
        raise ValueError(f"regulation function: {key!r} is not one of {', '.join(functions)}")
    return functions[key]


def citation(key: str) -> str:
    """'document, table' of a function's (or a ratio's) values."""
    entry = data()["functions"].get(key) or data()["ratios"][key]
    return f"{data()['sources'][entry['source']]['document']}; {entry['cite']}"


def round_down_3(x: float) -> float:
    """``x`` rounded down to three significant digits (R148 Annex 3 §1.1, Supplement 6)."""
    if x <= 0:
        return x
    step = 10.0 ** (math.floor(math.log10(x)) - 2)
    return math.floor(x / step + 1e-9) * step


def test_points(key: str) -> list[tuple[str, float, float, float]]:
    """(point id, H, V, minimum cd) of a function's grid."""
    f = function(key)
    if "points" in f:
        return [(p["id"], float(p["h"]), float(p["v"]), float(p["min"])) for p in f["points"]]
    grid = data()["grids"][f["grid"]]
    out = []
    for h, v, value in grid["points"]:
        minimum = value if grid["unit"] == "cd" else round_down_3(f["min_hv"] * value / 100.0)
        out.append((_point_name(h, v), float(h), float(v), float(minimum)))
    return out


def directions_for(key: str) -> list[Direction]:
    """Every direction the check of ``key`` reads: its test points and, for its maxima, the field sweep."""
    seen = dict.fromkeys((h, v) for _, h, v, _ in test_points(key))
    seen.update(dict.fromkeys(FIELD_SWEEP))
    return list(seen)


def _point_name(h: float, v: float) -> str:
    """"5U-10L" in FMVSS's way of naming (U/D, L/R; H and V for 0)."""
    vert = "H" if v == 0 else f"{abs(v):g}{'U' if v > 0 else 'D'}"
    horiz = "V" if h == 0 else f"{abs(h):g}{'R' if h > 0 else 'L'}"
    return f"{vert}-{horiz}"


@dataclass(frozen=True)
class Row:
    function: str
    point: str
    h: float | None
    v: float | None
    kind: str  # "min", "max", "group min", "ratio"
    required: float
    simulated: float
    stderr: float
    margin: float  # (simulated − required)/required for a minimum, (required − simulated)/required for a maximum
    passed: bool
    note: str = ""

    @property
    def uncertain(self) -> bool:
        """Within two standard errors of the limit: the verdict could turn with more samples."""
        return abs(self.simulated - self.required) < 2.0 * self.stderr

    def as_dict(self) -> dict:
        return {**asdict(self), "uncertain": self.uncertain}


def _min_row(key, point, h, v, required, value, err, passed=None, note="") -> Row:
    margin = (value - required) / required if required > 0 else math.inf
    return Row(key, point, h, v, "min", required, value, err, margin,
               value >= required if passed is None else passed, note)


def _max_row(key, point, h, v, required, value, err, note="") -> Row:
    return Row(key, point, h, v, "max", required, value, err, (required - value) / required, value <= required, note)


def check(key: str, measured: Measured | Callable[[float, float], tuple[float, float]], *,
          night: bool = False) -> list[Row]:
    """Every limit of function ``key`` against the intensities ``measured`` ((H, V) → (cd, standard
    error), or a callable of (H, V)); ``night``: a variable-intensity category at night."""
    value = measured if callable(measured) else (lambda h, v: measured[(h, v)])
    f = function(key)
    if "rule" in f:
        return _check_fmvss(key, f, value, measured)
    rows = []
    for point, h, v, minimum in test_points(key):
        cd, err = value(h, v)
        rows.append(_min_row(key, point, h, v, minimum, cd, err))
    for name, limit, zone in _maxima(f, night):
        worst = max(((d, value(*d)) for d in _measured_directions(measured, key) if zone(*d)),
                    key=lambda item: item[1][0], default=None)
        if worst is not None:
            (h, v), (cd, err) = worst
            rows.append(_max_row(key, _point_name(h, v), h, v, limit, cd, err, name))
    return rows


def _maxima(f: dict, night: bool) -> list[tuple[str, float, Callable[[float, float], bool]]]:
    """(what, limit, the directions it holds in) of a UN function's maxima; a zone of the reversing
    lamp's Table 10 holds for v_from ≤ V < v_to."""
    if "max_zones" in f:
        return [(z["cite"], float(z["max"]), functools.partial(_in_band, float(z["v_from"]), float(z["v_to"])))
                for z in f["max_zones"]]
    limit = float(f["max_night"] if night and "max_night" in f else f["max"])
    return [("maximum in every direction measured", limit, lambda h, v: True)]


def _in_band(v_from: float, v_to: float, h: float, v: float) -> bool:
    return v_from <= v < v_to


def _measured_directions(measured, key: str) -> list[Direction]:
    if callable(measured):
        return directions_for(key)
    return list(measured)


def _check_fmvss(key: str, f: dict, value, measured) -> list[Row]:
    points = f["points"]
    values = {p["id"]: value(float(p["h"]), float(p["v"])) for p in points}
    group_ok, group_rows = {}, []
    for g, group_min in enumerate(f["groups"], start=1):
        members = [p for p in points if p["group"] == g]
        total = sum(values[p["id"]][0] for p in members)
        err = math.sqrt(sum(values[p["id"]][1] ** 2 for p in members))
        group_ok[g] = total >= group_min
        group_rows.append(Row(key, f"group {g}", None, None, "group min", float(group_min), total, err,
                              (total - group_min) / group_min, group_ok[g], "sum of the group's points"))
    rows = []
    for p in points:
        cd, err = values[p["id"]]
        h, v, minimum = float(p["h"]), float(p["v"]), float(p["min"])
        if f["rule"] == "floor-60":
            passed = cd >= minimum or (cd >= 0.6 * minimum and group_ok[p["group"]])
            note = "at least 60 % of the minimum, and the minimum or the group's sum"
        else:
            passed = cd >= minimum or group_ok[p["group"]]
            note = "the minimum, or the group's sum"
        rows.append(_min_row(key, p["id"], h, v, minimum, cd, err, passed, note))
        if "max" in p:
            rows.append(_max_row(key, p["id"], h, v, float(p["max"]), cd, err))
    rows.extend(group_rows)
    if "max" in f:  # over the test point range, 20° L to 20° R, 10° U to 10° D
        inside = [d for d in _measured_directions(measured, key) if abs(d[0]) <= 20 and abs(d[1]) <= 10]
        worst = max(((d, value(*d)) for d in inside), key=lambda item: item[1][0], default=None)
        if worst is not None:
            (h, v), (cd, err) = worst
            rows.append(_max_row(key, _point_name(h, v), h, v, float(f["max"]), cd, err, "over the test point range"))
    return rows


def check_ratio(key: str, stop: Measured | Callable, position: Measured | Callable) -> list[Row]:
    """A ratio rule of the data file's ``ratios``: R148's 5:1 of (stop + position) over position, or
    FMVSS 108's stop over taillamp, at every direction of its zone measured in both."""
    rule = data()["ratios"][key]
    stop_at = stop if callable(stop) else (lambda h, v: stop[(h, v)])
    position_at = position if callable(position) else (lambda h, v: position[(h, v)])
    if "points" in rule:
        points = [(name, float(h), float(v), float(factor)) for name, h, v, factor in rule["points"]]
    else:
        zone = (FIELD_SWEEP if callable(stop) else list(stop))
        points = [(_point_name(h, v), h, v, float(rule["factor"])) for h, v in zone
                  if abs(h) <= rule["h_within"] and abs(v) <= rule["v_within"]]
    rows = []
    for name, h, v, factor in points:
        s, s_err = stop_at(h, v)
        p, p_err = position_at(h, v)
        combined = s + p if "points" not in rule else s
        ratio = combined / p if p > 0 else math.inf
        err = ratio * math.hypot(s_err / max(combined, 1e-30), p_err / max(p, 1e-30)) if p > 0 else 0.0
        rows.append(Row(key, name, h, v, "ratio", factor, ratio, err, (ratio - factor) / factor, ratio >= factor,
                        rule["text"]))
    return rows


def verdict(rows: list[Row]) -> bool:
    return all(r.passed for r in rows)

"""The measures as a table a panel shows: a summary line first, then one row per check.

From a ``measures.json`` dict (``report.Measures.as_dict``). The summary gives each function's
verdict on its UN R148 grid and FMVSS 108 together, and for a failing one its worst point:
"Stop: pass · Reversing: fails AR at H-V 773 cd > 300 cd".
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .functions import FUNCTIONS

RATIOS = {"R148 stop/position 5:1": "stop", "FMVSS stop/taillamp": "stop"}


@dataclass(frozen=True)
class Line:
    """One row of the table: function, test point / measure, required, simulated, margin, pass."""

    function: str
    point: str
    required: str
    simulated: str
    margin: str
    passed: bool | None  # None for a figure without a limit (homogeneity)


def _function_of(key: str) -> str:
    for name, keys in FUNCTIONS.items():
        if key in keys[:2]:
            return name
    return RATIOS.get(key, key)


def _short(key: str) -> str:
    """"R148 AR" -> "AR"; "FMVSS backup" stays."""
    return key.removeprefix("R148 ")


def _cd(value: float) -> str:
    return f"{value:.3g}" if abs(value) < 100 else f"{value:.0f}"


def describe_failure(row: dict) -> str:
    """"AR at H-V 773 cd > 300 cd" for a failed row."""
    sign = ">" if row["kind"] == "max" else "<"
    unit = "" if row["kind"] == "ratio" else " cd"
    return (f"{_short(row['function'])} at {row['point']} {_cd(row['simulated'])}{unit} {sign} "
            f"{_cd(row['required'])}{unit}")


def summary(measured: dict) -> str:
    """One line: each function's verdict, a failing one with its worst point."""
    parts = []
    for name in measured["functions"]:
        rows = [r for r in measured["rows"] if _function_of(r["function"]) == name]
        failed = [r for r in rows if not r["passed"]]
        if not failed:
            parts.append(f"{name.capitalize()}: pass")
            continue
        worst = min(failed, key=lambda r: (not r["function"].startswith("R148"), r["margin"]))
        more = f" (+{len(failed) - 1} more)" if len(failed) > 1 else ""
        parts.append(f"{name.capitalize()}: fails {describe_failure(worst)}{more}")
    colours = [n for n, f in measured["functions"].items()
               if f.get("colour") and not all(f["colour"]["inside"].values())]
    if colours:
        parts.append("colour outside: " + ", ".join(colours))
    return " · ".join(parts) if parts else "No lit function to measure"


def lines(measured: dict) -> list[Line]:
    """Every regulation row, failed rows of a function first, then the homogeneity figures (no limit:
    ``passed`` None) and the colours."""
    out = []
    for r in sorted(measured["rows"], key=lambda r: (_function_of(r["function"]), r["passed"])):
        unit = "" if r["kind"] == "ratio" else " cd"
        margin = r["margin"]
        kind = "min" if r["kind"] == "group min" else r["kind"]  # "group 1 min", not "group 1 group min"
        out.append(Line(_function_of(r["function"]), f"{_short(r['function'])} {r['point']} {kind}",
                        f"{_cd(r['required'])}{unit}", f"{_cd(r['simulated'])}{unit}",
                        f"{100 * margin:+.0f} %" if margin is not None and math.isfinite(margin) else "—",
                        bool(r["passed"])))
    for name, h in measured["homogeneity"].items():
        out.append(Line(name, "Lmin/Lmax (lit lens)", "—", f"{h['lmin_over_lmax']:.2f}", "—", None))
    for name, f in measured["functions"].items():
        c = f.get("colour")
        if c:
            ok = all(c["inside"].values())
            out.append(Line(name, f"colour xy ({c['required']})", "inside", f"{c['xy'][0]:.3f}, {c['xy'][1]:.3f}",
                            "—", ok))
    return out

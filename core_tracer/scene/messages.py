"""How the scene's messages show values: a JSON value quoted, a value's kind in words, numbers
rounded so that the value shown is allowed, intervals rounded inward. Every ``SceneError`` that
quotes a value or a range says it through these, so that all messages read alike."""

from __future__ import annotations

import json
import math
from typing import Any

from .reading import HugeNumber
from .safe_text import printable


def kind_of(v: Any) -> str:
    """What a JSON value is, in words (``an object``, ``a list`` …), for messages."""
    return {dict: "an object", list: "a list", str: "a string", bool: "a boolean",
            type(None): "null"}.get(type(v), "a number" if isinstance(v, (int, float)) else type(v).__name__)


def show_value(v: Any) -> str:
    """A value as a message quotes it: JSON, escaped, at most 60 characters."""
    if isinstance(v, HugeNumber):
        return v.shown()
    if isinstance(v, int) and not isinstance(v, bool) and abs(v) >= 10**60:
        try:
            return f"a number of {len(str(abs(v)))} digits"
        except ValueError:  # str() refuses more than 4300 digits
            return "a number of more than 4300 digits"
    try:
        text = json.dumps(v, allow_nan=True)
    except (TypeError, ValueError, RecursionError):
        text = kind_of(v)
    return printable(text, 60)


def interval(lo: float, hi: float) -> str:
    """``[lo, hi]`` with both ends rounded inward to 4 significant digits (so the values shown are
    allowed), or to 12 when the interval is too narrow for that."""
    a, b = rounded(lo, True), rounded(hi, False)
    return f"[{a}, {b}]" if float(a) <= float(b) else f"[{lo:.12g}, {hi:.12g}]"


def rounded(x: float, up: bool) -> str:
    """``x`` to 4 significant digits, rounded up or down so that the value shown is allowed."""
    if x == 0:
        return "0"
    step = 10.0 ** (math.floor(math.log10(abs(x))) - 3)
    return f"{(math.ceil(x / step) if up else math.floor(x / step)) * step:.4g}"


def lens_size(lens: dict) -> str:
    """The lens's size in words, for messages."""
    if lens.get("outline", "round") == "round":
        return f"lens radius {lens['radius']:g} mm"
    return f"lens {lens['width']:g} x {lens['height']:g} mm"


def leaves(doc: Any, path: str = "") -> dict[str, Any]:
    """A design's leaf values by the path a message names them with (``lamps[0].lens.radius``)."""
    if isinstance(doc, dict):
        out: dict[str, Any] = {}
        for key, value in doc.items():
            out.update(leaves(value, f"{path}.{key}" if path else key))
        return out
    if isinstance(doc, list) and doc and isinstance(doc[0], dict):
        out = {}
        for i, value in enumerate(doc):
            out.update(leaves(value, f"{path}[{i}]"))
        return out
    return {path: doc}

"""The designer's words for the panel: labels and tooltips made from the spec's field declarations.

A tooltip says what the field does first, in the designer's words; field names written in a spec's
text (``sun_color``) are said as the panel shows them ("Sun Color"); the paper's symbol or equation
comes last ("Paper: w in eq. 1"); the allowed range is said in words ("from 0 to 1", "more than 0,
up to 100 mm"), not in interval notation. A few labels are the designer's words rather than the
key's (``LABELS``): "Light Gathering" for the reflector or prism plate, "Position" for the bulb's
offset from the focus, "Highlight Color" and "Sun Strength" in the Light panel, where the
surroundings have a "Strength" of their own.
"""

from __future__ import annotations

import re

from ...core_tracer.scene import spec as S
from ...core_tracer.scene.field_kinds import _fmt

# (section, key) -> the panel's label (without the unit, which the property name adds).
LABELS = {
    (id(S.LAMP), "collection"): "Light Gathering",
    (id(S.BULB), "offset"): "Position",
    (id(S.LIGHT), "color"): "Highlight Color",
    (id(S.LIGHT), "strength"): "Sun Strength",
    (id(S.ENVIRONMENT), "strength"): "Surroundings Strength",
    (id(S.GLARE), "on"): "Glare",
    (id(S.GLARE), "strength"): "Glare Strength",
    (id(S.LIGHT), "illuminance_lux"): "Sun Illuminance",
    (id(S.ENVIRONMENT), "illuminance_lux"): "Surroundings Illuminance",
    (id(S.ENVIRONMENT), "luminance_cd_m2"): "Surroundings Luminance",
    (id(S.CAMERA), "ev100"): "EV100",
}
# The choices of a field in the designer's words, where the key's words are not.
CHOICE_LABELS = {"collection": {"reflector": "Reflector", "prism_plate": "Prism Plate"},
                 "source": {"bulb": "Bulb", "led": "LEDs"},
                 "distribution": {"lambertian": "Lambertian", "file": "Far-Field File"}}

_SNAKE = re.compile(r"\b[a-z][a-z0-9]*(?:_[a-z0-9]+)+\b")
# A parenthesis that cites the paper: a symbol and an equation or table ("(w in eq. 1)", "(I0 per R, G, B)").
# One level of nested parentheses is allowed inside ("(the (1 - d) cos term of eq. 1)"); a lone short
# symbol ("(h)") is the paper's too.
_INNER = r"(?:[^()]|\([^()]*\))*?"
_PAPER = re.compile(rf"\s*\(({_INNER}(?:\beq\.\s*\d|\bTable\s*\d|\bI0\b|R[01]G[01]B[01]){_INNER}|[A-Za-z]\d?)\)")


def label(section: S.Section, key: str) -> str | None:
    """The designer's label of ``section``'s field ``key``, when it is not the key's own words."""
    return LABELS.get((id(section), key))


def _spoken(name: str) -> str:
    words = name.split("_")
    if words[-1] in ("nm", "mm", "deg", "lm", "lx", "px"):
        words = words[:-1]
    return " ".join(w.capitalize() for w in words)


def designer_text(doc: str) -> str:
    """A spec text in the designer's words: snake_case names as the panel says them, the paper's
    symbols moved to the end."""
    cited = [m.strip() for m in _PAPER.findall(doc)]
    text = _PAPER.sub("", doc)
    text = _SNAKE.sub(lambda m: _spoken(m[0]), text).strip()
    if cited:
        text = text.rstrip(". ") + ". Paper: " + "; ".join(cited)
    return text


def range_words(spec: S.Spec) -> str:
    """The allowed values in words: "from 0 to 1", "more than 0, up to 100 mm", "Reflector or Prism Plate"."""
    if isinstance(spec, S.Num):
        unit = f" {spec.unit}" if spec.unit else ""
        if spec.lo is None and spec.hi is None:
            text = "any number"
        elif spec.hi is None:
            text = f"{'more than' if spec.lo_open else 'at least'} {_fmt(spec.lo)}{unit}"
        elif spec.lo is None:
            text = f"{'less than' if spec.hi_open else 'up to'} {_fmt(spec.hi)}{unit}"
        elif spec.lo_open or spec.hi_open:
            low = f"more than {_fmt(spec.lo)}" if spec.lo_open else f"at least {_fmt(spec.lo)}"
            high = f"less than {_fmt(spec.hi)}" if spec.hi_open else f"up to {_fmt(spec.hi)}"
            text = f"{low}, {high}{unit}"
        else:
            text = f"from {_fmt(spec.lo)} to {_fmt(spec.hi)}{unit}"
        return f"each {text}" if spec.size > 1 else text
    if isinstance(spec, S.Choice):
        names = [_spoken(c) for c in spec.choices]
        return ", ".join(names[:-1]) + f" or {names[-1]}" if len(names) > 1 else names[0]
    if isinstance(spec, S.Text):
        return f"at most {spec.max_len} characters"
    if isinstance(spec, S.Tags):
        return f"at most {spec.max_items} words of at most {spec.max_len} characters"
    return ""


def tooltip(spec: S.Spec) -> str:
    """A property's tooltip: what the field does, then what it allows, then the paper's symbol."""
    text = designer_text(spec.doc) if spec.doc else ""
    body, _, paper = text.partition(". Paper: ")
    allowed = range_words(spec)
    parts = [body.rstrip(". ")] if body else []
    if allowed and not isinstance(spec, S.Flag):
        parts.append(f"Allowed: {allowed}")
    if paper:
        parts.append(f"Paper: {paper}")
    return ". ".join(parts)

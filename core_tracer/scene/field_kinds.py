"""The kinds of field a scene document declares (``spec``): numbers and vectors with their range
and unit, choices, text, tags, flags, sections of fields, lists of sections, and the either/or
rules of a section (``OneOf``). Each kind says its allowed range in words (``range_text``) as
the messages and the field table of docs/scene-format.md print it."""

from __future__ import annotations

import math
from dataclasses import dataclass

# A direction vector shorter than this cannot be normalised reliably (its square underflows).
MIN_DIRECTION_LENGTH = 1e-9


@dataclass(frozen=True)
class Num:
    """A number, or a fixed-size vector of numbers (``size`` > 1)."""

    default: float | tuple[float, ...] | None
    lo: float | None = None
    hi: float | None = None
    lo_open: bool = False
    hi_open: bool = False
    unit: str = ""
    doc: str = ""
    size: int = 1
    integer: bool = False
    nonzero: bool = False  # a direction: length at least MIN_DIRECTION_LENGTH
    subtype: str = ""  # a hint for user interfaces: "color", "rgb" (per-channel numbers, not a colour),
    # "distance", "direction", "xyz"

    def range_text(self) -> str:
        """The allowed range as the error messages and docs/scene-format.md print it."""
        left = "(" if self.lo_open else "["
        right = ")" if self.hi_open else "]"
        lo = "-inf" if self.lo is None else _fmt(self.lo)
        hi = "inf" if self.hi is None else _fmt(self.hi)
        if self.lo is None and self.hi is None:
            text = "any finite number"
        else:
            text = f"{left}{lo}, {hi}{right}"
        if self.unit:
            text += f" {self.unit}"
        if self.size > 1:
            text = f"{self.size} numbers, each {text}"
        if self.nonzero:
            text += f", length at least {_fmt(MIN_DIRECTION_LENGTH)}"
        return text

    def too_short(self, items: list[float]) -> bool:
        """Whether a direction vector is too short to normalise (only for ``nonzero`` fields)."""
        return self.nonzero and math.fsum(x * x for x in items) < MIN_DIRECTION_LENGTH**2


@dataclass(frozen=True)
class Choice:
    default: str
    choices: tuple[str, ...]
    doc: str = ""

    def range_text(self) -> str:
        return "one of " + ", ".join(f'"{c}"' for c in self.choices)


@dataclass(frozen=True)
class Text:
    default: str
    doc: str = ""
    max_len: int = 200

    def range_text(self) -> str:
        return f"a string of at most {self.max_len} characters"


@dataclass(frozen=True)
class Tags:
    doc: str = ""
    max_items: int = 32
    max_len: int = 40

    @property
    def default(self) -> list[str]:
        return []

    def range_text(self) -> str:
        return f"a list of at most {self.max_items} strings of at most {self.max_len} characters"


@dataclass(frozen=True)
class Flag:
    default: bool
    doc: str = ""

    def range_text(self) -> str:
        return "true or false"


@dataclass(frozen=True)
class Alternative:
    """One form of an either/or rule: the fields written in that form.

    The first key selects the form (a document that gives it uses this form); the other keys
    may be left out and then take the value of the field named in ``same_as``, or their
    own default."""

    keys: tuple[str, ...]
    label: str
    doc: str = ""
    same_as: tuple[tuple[str, str], ...] = ()  # (key, field of the section whose value it takes)

    @property
    def name(self) -> str:
        return self.keys[0]


@dataclass(frozen=True)
class OneOf:
    """An either/or rule of a section: exactly one alternative's fields are present.

    ``default`` is the form a document means when it gives none (what earlier versions wrote);
    ``preferred`` is the form an editor starts a new design with."""

    name: str
    alternatives: tuple[Alternative, ...]
    default: str
    preferred: str
    doc: str = ""

    @property
    def keys(self) -> tuple[str, ...]:
        return tuple(k for alt in self.alternatives for k in alt.keys)

    def alternative(self, name: str) -> Alternative:
        return next(alt for alt in self.alternatives if alt.name == name)

    def of_key(self, key: str) -> Alternative | None:
        """The alternative that writes ``key``, or None."""
        return next((alt for alt in self.alternatives if key in alt.keys), None)

    def given(self, data: dict) -> list[Alternative]:
        """The alternatives of which ``data`` holds at least one field."""
        return [alt for alt in self.alternatives if any(k in data for k in alt.keys)]

    def chosen(self, data: dict) -> Alternative:
        """The alternative a normalised section uses."""
        given = self.given(data)
        return given[0] if given else self.alternative(self.default)

    def range_text(self) -> str:
        return "either " + " or ".join(
            alt.keys[0] + (f" (with {', '.join(alt.keys[1:])})" if alt.keys[1:] else "")
            for alt in self.alternatives) + ", never both"


@dataclass(frozen=True)
class Section:
    fields: dict[str, Spec]
    doc: str = ""
    optional: tuple[str, ...] = ()  # keys that have no default and may be absent
    one_of: tuple[OneOf, ...] = ()  # either/or rules; their keys are absent unless their form is used
    # (key, choice key, choice values): a field that means something only when the section's choice
    # field (or flag) holds one of the values (a rectangular lens's width); editors show it only then
    shown_when: tuple[tuple[str, str, tuple[str | bool, ...]], ...] = ()

    def shown(self, key: str, value_of) -> bool:
        """Whether field ``key`` means something for a section whose fields ``value_of(key)`` gives."""
        return all(value_of(choice) in values for k, choice, values in self.shown_when if k == key)

    def may_be_absent(self, key: str) -> bool:
        return key in self.optional or any(key in rule.keys for rule in self.one_of)

    def rule_of(self, key: str) -> OneOf | None:
        """The either/or rule ``key`` belongs to, or None."""
        return next((rule for rule in self.one_of if key in rule.keys), None)


@dataclass(frozen=True)
class ListOf:
    item: Section
    min_items: int
    max_items: int
    doc: str = ""

    def range_text(self) -> str:
        return f"a list of {self.min_items} to {self.max_items} items"


Spec = Num | Choice | Text | Tags | Flag | Section | ListOf


def _fmt(x: float) -> str:
    return f"{x:g}"

"""Measures under the cells of a study: which, how the sheet is sorted and filtered by them.

A ``lamp-study/1`` document may name measures of ``measures.by_name`` (photometric designs only)::

    "measures": ["homogeneity.lmin_lmax", "grid.min_margin"],
    "sort": "-homogeneity.lmin_lmax",              (a name; "-" first: highest first)
    "filter": ["grid.pass==1", "intensity.hv_cd@stop>=60"]

Each variant is measured as ``python -m core_tracer measure`` measures a design
(``measures.report.measure``, tens of seconds a variant: docs/measures.md); its values go under its
cell. A sorted or filtered sheet places the kept cells in that order, row by row; the variants a
filter leaves out are listed in the sheet's footer with their values, never dropped silently.
Without these fields a study is what it always was.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from ..measures import by_name
from ..scene.messages import show_value
from ..scene.reading import SceneError

OPERATORS: dict[str, Callable[[float, float], bool]] = {
    "==": lambda a, b: a == b, "!=": lambda a, b: a != b, ">=": lambda a, b: a >= b,
    "<=": lambda a, b: a <= b, ">": lambda a, b: a > b, "<": lambda a, b: a < b,
}
_FILTER = re.compile(r"^\s*([A-Za-z_.@]+)\s*(==|!=|>=|<=|>|<)\s*([-+0-9.eE]+)\s*$")


@dataclass(frozen=True)
class Filter:
    name: str
    operator: str
    number: float

    def keeps(self, value: float) -> bool:
        return not math.isnan(value) and OPERATORS[self.operator](value, self.number)

    def __str__(self) -> str:
        return f"{self.name}{self.operator}{self.number:g}"


@dataclass(frozen=True)
class Choice:
    """What a study measures and how its sheet is ordered."""

    measures: tuple[str, ...] = ()
    sort: str = ""  # a measure name, "-" first for highest first; "" keeps the study's grid
    filters: tuple[Filter, ...] = ()

    def __bool__(self) -> bool:
        return bool(self.measures or self.sort or self.filters)

    @property
    def reorders(self) -> bool:
        return bool(self.sort or self.filters)

    @property
    def names(self) -> tuple[str, ...]:
        """Every measure the sheet needs, in order: those named, then the sort's, then the filters'."""
        wanted = [*self.measures, self.sort.removeprefix("-")] + [f.name for f in self.filters]
        return tuple(dict.fromkeys(n for n in wanted if n))

    def to_doc(self) -> dict:
        return measured_doc(self.measures, self.sort, self.filters)


def measured_doc(measures: Sequence[str], sort: str, filters: Sequence[Any]) -> dict:
    """A study's measure fields as its document holds them, only those given (``measures``,
    ``sort``, ``filter``: each filter as its text)."""
    doc = {"measures": list(measures or ()), "sort": sort, "filter": [str(f) for f in filters or ()]}
    return {name: value for name, value in doc.items() if value}


def parse_filter(text: Any, where: str) -> Filter:
    found = _FILTER.match(text) if isinstance(text, str) else None
    if found is None:
        raise SceneError(where, f"{show_value(text)} is not MEASURE OPERATOR NUMBER (e.g. \"grid.pass==1\"); allowed "
                                f"operators {' '.join(OPERATORS)} and {by_name.allowed_text()}")
    name, operator, number = found.groups()
    return Filter(by_name.check_name(name, where), operator, parse_number(where, number))


def parse_number(where: str, text: str) -> float:
    """A finite number written as ``text`` (a study's filter, a ``--vary`` value), or a ``SceneError`` at ``where``."""
    try:
        x = float(text)
    except ValueError:
        raise SceneError(where, f"{text.strip()!r} is not a number") from None
    if not math.isfinite(x):
        raise SceneError(where, f"{text.strip()} is not a finite number")
    return x


def parse(doc: dict, base: dict) -> Choice:
    """The ``measures``, ``sort`` and ``filter`` fields of a study document (all optional)."""
    measures = doc.get("measures", [])
    if not isinstance(measures, list) or len(measures) > 8:
        raise SceneError("measures", f"expected a list of at most 8 measure names, got {show_value(measures)}; "
                                     f"{by_name.allowed_text()}")
    names = tuple(by_name.check_name(m, f"measures[{i}]") for i, m in enumerate(measures))
    sort = doc.get("sort", "")
    if sort != "":
        if not isinstance(sort, str):
            raise SceneError("sort", f"expected a measure name, got {show_value(sort)}; {by_name.allowed_text()}")
        try:
            by_name.check_name(sort.removeprefix("-"), "sort")
        except SceneError:
            raise SceneError("sort", f"{show_value(sort)} is not a measure, or \"-\" and one; "
                                     f"{by_name.allowed_text()}") from None
    filters = doc.get("filter", [])
    if isinstance(filters, str):
        filters = [filters]
    if not isinstance(filters, list) or len(filters) > 8:
        raise SceneError("filter", f"expected a list of at most 8 filters, got {show_value(filters)}")
    choice = Choice(names, sort, tuple(parse_filter(f, f"filter[{i}]") for i, f in enumerate(filters)))
    if choice and base.get("light_model", "paper") != "photometric":
        field = "measures" if names else "sort" if sort else "filter"
        raise SceneError(field, "measures need a photometric design; allowed with base.light_model \"photometric\"")
    return choice


def measure_variants(scenes: Sequence[dict], names: Sequence[str],
                     progress: Callable[[int, int], None] | None = None, cache=None) -> list[dict[str, float]]:
    """Each scene's values of ``names``, measured as the ``measure`` command measures a design.

    ``cache``: a ``cluster.cache.CellCache`` (or None): the values are kept there by content (the
    whole variant scene and the names), so a re-run measures only what is new."""
    from ..freeform.traced import by_content, meshes_of
    from ..measures import report

    out = []
    for k, scene in enumerate(scenes):
        if progress is not None:
            progress(k, len(scenes))
        key = measures_key(by_content(scene), names)  # a free-form design's meshes by their bytes
        kept = cache.get_array(key) if cache is not None else None
        if kept is not None and kept.shape == (len(names),):
            out.append(dict(zip(names, (float(v) for v in kept), strict=True)))
            continue
        values = by_name.values(report.measure(scene, meshes=meshes_of(scene)).as_dict(), names)
        if cache is not None:
            import numpy as np

            cache.put_array(key, np.array([values[n] for n in names], dtype=np.float64))
        out.append(values)
    if progress is not None:
        progress(len(scenes), len(scenes))
    return out


MEASURES_KEY_VERSION = "lamp-study-measures/1"  # change it when what a measure computes changes


def measures_key(scene: dict, names: Sequence[str]) -> str:
    """The cache key of a variant's measures: its whole scene (canonical JSON) and the names."""
    import hashlib
    import json

    text = json.dumps([MEASURES_KEY_VERSION, scene, list(names)], sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def arrange(choice: Choice, values: Sequence[dict[str, float]]) -> tuple[list[int], list[int]]:
    """(the variants shown, in sheet order; the variants a filter leaves out, in study order)."""
    kept = [i for i, v in enumerate(values) if all(f.keeps(v[f.name]) for f in choice.filters)]
    dropped = [i for i in range(len(values)) if i not in kept]
    if choice.sort:
        name = choice.sort.removeprefix("-")
        sign = -1.0 if choice.sort.startswith("-") else 1.0
        kept.sort(key=lambda i: (math.isnan(values[i][name]), sign * values[i][name] if not
                                 math.isnan(values[i][name]) else 0.0))
    return kept, dropped


def format_measure(name: str, value: float) -> str:
    """``name=value unit`` (``by_name.unit``: "intensity.hv_cd=121 cd"; ratios have none)."""
    if math.isnan(value):
        return f"{name}=n/a"
    unit = by_name.unit(name)
    return f"{name}={value:.3g}" + (f" {unit}" if unit else "")

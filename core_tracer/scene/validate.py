"""Validating and normalising ``lamp-scene`` documents (read by ``reading``): the walk of the
document against the field declarations (``spec``).

A *scene* is the normalised document: a plain JSON-compatible dict in which every field of
``spec.SCENE`` is present (defaults filled in, the default camera computed), numbers are
floats, vectors are lists. The one exception is the lens colour, kept in the form the designer
gave it: ``absorption`` or ``transmitted_color`` with ``reference_thickness``.

Each field is checked against its own declaration here; the rules that relate several fields
are ``geometry_checks``'s (called once the walk is done). Every problem raises ``SceneError``
whose text names the field, the value and the allowed range, e.g.
``lamps[0].lens.radius: -3 is out of range; allowed (0, 1000] mm``.

A ``lamp-scene/1`` document (what earlier versions wrote) is migrated on load: it is the
``lamp-scene/2`` document with the same fields and no ``freeform`` section, so it renders the same.
"""

from __future__ import annotations

import copy
import math
import os
from typing import Any

from . import spec as S
from .derived import default_camera, default_value, fill_alternative
from .freeform_section import finish_freeform
from .geometry_checks import check_geometry
from .messages import kind_of, show_value
from .photometric_checks import check_photometric
from .reading import HugeNumber, SceneError, read_json
from .safe_text import has_surrogate, printable, show_key


def load_scene(path: str | os.PathLike) -> dict:
    """Read, validate and normalise a scene file."""
    return parse_scene(read_json(path))


def parse_scene(doc: Any) -> dict:
    """Validate a decoded JSON document and return the normalised scene."""
    if not isinstance(doc, dict):
        raise SceneError("", f"a lamp-scene document is a JSON object, not {kind_of(doc)}")
    schema = doc.get("schema")
    readable = (S.SCHEMA, *S.OLDER_SCHEMAS)
    if schema not in readable:
        allowed = " or ".join(f'"{s}"' for s in readable)
        if isinstance(schema, str) and schema.startswith("lamp-scene/"):
            raise SceneError("schema", f'"{printable(schema, 40)}" is not supported; this version reads {allowed}')
        raise SceneError("schema", f"{show_value(schema)} is missing or wrong; allowed {allowed}")
    raw_freeform = doc.get("freeform") if schema == S.SCHEMA else None  # lamp-scene/1 knew no freeform
    if raw_freeform is not None:
        doc = {key: value for key, value in doc.items() if key != "freeform"}
    scene = _section({**doc, "schema": S.SCHEMA}, S.SCENE, "")
    if "camera" not in scene:
        scene["camera"] = default_camera(scene)
    check_geometry(scene)
    if raw_freeform is not None:
        scene["freeform"] = finish_freeform(raw_freeform, _section(raw_freeform, S.FREEFORM, "freeform."))
    check_photometric(scene)
    return scene


def normalize(scene: dict) -> dict:
    """Validate an already-normalised (or hand-edited) scene again; returns a fresh copy."""
    return parse_scene(copy.deepcopy(scene))


def _section(doc: Any, sec: S.Section, path: str) -> dict:
    if not isinstance(doc, dict):
        raise SceneError(path.rstrip("."), f"expected an object, got {kind_of(doc)}; allowed an object with "
                                           f"the keys {', '.join(sec.fields)}")
    for key in doc:
        if key not in sec.fields:
            allowed = ", ".join(sec.fields)
            raise SceneError(f"{path}{show_key(str(key))}", f"unknown key; allowed keys here: {allowed}")
    out: dict = {}
    for key, spec in sec.fields.items():
        where = f"{path}{key}"
        if key not in doc:
            if sec.may_be_absent(key):
                continue
            out[key] = _default(spec, where)
            continue
        out[key] = _value(doc[key], spec, where)
    _either_or(out, sec, path)
    # The canonical order is the declaration's: a form filled in by its default (a photometric lens
    # without a colour) sits where a written one would, so normalising twice gives the same text.
    return {key: out[key] for key in sec.fields if key in out}


def _default(spec: S.Spec, where: str) -> Any:
    if isinstance(spec, S.ListOf):
        raise SceneError(where, f"is required; {spec.range_text()}")
    return default_value(spec)


def _value(v: Any, spec: S.Spec, where: str) -> Any:
    if isinstance(spec, S.Section):
        return _section(v, spec, where + ".")
    if isinstance(spec, S.ListOf):
        if not isinstance(v, list):
            raise SceneError(where, f"expected a list, got {kind_of(v)}; allowed {spec.range_text()}")
        if not spec.min_items <= len(v) <= spec.max_items:
            raise SceneError(where, f"has {len(v)} items; allowed {spec.min_items} to {spec.max_items}")
        return [_section(item, spec.item, f"{where}[{i}].") for i, item in enumerate(v)]
    if isinstance(spec, S.Num):
        return _num(v, spec, where)
    if isinstance(spec, S.Choice):
        if v not in spec.choices:
            raise SceneError(where, f"{show_value(v)} is not allowed; allowed {spec.range_text()}")
        return v
    if isinstance(spec, S.Text):
        if not isinstance(v, str):
            raise SceneError(where, f"expected a string, got {kind_of(v)}; allowed {spec.range_text()}")
        if len(v) > spec.max_len:
            raise SceneError(where, f"has {len(v)} characters; allowed at most {spec.max_len}")
        _check_characters(v, where, spec.range_text())
        return v
    if isinstance(spec, S.Flag):
        if not isinstance(v, bool):
            raise SceneError(where, f"{show_value(v)} is not allowed; allowed true or false")
        return v
    if isinstance(spec, S.Tags):
        if not isinstance(v, list) or not all(isinstance(t, str) for t in v):
            raise SceneError(where, f"expected a list of strings, got {show_value(v)}; allowed {spec.range_text()}")
        if len(v) > spec.max_items or any(len(t) > spec.max_len for t in v):
            raise SceneError(where, f"too long; allowed {spec.range_text()}")
        for i, t in enumerate(v):
            _check_characters(t, f"{where}[{i}]", spec.range_text())
        return list(v)
    raise AssertionError(spec)  # pragma: no cover - every spec kind is handled above


def _num(v: Any, spec: S.Num, where: str) -> Any:
    if spec.size > 1:
        if not isinstance(v, list) or len(v) != spec.size:
            raise SceneError(where, f"expected a list of {spec.size} numbers, got {show_value(v)}; "
                                    f"allowed {spec.range_text()}")
        items = [_scalar(x, spec, f"{where}[{i}]") for i, x in enumerate(v)]
        if spec.too_short(items):
            raise SceneError(where, f"{show_value(v)} is too short to give a direction; allowed {spec.range_text()}")
        return items
    return _scalar(v, spec, where)


def _scalar(x: Any, spec: S.Num, where: str) -> float | int:
    return check_number(x, spec, where, spec.range_text())


def check_number(x: Any, spec: S.Num, where: str, allowed: str) -> float | int:
    """One number checked against ``spec``'s range (``allowed`` is that range as the message says it).

    A JSON integer may have thousands of digits; it is compared exactly and never converted to a
    float before it is known to be in range (the conversion would overflow)."""
    if isinstance(x, bool) or not isinstance(x, (int, float)):
        raise SceneError(where, f"expected a number, got {show_value(x)}; allowed {allowed}")
    if isinstance(x, HugeNumber):
        raise SceneError(where, f"{x.shown()} is out of range; allowed {allowed}")
    if isinstance(x, float) and not math.isfinite(x):
        raise SceneError(where, f"{show_value(x)} is not a finite number; allowed {allowed}")
    if spec.integer and isinstance(x, float) and not x.is_integer():
        raise SceneError(where, f"{show_value(x)} is not a whole number; allowed {allowed}")
    lo_bad = spec.lo is not None and (x < spec.lo or (spec.lo_open and x == spec.lo))
    hi_bad = spec.hi is not None and (x > spec.hi or (spec.hi_open and x == spec.hi))
    if lo_bad or hi_bad or (isinstance(x, int) and abs(x) > _LARGEST_FLOAT):
        raise SceneError(where, f"{show_value(x)} is out of range; allowed {allowed}")
    return int(x) if spec.integer else float(x)


_LARGEST_FLOAT = int(1.7976931348623157e308)


def _check_characters(text: str, where: str, allowed: str) -> None:
    if has_surrogate(text):
        raise SceneError(where, f"\"{printable(text, 40)}\" holds a lone surrogate (\\ud800-\\udfff), which is "
                                f"not a character; allowed Unicode text only, {allowed}")


def _either_or(out: dict, sec: S.Section, path: str) -> None:
    """Apply the section's either/or rules (``spec.OneOf``) to the fields read into ``out``:
    one form at most, its selecting field present, its missing fields filled in; no form given
    means the rule's default form with its defaults (what earlier versions wrote)."""
    for rule in sec.one_of:
        given = rule.given(out)
        if len(given) > 1:
            first, other = given[0], given[1]
            raise SceneError(f"{path}{other.name}", f"cannot be given with {first.name}; allowed "
                                                    f"{rule.range_text()}")
        alt = given[0] if given else rule.alternative(rule.default)
        if given and alt.name not in out:
            stray = next(k for k in alt.keys if k in out)
            raise SceneError(f"{path}{stray}", f"only allowed with {alt.name}; allowed {rule.range_text()}")
        fill_alternative(out, sec, alt)

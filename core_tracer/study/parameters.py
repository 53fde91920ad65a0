"""What a design study can vary (``study_parameters``): a parameter path such as ``lens.ior``,
``lamps[1].cuts.height`` or ``bulb.offset[1]`` resolved against the field declarations (``spec``),
one value checked against its field's range, and values applied to a scene as choosing them in
Blender does (``apply_values``). The study itself (axes, variants, the document) is ``definition``'s.
"""

from __future__ import annotations

import copy
import re
from dataclasses import dataclass
from typing import Any

from ..scene import functions
from ..scene import spec as S
from ..scene.derived import use_form
from ..scene.messages import show_value
from ..scene.photometric_checks import BULB_STATES
from ..scene.reading import SceneError
from ..scene.safe_text import show_key
from ..scene.validate import check_number

_PARAMETER = re.compile(
    r"^(?:lamps\[(?P<lamp>\d*)\]\.|freeform\.parts\[(?P<part>\d*)\]\.)?"
    r"(?P<path>[a-z_][a-z0-9_]*(?:\.[a-z_][a-z0-9_]*)*)(?:\[(?P<component>\d+)\])?$"
)
# A free-form part's values are varied under its role (``freeform.parts[2].lens.filter``; ``parts[]``:
# every part of that role); its mesh, name and role are the design's geometry, which a study keeps.
_PART_PREFIX = "freeform.parts[]."
# Scene-level sections and fields a study may vary; image is the study's own size, but its
# samples per pixel vary like any parameter, and a study may set one design in both light models.
_SCENE_PARTS = ("camera", "light", "background", "body", "environment")
_SCENE_FIELDS = ("image.samples", "light_model")
# A lamp's function sets these lamp fields (``functions.apply_function``): an axis over the function
# and an axis over one of them would set the same thing. Both forms of the lens colour count: the
# function switches the lens to a transmitted colour.
_FUNCTION_SETS = frozenset(
    {("lens", key) for look, _ in functions.DEFAULTS.values() for key in look.fields}
    | {("lens", key) for key in S.LENS.rule_of("transmitted_color").keys} | {("bulb", "intensity")})


@dataclass(frozen=True)
class Parameter:
    """A resolved parameter path."""

    text: str  # as the user wrote it, e.g. "lamps[1].lens.ior"
    keys: tuple[str, ...]  # path inside the scene (or inside each lamp when lamp_scope)
    spec: S.Num | S.Flag | S.Choice
    lamp_scope: bool  # a lamp field
    lamp: int | None  # one lamp; None = every lamp
    component: int | None  # one component of a vector field
    part_scope: bool = False  # a free-form part's value (keys start with its role)
    part: int | None = None  # one part; None = every part of the role

    @property
    def scope(self) -> tuple[str, int | None]:
        """What the field belongs to: ("lamp", index), ("part", index) or ("scene", None)."""
        return ("lamp", self.lamp) if self.lamp_scope else ("part", self.part) if self.part_scope else ("scene", None)

    @property
    def short(self) -> str:
        """The name printed next to each cell's value: the last key (and component); a choice named
        only "type" keeps its section, ``cuts.type``, so a cell says what kind of thing it shows."""
        name = ".".join(self.keys[-2:]) if self.keys[-1] == "type" else self.keys[-1]
        return name if self.component is None else f"{name}[{self.component}]"

    @property
    def is_vector(self) -> bool:
        return isinstance(self.spec, S.Num) and self.spec.size > 1 and self.component is None

    @property
    def section(self) -> S.Section:
        """The section that holds the field (the lens for ``lens.ior``)."""
        if self.lamp_scope:
            return S.lookup(".".join(("lamps[]",) + self.keys[:-1])) if len(self.keys) > 1 else S.LAMP
        if self.part_scope:
            return _part_spec(self.keys[:-1])
        return S.lookup(".".join(self.keys[:-1])) if len(self.keys) > 1 else S.SCENE

    @property
    def form(self) -> S.Alternative | None:
        """The form of an either/or rule the field belongs to (``lens.absorption``), or None."""
        rule = self.section.rule_of(self.keys[-1])
        return rule.of_key(self.keys[-1]) if rule is not None else None

    def nodes(self, scene: dict) -> list[dict]:
        """The dicts of ``scene`` that hold the field: one per lamp it applies to."""
        if self.part_scope:
            parts = scene["freeform"]["parts"]
            roots = [p for p in parts if p["role"] == self.keys[0]] if self.part is None else [parts[self.part]]
        elif self.lamp_scope:
            roots = scene["lamps"] if self.lamp is None else [scene["lamps"][self.lamp]]
        else:
            roots = [scene]
        out = []
        for node in roots:
            for key in self.keys[:-1]:
                node = node[key]
            out.append(node)
        return out


def study_parameters() -> list[str]:
    """Every parameter a study can vary, lamp fields lamp-relative (``lens.ior``), in spec order.

    Lamp centres are left out: moving every lamp to the same place makes the lenses overlap;
    ``lamps[i].center`` names one lamp's centre.
    """
    out = []
    for info in S.iter_fields():
        if not isinstance(info.spec, S.Num | S.Flag | S.Choice):
            continue
        path = info.path
        if path.startswith("lamps[]."):
            path = path[len("lamps[]."):]
            if path == "center":
                continue
        elif path.split(".")[0] not in _SCENE_PARTS and path not in _SCENE_FIELDS:
            continue
        out.append(path)
    # a free-form part's values under its role; its object and role are its geometry
    out += [info.path for info in S.iter_fields(S.FREEFORM_PART, _PART_PREFIX)
            if info.path.count(".") >= 3 and isinstance(info.spec, S.Num | S.Flag | S.Choice)]
    return out


def resolve_parameter(text: Any, base: dict | None = None) -> Parameter:
    """Check a parameter path against ``spec`` (and the lamp index against ``base``)."""
    if not isinstance(text, str) or not text:
        raise SceneError("parameter", f"expected a parameter name such as \"lens.ior\", got {show_value(text)}")
    m = _PARAMETER.match(text)
    if m is None:
        raise SceneError(show_key(text), "is not a parameter name; write e.g. lens.ior, lamps[1].cuts.height, "
                                         "body.color or bulb.offset[1]")
    keys = tuple(m["path"].split("."))
    if m["part"] is not None:
        return _part_parameter(text, keys, m, base)
    explicit_lamp = m["lamp"] is not None
    lamp_scope = explicit_lamp or (keys[0] in S.LAMP.fields and keys[0] not in S.SCENE.fields)
    if not lamp_scope and keys[0] not in _SCENE_PARTS and ".".join(keys) not in _SCENE_FIELDS:
        raise SceneError(show_key(text), f"unknown parameter; a study varies {', '.join(_SCENE_PARTS)} fields, "
                               f"{', '.join(_SCENE_FIELDS)} "
                               "or lamp fields (lens, cuts, reflector, bulb, socket)")
    try:
        field_spec = S.lookup(".".join(("lamps[]",) + keys) if lamp_scope else ".".join(keys))
    except KeyError:
        raise SceneError(show_key(text), "unknown parameter; see `python -m core_tracer study --list` "
                               "for the names") from None
    _check_variable(text, field_spec)
    if lamp_scope and base is not None and "freeform" in base:  # its lamps are not what is traced
        raise SceneError(show_key(text), "is a field of the parametric lamps, which a free-form design does not "
                                         "trace; allowed its parts' values, freeform.parts[i].<role>.<field> "
                                         "(e.g. freeform.parts[].lens.filter), and scene fields")
    lamp = None
    if explicit_lamp and m["lamp"] != "":
        n = len(base["lamps"]) if base is not None else S.MAX_LAMPS
        lamp = _index(m["lamp"])
        if lamp >= n:
            raise SceneError(show_key(text), f"lamp index {show_key(m['lamp'])} does not exist; the base design has "
                                             f"{n} lamp{'s' if n != 1 else ''} (allowed 0 to {n - 1})")
    component = _component(text, m, field_spec)
    return Parameter(text, keys, field_spec, lamp_scope, lamp, component)


def _part_spec(keys: tuple[str, ...]) -> S.Spec:
    """The spec at ``keys`` inside a free-form part (``("lens", "filter")``); KeyError if none."""
    node: S.Spec = S.FREEFORM_PART
    for key in keys:
        if not isinstance(node, S.Section) or key not in node.fields:
            raise KeyError(".".join(keys))
        node = node.fields[key]
    return node


def _check_variable(text: str, field_spec: S.Spec) -> None:
    if not isinstance(field_spec, S.Num | S.Flag | S.Choice):
        raise SceneError(show_key(text), "is not a field a study can vary; allowed numbers, switches and choices "
                                         "(see `python -m core_tracer study --list`)")


def _component(text: str, m: re.Match, field_spec: S.Spec) -> int | None:
    """The component [k] of a vector field a parameter names, checked; None for the whole field."""
    if m["component"] is None:
        return None
    component = _index(m["component"])
    size = field_spec.size if isinstance(field_spec, S.Num) else 1
    if size == 1:
        raise SceneError(show_key(text), "is a single number; a component [k] only applies to vectors")
    if component >= size:
        raise SceneError(show_key(text), f"component {show_key(m['component'])} does not exist; "
                                         f"allowed 0 to {size - 1}")
    return component


def _part_parameter(text: str, keys: tuple[str, ...], m: re.Match, base: dict | None) -> Parameter:
    """A free-form part's value, ``freeform.parts[i].<role>.<field>``: the role must be the part's
    (every part of it for ``parts[]``), and the base a free-form design."""
    if keys[0] not in S.FREEFORM_ROLES or len(keys) < 2:
        raise SceneError(show_key(text), f"is not a value of a free-form part; write freeform.parts[i].<role>.<field> "
                                         f"with a role of {', '.join(S.FREEFORM_ROLES)} (the mesh and the role are "
                                         "the design's geometry, which a study keeps)")
    try:
        field_spec = _part_spec(keys)
    except KeyError:
        raise SceneError(show_key(text), "unknown parameter; see `python -m core_tracer study --list` "
                                         "for the names") from None
    _check_variable(text, field_spec)
    part = None
    if base is not None and "freeform" not in base:
        raise SceneError(show_key(text), "varies a free-form part, and the base design has no freeform section; "
                                         "allowed only for a free-form design")
    if m["part"] != "":
        part = _index(m["part"])
        parts = base["freeform"]["parts"] if base is not None else None
        n = len(parts) if parts is not None else S.MAX_FREEFORM_PARTS
        if part >= n:
            raise SceneError(show_key(text), f"part index {show_key(m['part'])} does not exist; the base design has "
                                             f"{n} part{'s' if n != 1 else ''} (allowed 0 to {n - 1})")
        if parts is not None and parts[part]["role"] != keys[0]:
            raise SceneError(show_key(text), f"part {part} is a {parts[part]['role']}, not a {keys[0]}; allowed "
                                             f"freeform.parts[{part}].{parts[part]['role']}.<field>")
    elif base is not None and not any(p["role"] == keys[0] for p in base["freeform"]["parts"]):
        raise SceneError(show_key(text), f"the base design has no {keys[0]} part; allowed the roles it has")
    component = _component(text, m, field_spec)
    return Parameter(text, keys, field_spec, False, None, component, True, part)


def _index(digits: str) -> int:
    """An index written in a parameter name; thousands of digits are simply too large (int() of
    them would fail), and every index allowed has one digit."""
    return int(digits) if len(digits) <= 3 else 10**3


def check_value(param: Parameter, value: Any) -> Any:
    """One axis value, checked against the field's range; returns it as the scene stores it."""
    sp = param.spec
    if isinstance(sp, S.Choice):
        if value not in sp.choices:
            raise SceneError(param.text, f"{show_value(value)} is not allowed; allowed {sp.range_text()}")
        return value
    if isinstance(sp, S.Flag):
        if not isinstance(value, bool):
            raise SceneError(param.text, f"{show_value(value)} is not allowed; allowed true or false")
        return value
    if param.is_vector:
        if not isinstance(value, list) or len(value) != sp.size:
            raise SceneError(param.text, f"expected a list of {sp.size} numbers, got {show_value(value)}; "
                                         f"allowed {sp.range_text()}")
        items = [_check_scalar(param, x, sp) for x in value]
        if sp.too_short(items):
            raise SceneError(param.text, f"{show_value(value)} is too short to give a direction; "
                                         f"allowed {sp.range_text()}")
        return items
    return _check_scalar(param, value, sp)


def _check_scalar(param: Parameter, x: Any, sp: S.Num) -> float | int:
    one = S.Num(None, sp.lo, sp.hi, sp.lo_open, sp.hi_open, sp.unit)  # the range of one component
    return check_number(x, sp, param.text, one.range_text())


def apply_values(scene: dict, params: tuple[Parameter, ...], values: tuple[Any, ...]) -> None:
    """Set each parameter to its value (``apply_value``), a lamp's function first: it sets the lens
    colour seen through the lens's thickness as it is then, so a thickness varied with it still
    makes the lens look deeper, whichever axis comes first."""
    # a named bulb before its filament: choosing the bulb keeps a filament it has (``_keep_filament``)
    pairs = sorted(zip(params, values, strict=True),
                   key=lambda pv: (pv[0].keys != ("function",), pv[0].keys[-2:] != ("bulb", "type")))
    for param, value in pairs:
        apply_value(scene, param, value)


def apply_value(scene: dict, param: Parameter, value: Any) -> None:
    """Set ``param`` to ``value`` in ``scene`` (a normalised scene, edited in place). A field of
    one form of an either/or rule (the lens colour) switches the section to that form first,
    keeping what it describes, so a component edit keeps the other components."""
    last = param.keys[-1]
    if param.lamp_scope and param.keys == ("function",):
        for lamp in param.nodes(scene):  # as choosing it in Blender: its lens colour and bulb
            functions.apply_function(lamp, value)
        return
    for node in param.nodes(scene):
        use_form(node, param.section, last)
        if param.component is None:
            node[last] = copy.deepcopy(value)
        else:
            vector = list(node[last])
            vector[param.component] = value
            node[last] = vector
        if param.section in (S.BULB, S.FREEFORM_ROLE_SECTIONS["bulb"]) and last == "type":
            _keep_filament(node)


def _keep_filament(bulb: dict) -> None:
    """As choosing a named bulb in Blender: its filament stays when the bulb has it (a P21/5W's stop),
    else it becomes the bulb's first (an R5W's "on"), so a study can set bulb types side by side."""
    states = BULB_STATES.get(bulb["type"])
    if states is not None and bulb.get("state") not in states:
        bulb["state"] = states[0]


def sets_same(a: Parameter, b: Parameter) -> bool:
    """Whether two axes would set the same number (or the two exclusive forms of one lens colour, or
    a lamp's function and a field it sets)."""
    (kind_a, at_a), (kind_b, at_b) = a.scope, b.scope
    lamps_meet = kind_a == kind_b and (at_a is None or at_b is None or at_a == at_b)
    if lamps_meet and a.lamp_scope and ("function",) in (a.keys, b.keys) and a.keys != b.keys:
        other = b if a.keys == ("function",) else a
        return other.keys in _FUNCTION_SETS
    if a.keys != b.keys:
        # Two forms of one either/or rule (absorption against a transmitted colour) exclude each other.
        same_section = a.keys[:-1] == b.keys[:-1]
        return lamps_meet and same_section and a.form is not None and b.form is not None and a.form is not b.form \
            and a.section.rule_of(a.keys[-1]) is b.section.rule_of(b.keys[-1])
    comps_meet = a.component is None or b.component is None or a.component == b.component
    return lamps_meet and comps_meet

"""Whether the scene's design is valid, and which property to change when it is not.

The panel asks at every redraw, so the answer is kept until the design changes: the key is the
design document's canonical JSON (reading the properties takes well under a millisecond; checking
a design, up to a few tens of milliseconds when the bulb does not fit).
"""

from __future__ import annotations

import json
import re
import textwrap
from dataclasses import dataclass

from ...core_tracer.scene import spec as S
from ...core_tracer.scene.limits import lamp_limits
from ...core_tracer.scene.reading import SceneError
from ...core_tracer.scene.validate import parse_scene
from . import photometric_words, properties

WRAP = 44  # characters per label line in the sidebar


@dataclass(frozen=True)
class Problem:
    """The first error of a design: the field's path (``lamps[2].cuts.height``) and the message."""

    path: str
    message: str

    @property
    def property_path(self) -> str:
        """The path of the property to change below ``lamp_design`` (a vector's component dropped)."""
        return re.sub(r"\[\d+\]$", "", self.path)

    def field(self, design):
        """``(group, key)`` of the property to change, or None when the error is not about one."""
        owner, _, key = self.property_path.rpartition(".")
        key = properties.property_id(key)
        try:
            group = design.path_resolve(owner) if owner else design
        except ValueError:
            return None
        if key not in group.bl_rna.properties.keys() or key == "lamps":
            return None
        return group, key

    def label(self) -> str:
        """The field in the panel's words: ``lamps[2].cuts.height`` -> "Lamp 3 Cuts: Height"."""
        words = []
        for part in self.property_path.split("."):
            m = re.fullmatch(r"(\w+)\[(\d+)\]", part)
            words.append(f"Lamp {int(m[2]) + 1}" if m and m[1] == "lamps" else properties.display_name(part))
        owner, _, key = re.sub(r"\[\d+\]", "[]", self.property_path).rpartition(".")
        section = _spec(owner) if owner else S.SCENE
        if isinstance(section, S.Section):  # a photometric field's own words ("Filament", not "State")
            words[-1] = photometric_words.label(section, key) or words[-1]
        return " ".join(words[:-1]) + (": " if len(words) > 1 else "") + words[-1]

    def lines(self) -> list[str]:
        return textwrap.wrap(self.message, WRAP)


@dataclass(frozen=True)
class Status:
    problem: Problem | None
    limits: dict[str, str]  # property path below lamp_design -> the limit that depends on other fields


_memo: dict = {"key": None, "status": None}


def status(bl_scene) -> Status:
    """The design's status, checked again only when the design (or the active lamp) changed."""
    doc = properties.design_document(bl_scene)
    active = bl_scene.lamp_design.active_lamps_index
    key = (json.dumps(doc, sort_keys=True), active)
    if _memo["key"] != key:
        _memo.update(key=key, status=_check(doc, active))
    return _memo["status"]


def _check(doc: dict, active: int) -> Status:
    try:
        parse_scene(doc)
        problem = None
    except SceneError as e:
        problem = Problem(e.path, e.message)
    limits = {}
    if 0 <= active < len(doc["lamps"]):  # the lamp the panel shows; the bulb's limits take a few ms
        limits = {f"lamps[{active}].{path}": text for path, text in lamp_limits(doc, active).items()}
    return Status(problem, limits)


def field_path(group, key: str) -> str:
    """The spec path below ``lamp_design`` of ``group``'s property ``key`` (``lamps[0].cuts.height``)."""
    owner, _, ident = group.path_from_id(key).removeprefix("lamp_design.").rpartition(".")
    return f"{owner}.{properties.spec_key(ident)}" if owner else properties.spec_key(ident)


def draw_status(layout, bl_scene) -> None:
    """The design's state as the panel's first lines: valid, or the field to change (highlighted,
    editable here) with the message under it."""
    design = bl_scene.lamp_design
    box = layout.box()
    if not design.lamps:
        box.label(text="No lamp yet: add one in Lamps below", icon="INFO")
        return
    problem = status(bl_scene).problem
    if problem is None:
        box.label(text="Design is valid", icon="CHECKMARK")
        return
    col = box.column(align=True)
    col.alert = True
    col.label(text=problem.label(), icon="ERROR")
    field = problem.field(design)
    if field is not None:
        col.prop(*field)
    for line in problem.lines():
        col.label(text=line)


def draw_field(layout, group, key: str, st: Status) -> None:
    """``layout.prop(group, key)``, highlighted with the message under it when it is the field the
    design's first error (in ``st``, the design's ``status``) names, and with the limit other fields
    set on it."""
    path = field_path(group, key)
    problem = st.problem if st.problem is not None and st.problem.property_path == path else None
    col = layout.column(align=True)
    col.alert = problem is not None
    spec = _spec(path)
    if isinstance(spec, S.Num) and spec.subtype == "rgb":  # per-channel numbers: R, G, B, not X, Y, Z
        name = group.bl_rna.properties[key].name
        for index, channel in enumerate("RGB"):
            col.prop(group, key, index=index, text=f"{name} {channel}" if index == 0 else channel)
    else:
        col.prop(group, key)
    if problem is not None:
        for line in problem.lines():
            col.label(text=line)
    elif path in st.limits:
        col.label(text=st.limits[path].capitalize(), icon="INFO")


def _spec(path: str) -> S.Spec | None:
    try:
        return S.lookup(re.sub(r"\[\d+\]", "[]", path))
    except KeyError:
        return None

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

from ...core_tracer.raytrace import spectral
from ...core_tracer.scene import spec as S
from ...core_tracer.scene.light_models import ignored_note
from ...core_tracer.scene.limits import lamp_limits
from ...core_tracer.scene.messages import leaves
from ...core_tracer.scene.reading import SceneError
from ...core_tracer.scene.validate import parse_scene
from . import photometric_words, properties

WRAP = 44  # characters per label line in the sidebar


# Where a top-level section's fields are drawn: the panel's own words for it.
PANEL_OF = {"camera": "Camera & Image", "image": "Camera & Image", "glare": "Camera & Image › Glare",
            "environment": "Light › Surroundings", "background": "Light › Background", "light": "Light"}
SEPARATOR = " › "
_UNIT = re.compile(r" \([^)]*\)$")
# A field's path inside a message: "lamps[0].lens.radius", "body.size", "lens.outline", "lamps[1]".
_PATH_IN_TEXT = re.compile(r"(?<![\w.\[])((?:lamps\[\d+\]|[a-z][a-z_]*)(?:\.[a-z][a-z0-9_]*)+|lamps\[\d+\])(?![\w\[])")


def field_words(path: str) -> str | None:
    """A field's path in the panel's words: ``lamps[0].cuts.height`` -> "Lamp 1 › Cuts › Height";
    ``lens.radius`` (a lamp's) -> "Lens › Radius"; None when the path is no field of the design."""
    path = re.sub(r"\[\d+\]$", "", path) if not re.fullmatch(r"lamps\[\d+\]", path) else path
    try:
        S.lookup(re.sub(r"\[\d+\]", "[]", path))
    except KeyError:
        return None
    words = []
    for i, part in enumerate(path.split(".")):
        m = re.fullmatch(r"lamps\[(\d+)\]", part)
        if m:
            words.append(f"Lamp {int(m[1]) + 1}")
        elif i == 0 and part in PANEL_OF:
            words.append(PANEL_OF[part])
        else:
            parent_path = re.sub(r"\[\d+\]", "[]", ".".join(path.split(".")[:i]))
            try:
                parent = S.lookup(parent_path) if parent_path else S.SCENE
            except KeyError:
                parent = None
            if isinstance(parent, S.ListOf):
                parent = parent.item
            own = ((properties.words.label(parent, part) or photometric_words.label(parent, part))
                   if isinstance(parent, S.Section) else None)  # a photometric field's own words ("Filament")
            words.append(own or _UNIT.sub("", properties.display_name(part)))
    return SEPARATOR.join(words)


def in_panel_words(text: str) -> str:
    """``text`` with every field path in it said in the panel's words (``field_words``)."""
    return _PATH_IN_TEXT.sub(lambda m: field_words(m[1]) or m[1], text)


@dataclass(frozen=True)
class Problem:
    """The first error of a design: the field's path (``lamps[2].cuts.height``) and the message, and
    the field to highlight: the one whose change back fixes the design (``fix_path``, the field the
    designer just changed), else the field the error names."""

    path: str
    message: str
    fix_path: str = ""

    @property
    def property_path(self) -> str:
        """The path of the property to change below ``lamp_design`` (a vector's component dropped)."""
        return re.sub(r"\[\d+\]$", "", self.fix_path or self.path)

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
        """The field to change in the panel's words: ``lamps[2].cuts.height`` -> "Lamp 3 › Cuts › Height"."""
        return field_words(self.property_path) or self.property_path

    def explanation(self) -> str:
        """What is wrong, in the panel's words; when the field to change is another than the one the
        error names, that field is named in the message, as the second way out."""
        said = in_panel_words(self.message)
        if self.fix_path and re.sub(r"\[\d+\]$", "", self.path) != self.property_path:
            return f"{field_words(self.path) or self.path} {said}"  # the rule's own field, with its remedy
        return said

    def text(self) -> str:
        """The one message every surface shows: "Lamp 1 › Cuts › Height: 8 is more than ..."."""
        return f"{self.label()}: {self.explanation()}"

    def lines(self) -> list[str]:
        return textwrap.wrap(self.explanation(), WRAP)


@dataclass(frozen=True)
class Status:
    problem: Problem | None
    limits: dict[str, str]  # property path below lamp_design -> the limit that depends on other fields
    note: str | None = None  # what a valid design sets that its light model ignores (``light_models.ignored_note``)


_memo: dict = {"key": None, "status": None, "valid": {}}  # "valid": the last valid design of each scene


def status(bl_scene) -> Status:
    """The design's status, checked again only when the design (or the active lamp) changed."""
    doc = properties.design_document(bl_scene)
    active = bl_scene.lamp_design.active_lamps_index
    key = (json.dumps(doc, sort_keys=True), active, bl_scene.name)
    if _memo["key"] != key:
        _memo.update(key=key, status=_check(doc, active, _memo["valid"].get(bl_scene.name)))
        if _memo["status"].problem is None:
            _memo["valid"][bl_scene.name] = doc
    return _memo["status"]


def remember(bl_scene) -> None:
    """Check the design as it is now, so that a valid one becomes the design the next error is
    measured from (``fixing_field``). The panel does this as it draws; Apply Preset and Build call it
    too, so that an edit made before the panel is drawn again (a script, a driver, a headless walk)
    still highlights the field changed rather than the one the rule names."""
    if status(bl_scene).problem is None:
        _memo["valid"][bl_scene.name] = properties.design_document(bl_scene)


def _set_leaf(doc: dict, path: str, value) -> None:
    node = doc
    parts = re.findall(r"[^.\[\]]+|\[\d+\]", path)
    for part in parts[:-1]:
        node = node[int(part[1:-1])] if part.startswith("[") else node[part]
    node[parts[-1]] = value


def _valid(doc: dict) -> bool:
    try:
        parse_scene(doc)
    except SceneError:
        return False
    return True


def fixing_field(doc: dict, valid: dict | None, error_path: str) -> str:
    """Of the fields changed since the last valid design ``valid``, the one whose old value alone
    makes ``doc`` valid again ("" when the error's own field is one of them, or none does): the field
    the designer just changed, to highlight before the one the error names."""
    if valid is None:
        return ""
    now, before = leaves(doc), leaves(valid)
    if set(now) != set(before):
        return ""  # lamps added or removed: no single field to go back on
    changed = [path for path in now if now[path] != before[path]]
    if re.sub(r"\[\d+\]$", "", error_path) in changed:
        return ""
    for path in changed:
        trial = json.loads(json.dumps(doc))
        _set_leaf(trial, path, before[path])
        if _valid(trial):
            return path
    return ""


def _check(doc: dict, active: int, valid: dict | None = None) -> Status:
    note = None
    try:
        scene = parse_scene(doc)
        note = ignored_note(scene, lambda path: field_words(path) or path)
        if scene.get("light_model") == "photometric":  # what F12 computes from the spectra (issue 33)
            spectral.check_lamps(scene, curves=False)  # the measured curves: at render (curves.with_curves)
        problem = None
    except SceneError as e:
        problem = Problem(e.path, e.message, fixing_field(doc, valid, e.path))
    limits = {}
    if 0 <= active < len(doc["lamps"]):  # the lamp the panel shows; the bulb's limits take a few ms
        limits = {f"lamps[{active}].{path}": text for path, text in lamp_limits(doc, active).items()}
    return Status(problem, limits, note)


def message(bl_scene, error: SceneError) -> str:
    """What an operator (Build, F12, Compare, ...) says of the design's error ``error``: the panel's own
    message when it is the design's first error (the same words, the same field first), else the
    error with its fields in the panel's words."""
    problem = status(bl_scene).problem
    if problem is not None and (problem.path, problem.message) == (error.path, error.message):
        return problem.text()
    return Problem(error.path, error.message).text() if field_words(error.path) else in_panel_words(str(error))


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
    st = status(bl_scene)
    problem = st.problem
    if problem is None:
        box.label(text="Design is valid", icon="CHECKMARK")
        if st.note:  # reported, not refused: the fields are kept for a switch of light model
            for i, line in enumerate(textwrap.wrap(st.note[0].upper() + st.note[1:], WRAP)):
                box.label(text=line, icon="INFO" if i == 0 else "BLANK1")
        return
    col = box.column(align=True)
    col.alert = True
    col.label(text=problem.label(), icon="ERROR")  # the message's first words (``Problem.text``)
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

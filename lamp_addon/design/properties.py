"""The lamp design stored on the scene (``Scene.lamp_design``), generated from ``core_tracer.spec``.

No field is listed here by hand: the PropertyGroups are made by walking ``spec.SCENE`` (and the
``LAMP`` section inside its ``lamps`` list), so names, descriptions, ranges and defaults follow the
scene declaration. Kinds map as follows:

- ``Num`` -> ``FloatProperty`` / ``IntProperty``, or ``FloatVectorProperty`` (size 2 or 3, subtype
  ``COLOR`` for colours, ``XYZ`` for 3-vectors), hard and soft limits from the spec range; an open
  bound such as ``(0, 1000] mm`` becomes a closed one just inside it (``OPEN_BOUND_MARGIN``).
- ``Choice`` -> ``EnumProperty`` (identifiers are the JSON strings); a choice with a single allowed
  value (``schema``) is a constant, not a property.
- ``Flag`` -> ``BoolProperty``; ``Text`` -> ``StringProperty``; ``Tags`` -> ``StringProperty`` holding
  the tags separated by commas.
- ``Section`` -> a nested PropertyGroup; ``ListOf`` (the lamps) -> ``CollectionProperty`` plus an
  ``active_<key>_index``.

Lengths are kept in millimetres exactly as in the JSON (the property name carries the unit, e.g.
"Radius (mm)"), not in Blender units, so no scale factor touches the numbers. Blender stores floats in
32 bits; reading one back takes the shortest decimal that gives the same 32-bit float, which turns
every JSON value of at most 6 significant digits back into itself (``design_to_scene``).

An either/or rule of the spec (``spec.OneOf``, the lens colour: a transmitted colour at a reference
thickness, or absorption coefficients) becomes an ``EnumProperty`` ``<rule>_mode`` (``color_mode``)
whose items are the rule's forms and whose default is its preferred form (the colour picker). The
properties of every form exist; the mode says which form the design uses, and only that form's fields
are written to the scene.
"""

from __future__ import annotations

import struct

import bpy
from bpy.props import (
    BoolProperty,
    CollectionProperty,
    EnumProperty,
    FloatProperty,
    FloatVectorProperty,
    IntProperty,
    PointerProperty,
    StringProperty,
)

from ...core_tracer.scene import functions, photometric_checks
from ...core_tracer.scene import spec as S
from ...core_tracer.scene.reading import SceneError
from ...core_tracer.scene.validate import normalize, parse_scene
from . import photometric_words, words

OPEN_BOUND_MARGIN = 1.0e-6  # an open bound lo < x becomes lo + margin * max(1, |lo|) <= x
TAG_SEPARATOR = ","

_ACRONYMS = {"fov": "FOV", "ior": "IOR", "rgb": "RGB", "led": "LED"}

# Called with the scene after every edit of its design (Auto Build listens); see ``notify_edited``.
EDIT_LISTENERS: list = []


def notify_edited(bl_scene: bpy.types.Scene) -> None:
    """Tell the listeners that the design of ``bl_scene`` changed. Property edits call it themselves;
    changes no property reports (a lamp removed from the list) call it directly."""
    for listener in EDIT_LISTENERS:
        listener(bl_scene)


def _edited(self, context) -> None:
    notify_edited(self.id_data)  # the scene that owns the edited group, whichever scene is active


# ---------------------------------------------------------------------------------------------
# Spec -> bpy.props


def display_name(key: str, unit: str = "") -> str:
    """The UI name of a field: ``focal_length`` + mm -> "Focal Length (mm)", ``fov_deg`` -> "FOV (deg)"."""
    words = key.split("_")
    if unit and len(words) > 1 and words[-1] == unit:
        words = words[:-1]
    text = " ".join(_ACRONYMS.get(w, w.capitalize()) for w in words)
    return f"{text} ({unit})" if unit else text


# Keys that name a built-in property of every PropertyGroup: Blender shows the built-in's tooltip
# ("Unique name used in the code and scripting"), so the field gets its own identifier, stored in
# the same place (the "name" ID property), which keeps the names of files saved before.
RESERVED_KEYS = {"name": "design_name"}


def property_id(key: str) -> str:
    """The identifier of the property of spec field ``key``: the key itself, unless it is reserved."""
    return RESERVED_KEYS.get(key, key)


def spec_key(identifier: str) -> str:
    """The spec field of a property identifier (the inverse of ``property_id``)."""
    return next((key for key, ident in RESERVED_KEYS.items() if ident == identifier), identifier)


def _stored_in(key: str, spec: S.Text) -> StringProperty:
    """A string property kept in the ID property ``key`` (a built-in's place), with the spec's
    name, description and default."""
    def get(self) -> str:
        return self.get(key, spec.default)

    def set(self, value: str) -> None:
        self[key] = value

    return StringProperty(name=display_name(key), description=_description(spec), get=get, set=set)


def mode_property(rule: S.OneOf) -> str:
    """The name of the ``EnumProperty`` that says which form of ``rule`` a section uses."""
    return f"{rule.name}_mode"


def form_used(group, section: S.Section, key: str) -> bool:
    """Whether the field ``key`` of ``group`` (a ``section``) is part of the design: always,
    unless it belongs to a form of an either/or rule that the group does not use."""
    rule = section.rule_of(key)
    return rule is None or key in rule.alternative(getattr(group, mode_property(rule))).keys


def _mode_enum(rule: S.OneOf) -> EnumProperty:
    # Items in the rule's order: Blender stores the index, so the order is part of saved files.
    return EnumProperty(name=display_name(rule.name) + " Mode",
                        items=tuple((alt.name, alt.label, alt.doc) for alt in rule.alternatives),
                        default=rule.preferred, description=rule.doc, update=_edited)


def is_constant(spec: S.Spec) -> bool:
    """A field with one allowed value (the schema tag): written by the converter, never a property."""
    return isinstance(spec, S.Choice) and len(spec.choices) == 1


def blender_range(spec: S.Num) -> tuple[float | None, float | None]:
    """The closed (min, max) of the Blender property for a spec range; ``None`` is unbounded."""
    lo, hi = spec.lo, spec.hi
    if lo is not None and spec.lo_open:
        lo = lo + OPEN_BOUND_MARGIN * max(1.0, abs(lo))
    if hi is not None and spec.hi_open:
        hi = hi - OPEN_BOUND_MARGIN * max(1.0, abs(hi))
    return lo, hi


def _description(spec: S.Spec) -> str:
    return words.tooltip(spec)  # the designer's words first, the allowed values in words, the paper's symbol last


def field_label(section: S.Section, key: str, unit: str = "") -> str:
    """The panel's label of ``section``'s field ``key``: the designer's word for it (``words.LABELS``) or the
    key's, with the unit ("Position (mm)")."""
    own = words.label(section, key)
    if own is None:
        return display_name(key, unit)
    return f"{own} ({unit})" if unit else own


def _num_property(key: str, spec: S.Num, section: S.Section | None = None, name: str | None = None):
    lo, hi = blender_range(spec)
    if name is None:
        name = field_label(section, key, spec.unit) if section is not None else display_name(key, spec.unit)
    kw = {"name": name, "description": _description(spec), "update": _edited}
    if spec.integer:
        if lo is not None:
            kw["min"] = kw["soft_min"] = int(lo)
        if hi is not None:
            kw["max"] = kw["soft_max"] = int(hi)
        return IntProperty(default=int(spec.default), **kw)
    if lo is not None:
        kw["min"] = kw["soft_min"] = lo
    if hi is not None:
        kw["max"] = kw["soft_max"] = hi
    kw["precision"] = 4
    if spec.size > 1:
        if spec.subtype == "color":
            subtype = "COLOR"
        elif spec.size == 3:
            subtype = "XYZ"
        else:
            subtype = "NONE"  # the 2-vectors are [x, z] or [width, height]: X/Y labels would mislead
        return FloatVectorProperty(size=spec.size, subtype=subtype, default=tuple(float(x) for x in spec.default),
                                   **kw)
    return FloatProperty(default=float(spec.default), **kw)


def _function_chosen(self, context) -> None:
    """Picking a lamp's function sets the lens colour and bulb it goes with (``scene.functions``);
    writing a whole design (a preset) sets the function without touching the rest."""
    if _writing[0]:
        return
    lamp = _read_section(self, S.LAMP)
    functions.apply_function(lamp, self.function)
    set_lamp(self, lamp)


_writing = [0]  # > 0 while a design is being written: update callbacks leave the values alone


def _leaf_property(key: str, spec: S.Spec, section: S.Section):
    if photometric_words.label(section, key) is not None:
        return _worded_property(key, spec, section)
    if isinstance(spec, S.Num):
        return _num_property(key, spec, section)
    if isinstance(spec, S.Choice):
        is_function = section is S.LAMP and key == "function"
        items = tuple((c, display_name(c), functions.describe(c) if is_function else "") for c in spec.choices)
        update = _function_chosen if is_function else _edited
        return EnumProperty(name=field_label(section, key), description=_description(spec), items=items,
                            default=spec.default, update=update)
    if isinstance(spec, S.Flag):
        return BoolProperty(name=field_label(section, key), description=_description(spec), default=spec.default,
                            update=_edited)
    if isinstance(spec, S.Text):
        return StringProperty(name=display_name(key), description=_description(spec), default=spec.default,
                              update=_edited)
    if isinstance(spec, S.Tags):
        return StringProperty(name=display_name(key), default="", update=_edited,
                              description=f"{words.designer_text(spec.doc)}, separated by commas. Allowed: "
                                          f"{words.range_words(spec)}")
    raise TypeError(f"no property for {spec!r}")  # pragma: no cover - every leaf kind is handled above


def _worded_property(key: str, spec: S.Spec, section: S.Section):
    """The property of a field the panel names in a designer's words (``photometric_words``): its
    label, and a choice's items by name with their own tooltips (the menu lists what is allowed)."""
    words = photometric_words.label(section, key)
    name = f"{words} ({spec.unit})" if getattr(spec, "unit", "") else words
    if isinstance(spec, S.Choice):
        items = tuple((c, *photometric_words.choice_item(c, display_name(c))) for c in spec.choices)
        update = _bulb_type_chosen if section is S.BULB and key == "type" else _edited
        return EnumProperty(name=name, description=_description(spec), items=items, default=spec.default, update=update)
    if isinstance(spec, S.Num):
        return _num_property(key, spec, name=name)
    if isinstance(spec, S.Text):
        return StringProperty(name=name, description=_description(spec), default=spec.default, update=_edited)
    raise TypeError(f"no worded property for {spec!r}")  # pragma: no cover - photometric_words names these kinds


def _bulb_type_chosen(self, context) -> None:
    """Picking a named bulb keeps its filament one the bulb has (a P21/5W's stop stays; an R5W's is on)."""
    if not _writing[0] and self.type in photometric_checks.BULB_STATES:
        states = photometric_checks.BULB_STATES[self.type]
        if self.state not in states:
            self.state = states[0]
    _edited(self, context)


def _make_groups(section: S.Section, class_name: str, out: list[type], extra: dict | None = None) -> type:
    """Create the PropertyGroup of ``section`` (and, first, of every section inside it) into ``out``."""
    annotations: dict = {}
    for key, spec in section.fields.items():
        if is_constant(spec):
            continue
        if isinstance(spec, S.Section):
            sub = _make_groups(spec, f"{class_name}_{key}", out)
            annotations[key] = PointerProperty(type=sub, name=display_name(key), description=spec.doc)
        elif isinstance(spec, S.ListOf):
            item = _make_groups(spec.item, f"{class_name}_{key}_item", out)
            annotations[key] = CollectionProperty(type=item, name=display_name(key), description=spec.doc)
            annotations[f"active_{key}_index"] = IntProperty(name=f"Active {display_name(key)} Index", min=0)
        else:
            annotations[property_id(key)] = (_stored_in(key, spec) if key in RESERVED_KEYS
                                             else _leaf_property(key, spec, section))
    for rule in section.one_of:
        annotations[mode_property(rule)] = _mode_enum(rule)
    if section is S.SCENE:
        # Not a design field (never written to a scene document): how the built objects follow the design.
        annotations["auto_build"] = BoolProperty(
            name="Auto Build", default=True, update=_edited,
            description="Update the lamp's objects as you edit the design (a lighter lens while you drag)")
    namespace = {"__annotations__": annotations, "__doc__": section.doc or class_name, **(extra or {})}
    cls = type(class_name, (bpy.types.PropertyGroup,), namespace)
    out.append(cls)
    return cls


def _attach(cls) -> None:
    bpy.types.Scene.lamp_design = PointerProperty(type=cls, name="Lamp Design",
                                                  description="The lamp-scene/1 design of this scene")


def _detach(cls) -> None:
    del bpy.types.Scene.lamp_design


classes: list[type] = []
LampDesign = _make_groups(S.SCENE, "LAMP_PG_design", classes,
                          extra={"register": classmethod(_attach), "unregister": classmethod(_detach)})
classes = tuple(classes)  # nested groups first, the root last: registration order


# ---------------------------------------------------------------------------------------------
# Conversion between the properties and a normalised scene


def from_float32(x: float) -> float:
    """The shortest decimal that is the same 32-bit float as ``x`` (undoes Blender's float storage)."""
    target = struct.pack("<f", x)
    for digits in range(1, 10):
        y = float(f"{x:.{digits}g}")
        if struct.pack("<f", y) == target:
            return y
    return float(x)  # pragma: no cover - 9 significant digits always identify a float32


def _read_leaf(value, spec: S.Spec):
    if isinstance(spec, S.Num):
        if spec.size > 1:
            return [from_float32(x) for x in value]
        return int(value) if spec.integer else from_float32(value)
    if isinstance(spec, S.Flag):
        return bool(value)
    if isinstance(spec, S.Tags):
        return [t.strip() for t in value.split(TAG_SEPARATOR) if t.strip()]
    return str(value)


def _read_section(group, section: S.Section) -> dict:
    out: dict = {}
    for key, spec in section.fields.items():
        if is_constant(spec):
            out[key] = spec.default
        elif isinstance(spec, S.Section):
            out[key] = _read_section(getattr(group, key), spec)
        elif isinstance(spec, S.ListOf):
            out[key] = [_read_section(item, spec.item) for item in getattr(group, key)]
        elif form_used(group, section, key):
            out[key] = _read_leaf(getattr(group, property_id(key)), spec)
    return out


def poll_design(cls, context) -> bool:
    """The ``poll`` of operators that work on the scene's design: False, saying why, without one."""
    if context.scene is None or not hasattr(context.scene, "lamp_design"):
        cls.poll_message_set("No lamp design in this scene")
        return False
    return True


def design_document(bl_scene: bpy.types.Scene) -> dict:
    """The scene's design as a ``lamp-scene/1`` document, read but not checked (``parse_scene`` checks it)."""
    return _read_section(bl_scene.lamp_design, S.SCENE)


def design_to_scene(bl_scene: bpy.types.Scene, *, camera: dict | None = None, image: dict | None = None) -> dict:
    """The scene's design as a normalised ``lamp-scene/1`` scene; raises ``SceneError`` if it is invalid.

    The camera and image are the design's own sections unless ``camera`` / ``image`` replace them;
    they are replaced before the scene is checked, so an out-of-date design camera cannot block a
    render through Blender's scene camera (``camera.scene_for_render``).
    """
    doc = design_document(bl_scene)
    if camera is not None:
        doc["camera"] = camera
    if image is not None:
        doc["image"] = image
    return parse_scene(doc)


def _check_section(data: dict, section: S.Section, path: str) -> None:
    """Refuse values the properties cannot hold as given, before anything is written."""
    for key, spec in section.fields.items():
        if key not in data or is_constant(spec):
            continue
        where = f"{path}{key}"
        value = data[key]
        if isinstance(spec, S.Section):
            _check_section(value, spec, where + ".")
        elif isinstance(spec, S.ListOf):
            for i, item in enumerate(value):
                _check_section(item, spec.item, f"{where}[{i}].")
        elif isinstance(spec, S.Tags):
            for tag in value:
                if TAG_SEPARATOR in tag or tag != tag.strip() or not tag:
                    raise SceneError(where, f'"{tag}" cannot be kept in the comma-separated tag field; '
                                                       "allowed tags without commas or surrounding spaces")
        elif isinstance(spec, S.Num):
            lo, hi = blender_range(spec)
            for x in value if spec.size > 1 else (value,):
                if (lo is not None and x < lo) or (hi is not None and x > hi):
                    low = "-inf" if lo is None else f"{lo:g}"
                    high = "inf" if hi is None else f"{hi:g}"
                    raise SceneError(where, f"{x:g} is too close to the open bound; allowed "
                                                       f"[{low}, {high}] in Blender")


def _write_section(group, section: S.Section, data: dict) -> None:
    for key, spec in section.fields.items():
        if is_constant(spec) or key not in data:
            continue
        value = data[key]
        if isinstance(spec, S.Section):
            _write_section(getattr(group, key), spec, value)
        elif isinstance(spec, S.ListOf):
            items = getattr(group, key)
            items.clear()
            for item_data in value:
                _write_section(items.add(), spec.item, item_data)
            setattr(group, f"active_{key}_index", 0)
        elif isinstance(spec, S.Tags):
            setattr(group, key, f"{TAG_SEPARATOR} ".join(value))
        else:
            setattr(group, property_id(key), value)
    for rule in section.one_of:
        if rule.given(data):  # a partial write (a lamp function's defaults) may leave the form alone
            setattr(group, mode_property(rule), rule.chosen(data).name)


def set_lamp(item, lamp: dict) -> None:
    """Set one lamp of the design (an item of ``lamp_design.lamps``) from a lamp of a checked design
    document or scene."""
    _writing[0] += 1
    try:
        _write_section(item, S.LAMP, lamp)
    finally:
        _writing[0] -= 1


def scene_to_design(bl_scene: bpy.types.Scene, scene_dict: dict) -> None:
    """Set the scene's design from a scene; validates everything first, so it applies all or nothing.

    Raises ``SceneError`` (and changes nothing) when ``scene_dict`` is not a valid scene.
    """
    scene = normalize(scene_dict)
    _check_section(scene, S.SCENE, "")
    _writing[0] += 1
    try:
        _write_section(bl_scene.lamp_design, S.SCENE, scene)
    finally:
        _writing[0] -= 1


register, unregister = bpy.utils.register_classes_factory(classes)


# ---------------------------------------------------------------------------------------------
# For other property owners (the free-form roles on objects): the same generation and conversion


def make_groups(section: S.Section, class_name: str, out: list[type]) -> type:
    """The PropertyGroup of ``section`` (nested groups first into ``out``, then the group itself)."""
    return _make_groups(section, class_name, out)


def read_section(group, section: S.Section) -> dict:
    """The values of ``group`` (a group made from ``section``) as a document section."""
    return _read_section(group, section)


def write_section(group, section: S.Section, data: dict) -> None:
    """Set ``group`` from the document section ``data`` (keys it lacks are left alone)."""
    _writing[0] += 1
    try:
        _write_section(group, section, data)
    finally:
        _writing[0] -= 1

"""Design studies: one design turned into a grid of variants.

A *study* (``lamp-study/1``) varies one or two parameters of a base design, each over a list of
values or over a range with a number of steps, at most ``MAX_VARIANTS`` variants in all::

    {"schema": "lamp-study/1",
     "title": "Refractive index against cut height",          (optional)
     "base": { ...a complete lamp-scene/1 document... },
     "axes": [{"parameter": "lens.ior", "range": [1.45, 1.6], "steps": 4},
              {"parameter": "lamps[1].cuts.height", "values": [0.5, 1, 2]}],
     "size": [256, 256]}

Optional: ``measures``, ``sort`` and ``filter`` put measures of a photometric design under each
cell and order the sheet by them (``measured``).

The base is embedded, so a study file (or a contact sheet carrying one) can be handed to another
machine and re-run. A *parameter* is a dotted path of ``spec.py``:

- ``body.…``, ``light.…``, ``camera.…``, ``environment.…``, ``background``: scene fields;
- ``lens.ior``, ``cuts.height``, ``bulb.intensity`` …: a lamp field, applied to every lamp;
- ``lamps[2].lens.ior``: the same field of one lamp (the index is checked against the base);
- a trailing ``[k]`` picks one component of a vector: ``bulb.offset[1]`` is the bulb's y offset.

Every numeric field (``spec.Num``) can be varied, scalar or vector (vector values are lists;
a vector range is interpolated per component), ``bulb.on`` over ``[true, false]``, and every
choice of the scene (``spec.Choice``) over a list of its names: the surroundings
``environment.world`` (``["city", "sunset", "night"]``), the camera's projection, and the kind of
lamp, ``cuts.type`` (fisheye, sawtooth, flutes), ``lens.outline``, ``lens.shape``,
``lens.wrap_toward`` and ``collection`` (reflector, prism_plate), so lamp types stand side by side
on one sheet. A lamp's ``function`` is varied as choosing it in Blender does: it sets the lens
colour and the bulb that go with it (``scene.functions``). Varying the lens colour
(``lens.transmitted_color``) replaces the lens's absorption coefficients, as the scene format allows
only one of the two (docs/model.md §6); varying ``lens.absorption`` replaces a transmitted colour.

Everything is checked when the study is built, before anything renders: the parameter names,
each value against its field's range, the number of variants, and every variant scene with
``scene.parse_scene`` (a cut height too large for the pitch, a bulb outside its reflector, a
combination of types the scene refuses such as saw-tooth cuts on a cylindrical lens…).
Errors are ``SceneError``s naming the parameter, the value and the allowed range.

What a study can vary, and how a value is checked and applied, is ``parameters``'s. This module
is bpy-free and numpy-free; rendering is ``study_run``, the contact sheet ``study_sheet``.
"""

from __future__ import annotations

import copy
import itertools
import math
import os
from dataclasses import dataclass
from typing import Any

from .. import budget
from ..fileio import atomic_write_text
from ..scene import spec as S
from ..scene.messages import show_value
from ..scene.reading import SceneError, parse_json_text, read_json, scene_to_json
from ..scene.safe_text import has_surrogate, show_key
from ..scene.validate import parse_scene
from .measured import Choice, parse_number
from .measured import parse as parse_measures
from .parameters import Parameter, apply_values, check_value, resolve_parameter, sets_same

SCHEMA = "lamp-study/1"
STUDY_ATTRIBUTE = "lamp:study"  # the header attribute of a contact sheet that holds the study
MAX_VARIANTS = 64
MAX_AXES = 2
DEFAULT_SIZE = (256, 256)  # a cell's pixels when the body's aspect is not known; framed_size keeps their count
CELL_MARGIN = 0.8  # of the body's width/height: the cell a little taller than the body, so the lens is not cut
MAX_CELL_ASPECT = 4.0
MAX_SIZE = 2048  # per variant image side; a study is for comparing, not for final images

# ---------------------------------------------------------------------------------------------
# Axes


@dataclass(frozen=True)
class Axis:
    parameter: Parameter
    values: tuple[Any, ...]
    doc: dict  # the axis as written (a list or a range), kept so a saved study reads the same

    def label(self, value: Any) -> str:
        return format_value(value)


def parse_axis(doc: Any, base: dict, where: str) -> Axis:
    if not isinstance(doc, dict):
        raise SceneError(where, f"expected an object with parameter and values or range, got {_show(doc)}")
    unknown = [k for k in doc if k not in ("parameter", "values", "range", "steps")]
    if unknown:
        raise SceneError(f"{where}.{show_key(unknown[0])}",
                         "unknown key; allowed keys here: parameter, values, range, steps")
    if "parameter" not in doc:
        raise SceneError(f"{where}.parameter", "is required (e.g. \"lens.ior\")")
    param = resolve_parameter(doc["parameter"], base)
    form = param.form
    if form is not None and param.keys[-1] != form.name:  # a field that only goes with its form's first
        rule = param.section.rule_of(form.name)
        used = {rule.chosen(node).name for node in param.nodes(base)} - {form.name}
        if used:
            prefix = ".".join(param.keys[:-1])
            raise SceneError(param.text, f"only applies where {prefix}.{form.name} is given; this base gives "
                                         f"{prefix}.{min(used)} (vary {prefix}.{form.name} instead)")
    has_values, has_range = "values" in doc, "range" in doc
    if has_values == has_range:
        raise SceneError(param.text, "give either values (a list) or range [lo, hi] with steps, not "
                         + ("both" if has_values else "neither"))
    if has_values:
        values = doc["values"]
        if "steps" in doc:
            raise SceneError(param.text, "steps only goes with range, not with values")
        if not isinstance(values, list) or not values:
            raise SceneError(param.text, f"values must be a non-empty list, got {_show(values)}")
        if len(values) > MAX_VARIANTS:
            raise SceneError(param.text, f"has {len(values)} values; allowed at most {MAX_VARIANTS} variants")
        checked = tuple(check_value(param, v) for v in values)
    else:
        checked = _expand_range(param, doc.get("range"), doc.get("steps"))
    return Axis(param, checked, dict(doc))


def _expand_range(param: Parameter, rng: Any, steps: Any) -> tuple[Any, ...]:
    if isinstance(param.spec, S.Flag):
        raise SceneError(param.text, "is true or false; give values [true, false] instead of a range")
    if isinstance(param.spec, S.Choice):
        raise SceneError(param.text, f"is a name; give values (a list) instead of a range, {param.spec.range_text()}")
    if not isinstance(rng, list) or len(rng) != 2:
        raise SceneError(param.text, f"range must be [lo, hi], got {_show(rng)}")
    if isinstance(steps, bool) or not isinstance(steps, int):
        raise SceneError(param.text, f"steps must be a whole number, got {_show(steps)}; allowed 1 to {MAX_VARIANTS}")
    if not 1 <= steps <= MAX_VARIANTS:
        raise SceneError(param.text, f"steps {_show(steps)} is out of range; allowed 1 to {MAX_VARIANTS}")
    lo, hi = (check_value(param, v) for v in rng)
    if steps == 1 and lo != hi:
        raise SceneError(param.text, f"steps 1 would give only {format_value(lo)}, not {format_value(hi)}; "
                                     f"allowed 2 to {MAX_VARIANTS} for a range (or give one value)")
    values = []
    for k in range(steps):
        t = k / (steps - 1) if steps > 1 else 0.0
        if param.is_vector:
            v = [_tidy(a + (b - a) * t) for a, b in zip(lo, hi, strict=True)]
        else:
            v = _tidy(lo + (hi - lo) * t)
        values.append(check_value(param, v))
    return tuple(values)


def _tidy(x: float) -> float:
    """1.45 + 0.05 * 1 is 1.4999999999999998; 12 significant digits keep labels and files clean."""
    return float(f"{x:.12g}")


def format_value(value: Any) -> str:
    """A value as cell labels and the CLI print it: 1.5, 0.9/0.1/0.1, on/off."""
    if isinstance(value, bool):
        return "on" if value else "off"
    if isinstance(value, list):
        return "/".join(format_value(v) for v in value)
    if isinstance(value, str):
        return value
    return f"{value:.6g}"


# ---------------------------------------------------------------------------------------------
# The study


@dataclass(frozen=True)
class Variant:
    index: int  # row-major: index = row * columns + column
    column: int  # position along axis 1
    row: int  # position along axis 2 (0 for a one-axis study)
    values: tuple[Any, ...]  # one value per axis
    scene: dict  # the normalised, validated variant scene

    def label(self, study: Study) -> str:
        return "  ".join(f"{a.parameter.short}={a.label(v)}" for a, v in zip(study.axes, self.values, strict=True))


@dataclass(frozen=True)
class Study:
    base: dict  # normalised scene
    axes: tuple[Axis, ...]
    size: tuple[int, int]  # (width, height) of each variant image
    title: str = ""
    variants: tuple[Variant, ...] = ()  # built and checked by ``from_doc``, row-major
    measured: Choice = Choice()  # measures under the cells, sort, filter (``measured``)

    # -- construction ------------------------------------------------------------------------

    @classmethod
    def from_doc(cls, doc: Any) -> Study:
        """Validate a ``lamp-study/1`` document; every variant is built and checked here."""
        if not isinstance(doc, dict):
            raise SceneError("", f"a {SCHEMA} document is a JSON object, got {_show(doc)}")
        if doc.get("schema") != SCHEMA:
            raise SceneError("schema", f"{_show(doc.get('schema'))} is missing or wrong; allowed \"{SCHEMA}\"")
        allowed = ("schema", "title", "base", "axes", "size", "measures", "sort", "filter")
        for key in doc:
            if key not in allowed:
                raise SceneError(show_key(key), f"unknown key; allowed keys here: {', '.join(allowed)}")
        if "base" not in doc:
            raise SceneError("base", "is required: the lamp-scene design the study varies")
        base_doc = doc["base"]
        size = parse_size(doc["size"]) if "size" in doc else framed_size(base_doc)
        if isinstance(base_doc, dict):
            # The variants are rendered at the study's size: a default camera frames the body for it,
            # and a variant kept as a preset says what was rendered.
            image = base_doc.get("image")
            image = {**image} if isinstance(image, dict) else {}
            base_doc = {**base_doc, "image": {**image, "width": size[0], "height": size[1]}}
        try:
            base = parse_scene(base_doc)
        except SceneError as e:
            raise SceneError(f"base.{e.path}" if e.path else "base", e.message) from None
        title = doc.get("title", "")
        if not isinstance(title, str) or len(title) > 200 or has_surrogate(title) or not title.isprintable():
            # A lone surrogate cannot be stored in the sheet's header, and a control character would reach
            # the sheet and the terminal (issue 33): refused now, not after rendering.
            raise SceneError("title", f"expected a string of at most 200 Unicode characters, printable (no control "
                                      f"characters), got {_show(title)}")
        axes_doc = doc.get("axes")
        if not isinstance(axes_doc, list) or not 1 <= len(axes_doc) <= MAX_AXES:
            raise SceneError("axes", f"expected a list of 1 or {MAX_AXES} axes, got {_show(axes_doc)}")
        axes = tuple(parse_axis(a, base, f"axes[{i}]") for i, a in enumerate(axes_doc))
        if len(axes) == 2 and sets_same(axes[0].parameter, axes[1].parameter):
            raise SceneError(axes[1].parameter.text, f"sets what {axes[0].parameter.text} sets (the same field, "
                                                     "the other form of the lens colour, or the lens colour and "
                                                     "bulb a lamp function sets); a study's two axes must vary "
                                                     "different things")
        count = math.prod(len(a.values) for a in axes)
        if count > MAX_VARIANTS:
            shape = " x ".join(str(len(a.values)) for a in axes)
            raise SceneError("axes", f"{shape} = {count} variants; allowed at most {MAX_VARIANTS}")
        budget.check_study_pixels(size, count)
        measured = parse_measures(doc, base)
        variants = _build_variants(base, axes)
        budget.check_study_rays(size, [v.scene["image"]["samples"] for v in variants])
        return cls(base, axes, size, title, variants, measured)

    @classmethod
    def from_json(cls, text: str, name: str = "") -> Study:
        return cls.from_doc(parse_json_text(text, name))

    @classmethod
    def load(cls, path: str | os.PathLike) -> Study:
        """A study from a ``.json`` definition or from the header of a contact sheet (EXR or PNG)."""
        name = os.fspath(path)
        suffix = os.path.splitext(name)[1].lower()
        if suffix in (".exr", ".png"):
            text = _sheet_attribute(name)
            try:
                return cls.from_json(text, f"{name} {STUDY_ATTRIBUTE}")
            except SceneError as e:
                raise SceneError(name, f"{STUDY_ATTRIBUTE} holds no valid study ({e})") from None
        doc = read_json(name)
        try:
            return cls.from_doc(doc)
        except SceneError as e:
            raise SceneError(f"{name}: {e.path}" if e.path else name, e.message) from None

    @classmethod
    def build(cls, base: dict, axes: list[dict], size: tuple[int, int] | None = DEFAULT_SIZE, title: str = "",
              measured: dict | None = None) -> Study:
        """A study from a base scene document and axis documents (the Python API, the CLI, Blender);
        ``size`` None: framed on the lamp (``framed_size``); ``measured``: its ``measures``, ``sort``
        and ``filter`` fields, if any."""
        doc = {"schema": SCHEMA, "base": base, "axes": axes, **({"size": list(size)} if size else {}),
               **(measured or {})}
        if title:
            doc["title"] = title
        return cls.from_doc(doc)

    # -- queries ------------------------------------------------------------------------------

    @property
    def columns(self) -> int:
        return len(self.axes[0].values)

    @property
    def rows(self) -> int:
        return len(self.axes[1].values) if len(self.axes) > 1 else 1

    def __len__(self) -> int:
        return len(self.variants)

    def variant_scene(self, index: int) -> dict:
        """The full scene of one variant (a fresh copy), e.g. to keep it as a preset."""
        v = self.variants[index]
        scene = copy.deepcopy(v.scene)
        scene["name"] = self.variant_name(index)[:S.SCENE.fields["name"].max_len]
        return scene

    def variant_name(self, index: int) -> str:
        return f"{self.base['name']} ({_setting(self.axes, self.variants[index].values)})"

    def heading(self) -> str:
        """The sheet's title: the study's own, else the base design's name."""
        return self.title or f"Study of {self.base['name']}"

    # -- saving -------------------------------------------------------------------------------

    def to_doc(self) -> dict:
        doc: dict = {"schema": SCHEMA}
        if self.title:
            doc["title"] = self.title
        doc["base"] = copy.deepcopy(self.base)
        doc["axes"] = [copy.deepcopy(a.doc) for a in self.axes]
        doc["size"] = list(self.size)
        doc.update(self.measured.to_doc())  # nothing when the study names no measures
        return doc

    def to_json(self) -> str:
        """Canonical JSON text (same layout as scene files)."""
        return scene_to_json(self.to_doc())

    def save(self, path: str | os.PathLike) -> None:
        atomic_write_text(path, self.to_json())

    def save_variants(self, folder: str | os.PathLike) -> list[str]:
        """Write every variant as a ``lamp-scene/1`` preset, ``<folder>/variant-NN.json``; returns the paths."""
        folder = os.fspath(folder)
        os.makedirs(folder, exist_ok=True)
        paths = []
        for v in self.variants:
            path = os.path.join(folder, f"variant-{v.index:02d}.json")
            atomic_write_text(path, scene_to_json(self.variant_scene(v.index)))
            paths.append(path)
        return paths


def _build_variants(base: dict, axes: tuple[Axis, ...]) -> tuple[Variant, ...]:
    """Every variant of ``base`` along ``axes``, each scene checked (``SceneError`` names the variant)."""
    columns = len(axes[0].values)
    out = []
    grids = [range(len(a.values)) for a in axes]
    # Row-major, axis 1 varying fastest: itertools.product varies the last factor fastest.
    for position in itertools.product(*reversed(grids)):
        index_per_axis = tuple(reversed(position))
        values = tuple(a.values[k] for a, k in zip(axes, index_per_axis, strict=True))
        column = index_per_axis[0]
        row = index_per_axis[1] if len(axes) > 1 else 0
        scene = copy.deepcopy(base)
        apply_values(scene, tuple(a.parameter for a in axes), values)
        try:
            scene = parse_scene(scene)
        except SceneError as e:
            raise SceneError(e.path, f"{e.message} (in the variant {_setting(axes, values)})") from None
        out.append(Variant(row * columns + column, column, row, values, scene))
    return tuple(out)


def _setting(axes: tuple[Axis, ...], values: tuple[Any, ...]) -> str:
    return ", ".join(f"{a.parameter.text}={format_value(v)}" for a, v in zip(axes, values, strict=True))


def framed_size(base_doc: Any, pixels: int = DEFAULT_SIZE[0] * DEFAULT_SIZE[1]) -> tuple[int, int]:
    """A cell framed on the lamp when a study gives no size: the body's aspect (its front, width over
    height, a little taller by ``CELL_MARGIN``; at most ``MAX_CELL_ASPECT`` either way) at about
    ``pixels`` pixels (those of ``DEFAULT_SIZE``), even sides, each at least 8 and at most ``MAX_SIZE``.
    A camera fits its field of view to the longer side (``camera.sensor_fit`` auto), so a wide body
    fills the cell's width instead of a band across a square with black above and below (the
    four-lamp combination, 480 x 120 mm: 458 x 144 px, not 256 x 256 with 70 % black).
    ``DEFAULT_SIZE`` when the base is not a valid design (its parse says why)."""
    try:
        width, height = parse_scene(base_doc)["body"]["size"]
    except (SceneError, TypeError, KeyError):
        return DEFAULT_SIZE
    return cell_size(width / height * CELL_MARGIN, pixels)


def cell_size(aspect: float, pixels: int) -> tuple[int, int]:
    """A cell of ``aspect`` (width over height; at most ``MAX_CELL_ASPECT`` either way) at about
    ``pixels`` pixels, even sides, each at least 8 and at most ``MAX_SIZE``."""
    aspect = min(MAX_CELL_ASPECT, max(1.0 / MAX_CELL_ASPECT, aspect))
    return tuple(min(MAX_SIZE, max(8, 2 * round(math.sqrt(pixels * a) / 2))) for a in (aspect, 1.0 / aspect))


def parse_size(value: Any, where: str = "size") -> tuple[int, int]:
    ok = (isinstance(value, list | tuple) and len(value) == 2
          and all(isinstance(v, int) and not isinstance(v, bool) for v in value))
    if not ok:
        raise SceneError(where, f"expected [width, height] in pixels, got {_show(value)}")
    for v in value:
        if not 1 <= v <= MAX_SIZE:
            raise SceneError(where, f"{_show(v)} is out of range; allowed [1, {MAX_SIZE}] px")
    return int(value[0]), int(value[1])


def _sheet_attribute(name: str) -> str:
    from ..images.imageio import read_attribute  # on use: a study without sheets needs no OpenImageIO

    text = read_attribute(name, STUDY_ATTRIBUTE)
    if not isinstance(text, str):
        raise SceneError(name, f"the image carries no study (no {STUDY_ATTRIBUTE} attribute)")
    return text


# ---------------------------------------------------------------------------------------------
# The command line's --vary syntax


def parse_vary(text: str) -> dict:
    """``lens.ior=1.45:1.60:4`` (lo:hi:steps, inclusive), ``lens.ior=1.45,1.5,1.55`` (a list),
    ``lens.transmitted_color=0.9/0.1/0.1,0.9/0.5/0.05`` (vectors with /), ``bulb.on=on,off``.
    Returns an axis document; the values are checked when the study is built."""
    name, sep, spec_text = text.partition("=")
    name = name.strip()
    if not sep or not name or not spec_text.strip():
        raise SceneError("--vary", f"{text!r} is not PARAMETER=LO:HI:STEPS or PARAMETER=V1,V2,...")
    spec_text = spec_text.strip()
    if ":" in spec_text and _is_choice(name):
        raise SceneError(name, f"is a name; give values (a list) instead of a range, "
                               f"{resolve_parameter(name).spec.range_text()}")
    if ":" in spec_text:
        parts = spec_text.split(":")
        if len(parts) != 3:
            raise SceneError(name, f"{spec_text!r} is not LO:HI:STEPS (e.g. 1.45:1.6:4)")
        lo, hi = _parse_item(name, parts[0]), _parse_item(name, parts[1])
        try:
            steps = int(parts[2])
        except ValueError:
            raise SceneError(name, f"steps {parts[2]!r} is not a whole number; allowed 1 to {MAX_VARIANTS}") from None
        return {"parameter": name, "range": [lo, hi], "steps": steps}
    if _is_choice(name):
        return {"parameter": name, "values": [item.strip() for item in spec_text.split(",")]}
    return {"parameter": name, "values": [_parse_item(name, item) for item in spec_text.split(",")]}


def _is_choice(name: str) -> bool:
    """Whether ``name`` is a choice a study varies by name (``environment.world``, ``lamps[1].cuts.type``)."""
    try:
        return isinstance(resolve_parameter(name).spec, S.Choice)
    except SceneError:  # not a parameter at all: said when the study is built
        return False


def _parse_item(name: str, item: str) -> Any:
    item = item.strip()
    if "/" in item:
        return [parse_number(name, x) for x in item.split("/")]
    if item.lower() in ("on", "true"):
        return True
    if item.lower() in ("off", "false"):
        return False
    return parse_number(name, item)


_show = show_value

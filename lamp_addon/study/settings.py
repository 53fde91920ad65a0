# SPDX-License-Identifier: GPL-3.0-or-later
"""The settings of a design study (``Scene.lamp_study``) and the study they describe.

For each axis a parameter (every field that ``core_tracer.study`` can vary: numbers, switches and
choices such as the cut type, lamp fields for all lamps or for one), and its values as a range with
a number of steps or as a list written as on the command line (``1.45, 1.5``; for colours and other
vectors ``0.9/0.1/0.1, 0.9/0.5/0.05``; for choices their names, ``fisheye, sawtooth``);
the size of each variant and the number of worker processes. ``study_from_settings`` turns them into
a ``core_tracer.study.Study`` of the current design; ``last_study`` is the study of the sheet shown.
Both the panel (``study.panel``) and the operators (``study.ops``) sit above this module.
"""

from __future__ import annotations

from dataclasses import dataclass

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty, PointerProperty, StringProperty

from ...core_tracer.scene import spec as S
from ...core_tracer.scene.functions import suggested_values
from ...core_tracer.scene.reading import SceneError
from ...core_tracer.study import definition as st
from ...core_tracer.study.parameters import resolve_parameter, study_parameters
from ..convert import camera as cm
from ..design import camera as render_camera
from ..design import photometric_words
from ..design import properties as design_properties
from ..freeform import written as freeform_written
from ..scene_settings import SceneSettings

ALL_LAMPS = "ALL"
SHEET_IMAGE = "Lamp Study"
STUDY_PROPERTY = "lamp_study"  # custom property of the sheet image: the study's JSON, so it can be re-run


def parameter_spec(path: str) -> S.Spec:
    """The field declaration of a study parameter (a lamp's, the scene's or a free-form part's)."""
    return resolve_parameter(path).spec


def _parameter_label(path: str) -> str:
    param = resolve_parameter(path)
    spec = param.spec
    *parents, key = param.keys
    unit = spec.unit if isinstance(spec, S.Num) else ""
    prefix = " ".join(design_properties.display_name(p) for p in parents)
    if param.part_scope:  # a free-form part's value, under its role: "Free-form Lens: Filter"
        prefix = f"Free-form {prefix}"
    parent = param.section
    rule = parent.rule_of(key) if isinstance(parent, S.Section) else None
    if rule is not None and rule.of_key(key).name == key:  # the field that picks a form: the form's name
        label = rule.of_key(key).label
    elif isinstance(parent, S.Section) and photometric_words.label(parent, key) is not None:
        words = photometric_words.label(parent, key)  # a photometric field's own words ("Bulb: Bulb Type")
        label = f"{words} ({unit})" if unit else words
    else:
        label = design_properties.display_name(key, unit)
    return f"{prefix}: {label}" if prefix else label


def _parameter_items() -> tuple[tuple[str, str, str], ...]:
    items = []
    for path in study_parameters():  # a free-form part's values too (every part of its role)
        spec = parameter_spec(path)
        vector = isinstance(spec, S.Num) and spec.size > 1
        how = "a list of values written a/b/c" if vector else "a list of names" if isinstance(spec, S.Choice) \
            else "a range or a list"
        items.append((path, _parameter_label(path), f"{spec.doc}. Allowed: {spec.range_text()}; {how}"))
    return tuple(items)


PARAMETER_ITEMS = _parameter_items()
LAMP_ITEMS = ((ALL_LAMPS, "All Lamps", "Change the parameter of every lamp"),
              *((str(i), f"Lamp {i + 1}", f"Change the parameter of lamp {i + 1} only") for i in range(S.MAX_LAMPS)))
MODE_ITEMS = (("RANGE", "Range", "From a first to a last value in a number of equal steps"),
              ("LIST", "List", "Values separated by commas; vectors and colours as a/b/c"))


def uses_cluster(settings) -> bool:
    """Whether the study renders on a Dask scheduler (an address) rather than this computer's workers."""
    return settings.scheduler.strip().lower() not in ("", "local")


def is_single_number(path: str) -> bool:
    spec = parameter_spec(path)
    return isinstance(spec, S.Num) and spec.size == 1


def is_lamp_parameter(path: str) -> bool:
    return path.split(".")[0] in S.LAMP.fields


def _suggest_range(self, context) -> None:
    """A new parameter gets a range around its default, inside its allowed range."""
    spec = parameter_spec(self.parameter)
    if isinstance(spec, S.Num) and spec.size == 1:
        lo, hi = design_properties.blender_range(spec)
        d = float(spec.default)
        span = abs(d) * 0.25 or 1.0
        self.start = max(d - span, lo) if lo is not None else d - span
        self.stop = min(d + span, hi) if hi is not None else d + span
        self.mode = "RANGE"
    else:
        self.mode = "LIST"
        if isinstance(spec, S.Flag):
            self.values = "on, off"
        elif self.parameter == "environment.world":  # the surroundings: by day, in the evening, at night
            self.values = "city, sunset, night"
        elif isinstance(spec, S.Choice):  # the kinds of lamp side by side: every name the field allows
            self.values = ", ".join(spec.choices)
        else:  # a vector: the values the lamp functions give it (red, amber, clear lenses), else its default
            values = suggested_values(self.parameter) or [list(spec.default)]
            self.values = ", ".join(st.format_value(v) for v in values)


def _axis_group(name: str, parameter: str, start: float, stop: float) -> type:
    annotations = {
        "parameter": EnumProperty(name="Parameter", items=PARAMETER_ITEMS, default=parameter,
                                  description="The field of the design this axis varies", update=_suggest_range),
        "lamp": EnumProperty(name="Lamp", items=LAMP_ITEMS, default=ALL_LAMPS,
                             description="Which lamp a lamp parameter changes"),
        "mode": EnumProperty(name="Values", items=MODE_ITEMS, default="RANGE"),
        "start": FloatProperty(name="From", default=start, precision=4,
                               description="First value of the range"),
        "stop": FloatProperty(name="To", default=stop, precision=4, description="Last value of the range"),
        "steps": IntProperty(name="Steps", default=4, min=1, max=st.MAX_VARIANTS,
                             description="Number of values from the first to the last, both included"),
        "values": StringProperty(name="Values", default="",
                                 description="Values separated by commas, e.g. 1.45, 1.5; colours and other "
                                             "vectors as 0.9/0.1/0.1, 0.9/0.5/0.05"),
    }
    return type(name, (bpy.types.PropertyGroup,), {"__annotations__": annotations})


LAMP_PG_study_axis_1 = _axis_group("LAMP_PG_study_axis_1", "lens.ior", 1.45, 1.6)
LAMP_PG_study_axis_2 = _axis_group("LAMP_PG_study_axis_2", "cuts.height", 0.5, 2.0)


class LAMP_PG_study(SceneSettings, bpy.types.PropertyGroup):
    scene_attribute = "lamp_study"
    scene_name = "Lamp Study"
    scene_description = "Settings of the design study"

    axis_1: PointerProperty(type=LAMP_PG_study_axis_1, name="Columns")
    use_axis_2: BoolProperty(name="Second Parameter", default=True,
                             description="Vary a second parameter down the rows of the sheet")
    axis_2: PointerProperty(type=LAMP_PG_study_axis_2, name="Rows")
    width: IntProperty(name="Width", default=128, min=8, max=st.MAX_SIZE, subtype="PIXEL",
                       description="Width of each variant image")
    height: IntProperty(name="Height", default=128, min=8, max=st.MAX_SIZE, subtype="PIXEL",
                        description="Height of each variant image")
    fit_lamp: BoolProperty(name="Fit to Lamp", default=True,
                           description="Give each cell the lamp body's aspect, with as many pixels as Width x "
                                       "Height, so the lamp fills it instead of a band with black around it")
    workers: IntProperty(name="Workers", default=0, min=0, max=256,
                         description="Worker processes rendering the variants (0: one per core)")
    scheduler: StringProperty(name="Scheduler", default="local", maxlen=300,
                              description="Where the variants render: \"local\" (worker processes on this "
                                          "computer) or a Dask scheduler's address, tcp://HOST:8786, to render "
                                          "them as tasks on the studio's cluster (docs/cluster.md)")
    measures: StringProperty(name="Measures", default="", maxlen=400,
                             description="Measures to put under each cell, separated by commas (photometric designs; "
                                         "e.g. homogeneity.lmin_lmax, grid.min_margin, intensity.hv_cd@stop: "
                                         "docs/measures.md); each variant is measured, tens of seconds each")
    sort_by: StringProperty(name="Sort By", default="", maxlen=100,
                            description="Order the cells by a measure, highest first with a leading \"-\" "
                                        "(e.g. -homogeneity.lmin_lmax); empty keeps the grid")
    filter: StringProperty(name="Filter", default="", maxlen=300,
                           description="Keep the variants where a measure holds, e.g. grid.pass==1 (several separated "
                                       "by commas); the others are listed under the sheet")
    variant: IntProperty(name="Variant", default=1, min=1, max=st.MAX_VARIANTS,
                         description="A variant of the last study (numbered along the rows of the sheet)")


def axis_doc(axis) -> dict:
    """One axis of the settings as a ``lamp-study/1`` axis document (checked when the study is built)."""
    path = axis.parameter
    if axis.lamp != ALL_LAMPS and is_lamp_parameter(path):
        path = f"lamps[{axis.lamp}].{path}"
    # Only a single number has a range; the others take the list the panel shows for them. The range's
    # values are rounded to 4 significant digits, so a sheet says "0.7143", not "0.714286", and
    # renders exactly the values it says.
    if axis.mode == "RANGE" and is_single_number(axis.parameter):
        steps = axis.steps
        values = [axis.start + (axis.stop - axis.start) * i / (steps - 1) for i in range(steps)] if steps > 1 \
            else [axis.start]
        if parameter_spec(axis.parameter).integer:
            return {"parameter": path, "range": [axis.start, axis.stop], "steps": axis.steps}
        return {"parameter": path, "values": [float(f"{v:.4g}") for v in values]}
    if not axis.values.strip():
        raise SceneError(path, "has no values; write them separated by commas")
    return st.parse_vary(f"{path}={axis.values}")


def study_from_settings(bl_scene) -> st.Study:
    """The study the settings describe, of the scene's current design seen through its camera; with
    free-form parts, of the design F12 renders, its meshes written to a file (``study.meshes``).
    Raises ``SceneError`` (with the parameter, value and range) for a bad setting or design."""
    settings = bl_scene.lamp_study
    parts = freeform_written.shown_parts(bl_scene)
    size = (settings.width, settings.height)
    if settings.fit_lamp and parts:  # the parts' view as F12 frames it, at the pixels asked for
        aspect = bl_scene.render.resolution_x / bl_scene.render.resolution_y
        size = st.cell_size(aspect, settings.width * settings.height)
    elif settings.fit_lamp:  # the body's aspect at the pixels asked for (st.framed_size)
        size = st.framed_size(design_properties.design_to_scene(bl_scene), settings.width * settings.height)
    if bl_scene.camera is not None:
        base = render_camera.scene_for_render(bl_scene, size=size)
    else:  # no scene camera: the design's own camera section
        base = design_properties.design_to_scene(bl_scene)
        base["image"] = {**base["image"], "width": size[0], "height": size[1]}
    if parts:  # the parts are the lamp: the view F12 shows of them, not one framed on the hidden body
        base = freeform_written.with_parts(bl_scene, base, parts)
    elif bl_scene.camera is None or render_camera.is_lamp_camera(bl_scene.camera):
        # The add-on's own view: each cell frames the lamp's body at the cell's size (a camera of the
        # designer's own is their choice of view, kept as it is).
        base["camera"] = cm.frame_view(base["camera"], cm.body_box(base), size)
    axes = [axis_doc(settings.axis_1)]
    if settings.use_axis_2:
        axes.append(axis_doc(settings.axis_2))
    try:
        return st.Study.build(base, axes, size, measured=measured_doc(settings))
    except SceneError as e:
        for field, words in MEASURE_WORDS.items():
            if e.path == field or e.path.startswith(f"{field}["):
                raise SceneError(words, e.message) from None
        raise


# The study fields of the measures in the panel's words (errors name them so)
MEASURE_WORDS = {"measures": "Measures", "sort": "Sort By", "filter": "Filter"}


def measured_doc(settings) -> dict:
    """The ``measures``, ``sort`` and ``filter`` fields of the settings (none when they are empty, so a
    study without measures is what it always was)."""
    doc: dict = {}
    measures = [m.strip() for m in settings.measures.split(",") if m.strip()]
    filters = [f.strip() for f in settings.filter.split(",") if f.strip()]
    if measures:
        doc["measures"] = measures
    if settings.sort_by.strip():
        doc["sort"] = settings.sort_by.strip()
    if filters:
        doc["filter"] = filters
    return doc


def worded(study: st.Study) -> st.Study:
    """``study`` with its parameters named in the panel's words for the sheet's labels ("Lens › IOR"
    over the columns, "Lens IOR=1.5" under a cell; "Lamp 1 › Function" for one lamp's field). The
    study itself (its JSON, its variants) is unchanged."""
    from dataclasses import fields, replace

    from ...core_tracer.study.parameters import Parameter
    from ..design import validity

    @dataclass(frozen=True)
    class Worded(Parameter):
        words: str = ""

        @property
        def short(self) -> str:
            return self.words

    axes = []
    for axis in study.axes:
        p = axis.parameter
        full = validity.field_words(p.text) or p.text
        if p.part_scope:  # "Free-form Parts › Lens › Filter": the role's field as a lamp's is worded
            field = ".".join(p.keys)
            whose = "Free-form Parts" if p.part is None else f"Free-form Part {p.part + 1}"
            full = f"{whose}{validity.SEPARATOR}{validity.field_words(field) or field}"
        words = [w for w in full.split(validity.SEPARATOR) if not w.startswith("Lamp ")]
        short = " ".join(words[-2:])  # "Bulb On", "Cuts Height", "Function"
        if p.component is not None:
            short += f" {'XYZ'[p.component] if p.component < 3 else p.component}"
        values = {f.name: getattr(p, f.name) for f in fields(p)}
        axes.append(replace(axis, parameter=Worded(**{**values, "text": full}, words=short)))
    return replace(study, axes=tuple(axes))


# ---------------------------------------------------------------------------------------------
# The sheet image and its study

_cache: dict[str, object] = {"json": None, "study": None}


def sheet_image() -> bpy.types.Image | None:
    return bpy.data.images.get(SHEET_IMAGE)


def last_study() -> st.Study | None:
    """The study of the "Lamp Study" image (parsed once per study, then cached)."""
    image = sheet_image()
    text = image.get(STUDY_PROPERTY) if image is not None else None
    if not isinstance(text, str):
        return None
    if _cache["json"] != text:
        try:
            study = st.Study.from_json(text, STUDY_PROPERTY)
        except SceneError:
            study = None
        _cache.update(json=text, study=study)
    return _cache["study"]  # type: ignore[return-value]


def remember_study(study: st.Study, text: str) -> None:
    """The study whose sheet was just stored with ``text``: no need to parse it again."""
    _cache.update(json=text, study=study)


classes = (LAMP_PG_study_axis_1, LAMP_PG_study_axis_2, LAMP_PG_study)


register, _unregister_classes = bpy.utils.register_classes_factory(classes)


def unregister() -> None:
    _unregister_classes()
    _cache.update(json=None, study=None)  # the cached study belongs to this registration

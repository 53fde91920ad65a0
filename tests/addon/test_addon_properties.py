"""The design properties follow core_tracer.spec and convert to and from scene JSON without loss."""

from __future__ import annotations

import copy
import json
import math
import re

import pytest
from helpers import BASELINE, PARAMETRIC_PRESETS

pytestmark = pytest.mark.blender

PRESETS = PARAMETRIC_PRESETS


@pytest.fixture
def S(addon_core):
    """The add-on's own ``core_tracer.spec`` (its classes are not the top-level package's)."""
    return addon_core.scene.spec


@pytest.fixture
def scene_mod(addon_core):
    return addon_core.scene


def _group_rna(lamp_addon, path: str):
    """The RNA property of a spec path like ``lamps[].lens.ior`` on the generated groups."""
    props = lamp_addon.design.properties
    cls = props.LampDesign
    parts = path.replace("[]", "").split(".")
    for part in parts[:-1]:
        cls = _rna(cls, part).fixed_type
    return _rna(cls, props.property_id(parts[-1]))


def _rna(cls, key: str):
    return cls.bl_rna.properties[key]


def test_every_spec_field_is_a_property(lamp_addon, S):
    for info in S.iter_fields():
        if lamp_addon.design.properties.is_constant(info.spec):
            continue
        rna = _group_rna(lamp_addon, info.path)
        words = lamp_addon.design.words
        assert rna.description.startswith(words.designer_text(info.spec.doc).partition(". Paper: ")[0]), info.path
        if not isinstance(info.spec, S.Tags):
            assert rna.description == words.tooltip(info.spec), info.path
        assert not re.search(r"\b[a-z]+_[a-z0-9_]+\b|[\[(]-?[0-9.e+]+, -?[0-9.e+]+[\])]", rna.description), (
            info.path, rna.description)  # no snake_case, no interval notation
        if isinstance(info.spec, S.Num):
            kind = "INT" if info.spec.integer else "FLOAT"
            assert rna.type == kind, info.path
            assert rna.array_length == (info.spec.size if info.spec.size > 1 else 0), info.path
            if info.spec.unit:
                assert rna.name.endswith(f"({info.spec.unit})"), (info.path, rna.name)
            if info.spec.subtype == "color":
                assert rna.subtype == "COLOR", info.path
        elif isinstance(info.spec, S.Choice):
            assert rna.type == "ENUM"
            assert [item.identifier for item in rna.enum_items] == list(info.spec.choices)
        elif isinstance(info.spec, S.Flag):
            assert rna.type == "BOOLEAN"
        else:
            assert rna.type == "STRING", info.path


def test_ranges_and_defaults_follow_the_spec(lamp_addon, S):
    """Soft limits from the spec (an open bound just inside it); no hard limits, so Blender keeps a
    value typed outside the range and the design's check refuses it (never clamped)."""
    margin = lamp_addon.design.properties.OPEN_BOUND_MARGIN
    for info in S.iter_fields():
        spec = info.spec
        if not isinstance(spec, S.Num):
            continue
        rna = _group_rna(lamp_addon, info.path)
        if spec.lo is not None:
            lo = spec.lo + (margin * max(1.0, abs(spec.lo)) if spec.lo_open else 0.0)
            assert rna.soft_min == pytest.approx(lo, rel=1e-6, abs=1e-12), info.path
            assert rna.hard_min < min(spec.lo, -1e9), info.path
        if spec.hi is not None:
            assert rna.soft_max == pytest.approx(spec.hi, rel=1e-6), info.path
            assert rna.hard_max > max(spec.hi, 1e9), info.path
        default = rna.default_array[:] if spec.size > 1 else rna.default
        expected = spec.default if spec.size > 1 else [spec.default]
        got = list(default) if spec.size > 1 else [default]
        assert got == pytest.approx(list(expected), rel=1e-6), info.path


def test_a_value_out_of_range_is_kept_and_refused_never_clamped(lamp_addon, bl_scene, S):
    """Issue 31: a negative lens thickness was clamped to 1e-6 mm and the panel said "Design is
    valid". Blender keeps what was typed; the check names the field and its range in the panel's words."""
    design = bl_scene.lamp_design
    lens = design.lamps.add().lens
    lens.thickness = -2.0
    assert lens.thickness == -2.0
    problem = lamp_addon.design.validity.status(bl_scene).problem
    assert problem.text() == "Lamp 1 › Lens › Thickness: -2.0 is out of range; allowed (0, 100] mm"
    lens.thickness = 3.0
    lens.ior = 0.5
    assert lens.ior == 0.5
    validity = lamp_addon.design.validity
    assert validity.status(bl_scene).problem.text().startswith("Lamp 1 › Lens › IOR: 0.5 is out of range")
    lens.ior = 1.49
    design.image.width = 100000
    assert design.image.width == 100000
    assert "allowed [1, 8192]" in validity.status(bl_scene).problem.text()


def test_a_preset_value_blender_cannot_hold_is_refused(lamp_addon, bl_scene, scene_mod, addon_core):
    """A value that rounds out of its range in Blender's 32-bit float is refused before anything is written."""
    scene = scene_mod.load_scene(PRESETS[0])
    scene["lamps"][0]["lens"]["thickness"] = 1e-50  # valid, (0, 100] mm, but 0 in 32 bits
    with pytest.raises(addon_core.scene.reading.SceneError, match="32-bit"):
        lamp_addon.design.properties.scene_to_design(bl_scene, scene)


def test_there_are_presets():
    assert PRESETS, "presets/*.json is empty"


@pytest.mark.parametrize("path", PRESETS, ids=lambda p: p.name)
def test_preset_round_trip(lamp_addon, bl_scene, path, scene_mod):
    """JSON -> properties -> JSON is lossless, and the text is the same canonical text."""
    scene = scene_mod.load_scene(path)
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    back = lamp_addon.design.properties.design_to_scene(bl_scene)
    assert back == scene
    assert scene_mod.scene_to_json(back) == scene_mod.scene_to_json(scene)
    # ... and again through the properties (the second pass sees the rounded values)
    lamp_addon.design.properties.scene_to_design(bl_scene, back)
    assert lamp_addon.design.properties.design_to_scene(bl_scene) == scene


def test_float32_values_come_back_as_written(lamp_addon):
    from_float32 = lamp_addon.design.properties.from_float32
    import struct

    for x in (1.49, 0.62, 0.02, 860.96, -1234.567, 1e-6, 99999.9, 0.1 + 0.2, 1 / 3):
        stored = struct.unpack("<f", struct.pack("<f", x))[0]
        y = from_float32(stored)
        assert struct.pack("<f", y) == struct.pack("<f", x)
        if len(f"{x:.7g}".rstrip("0")) <= 8:
            assert y == float(f"{x:.7g}")
    assert from_float32(struct.unpack("<f", struct.pack("<f", 1.49))[0]) == 1.49


def test_lens_colour_modes(lamp_addon, bl_scene, S, scene_mod):
    props = lamp_addon.design.properties
    scene = scene_mod.parse_scene({"schema": S.SCHEMA, "lamps": [
        {"lens": {"transmitted_color": [0.9, 0.4, 0.1], "reference_thickness": 2.5}},
    ]})
    props.scene_to_design(bl_scene, scene)
    lens = bl_scene.lamp_design.lamps[0].lens
    assert lens.color_mode == "transmitted_color"
    assert tuple(round(c, 6) for c in lens.transmitted_color) == (0.9, 0.4, 0.1)
    out = props.design_to_scene(bl_scene)["lamps"][0]["lens"]
    assert "absorption" not in out
    assert out["transmitted_color"] == [0.9, 0.4, 0.1] and out["reference_thickness"] == 2.5

    # Switching the mode writes the other form only; both sets of values are kept on the lens.
    lens.color_mode = "absorption"
    out = props.design_to_scene(bl_scene)["lamps"][0]["lens"]
    assert "transmitted_color" not in out and "reference_thickness" not in out
    assert out["absorption"] == list(S.LENS.fields["absorption"].default)
    lens.absorption = (0.1, 0.2, 0.3)
    lens.color_mode = "transmitted_color"
    assert props.design_to_scene(bl_scene)["lamps"][0]["lens"]["transmitted_color"] == [0.9, 0.4, 0.1]

    # The two forms describe the same absorption when they should.
    lens.transmitted_color = [math.exp(-0.1 * 2.5), math.exp(-0.2 * 2.5), math.exp(-0.3 * 2.5)]
    a = scene_mod.lens_absorption(props.design_to_scene(bl_scene)["lamps"][0]["lens"])
    assert a == pytest.approx([0.1, 0.2, 0.3], rel=1e-5)


def test_scene_to_design_is_all_or_nothing(lamp_addon, addon_core, bl_scene, scene_mod):
    props = lamp_addon.design.properties
    good = scene_mod.load_scene(PRESETS[0])
    props.scene_to_design(bl_scene, good)
    before = props.design_to_scene(bl_scene)

    bad = copy.deepcopy(good)
    bad["name"] = "changed"
    bad["lamps"][0]["lens"]["ior"] = 0.5
    with pytest.raises(addon_core.SceneError, match=r"lamps\[0\]\.lens\.ior: 0\.5 is out of range"):
        props.scene_to_design(bl_scene, bad)
    assert props.design_to_scene(bl_scene) == before

    bad = copy.deepcopy(good)
    bad["tags"] = ["red", "tail, stop"]
    with pytest.raises(addon_core.SceneError, match="tags"):
        props.scene_to_design(bl_scene, bad)
    assert props.design_to_scene(bl_scene) == before

    too_many = copy.deepcopy(good)
    too_many["lamps"] = too_many["lamps"] * 5
    with pytest.raises(addon_core.SceneError, match="lamps"):
        props.scene_to_design(bl_scene, too_many)
    assert len(bl_scene.lamp_design.lamps) == len(good["lamps"])


def test_design_to_scene_reports_the_field(lamp_addon, addon_core, bl_scene):
    props = lamp_addon.design.properties
    design = bl_scene.lamp_design
    with pytest.raises(addon_core.SceneError, match="lamps"):
        props.design_to_scene(bl_scene)  # no lamp yet
    design.lamps.add()
    design.lamps.add()  # both at the default centre: they overlap
    with pytest.raises(addon_core.SceneError, match=r"lamps\[1\]\.center"):
        props.design_to_scene(bl_scene)


def test_default_design_is_valid_and_matches_the_spec(lamp_addon, bl_scene, S, scene_mod):
    """Fresh properties hold the spec defaults, every either/or rule in its preferred form (the lens
    colour picker); with one lamp they are a valid scene."""
    bl_scene.lamp_design.lamps.add()
    scene = lamp_addon.design.properties.design_to_scene(bl_scene)
    expected = scene_mod.parse_scene({"schema": S.SCHEMA, "camera": {}, "lamps": [{"lens": {
        "transmitted_color": list(S.LENS.fields["transmitted_color"].default)}}]})
    assert scene == expected
    assert scene["lamps"][0] == scene_mod.new_lamp()


def test_tags_and_text(lamp_addon, bl_scene, S, scene_mod):
    props = lamp_addon.design.properties
    scene = scene_mod.parse_scene({"schema": S.SCHEMA, "name": "Ünïcode lamp ✓", "tags": ["a b", "c"],
                                   "description": "line one\nline two", "lamps": [{}]})
    props.scene_to_design(bl_scene, scene)
    assert bl_scene.lamp_design.tags == "a b, c"
    assert props.design_to_scene(bl_scene) == scene
    bl_scene.lamp_design.tags = " x ,, y,"
    assert props.design_to_scene(bl_scene)["tags"] == ["x", "y"]
    assert json.loads(scene_mod.scene_to_json(props.design_to_scene(bl_scene)))["name"] == "Ünïcode lamp ✓"


def test_an_image_size_out_of_range_is_not_clamped_through_the_render_resolution(lamp_addon, bl_scene, scene_mod):
    """The design's image size is Blender's render resolution (``design.view_link``): a width out of
    range is not handed to Blender, whose resolution would clamp it and write the clamped size back."""
    import bpy

    lamp_addon.design.properties.scene_to_design(bl_scene, scene_mod.load_scene(BASELINE))
    lamp_addon.design.lamp_camera.ensure_lamp_camera(bl_scene)
    before = bl_scene.render.resolution_x
    bl_scene.lamp_design.image.width = -5
    assert bpy.ops.lamp.lamp_add() == {"FINISHED"}  # frames the view again and syncs the link
    lamp_addon.design.view_link.sync_view(bl_scene)
    assert bl_scene.lamp_design.image.width == -5 and bl_scene.render.resolution_x == before
    text = lamp_addon.design.validity.status(bl_scene).problem.text()
    assert text == "Camera & Image › Width: -5 is out of range; allowed [1, 8192] px"
    bl_scene.lamp_design.image.width = 200
    lamp_addon.design.view_link.sync_view(bl_scene)
    assert bl_scene.render.resolution_x == 200

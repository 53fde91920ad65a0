"""The lens colour's either/or rule is declared once (spec.LENS.one_of) and the validator, the
study parameters and the field table of docs/scene-format.md follow it."""

import json

import pytest
from helpers import BASELINE, ROOT

from core_tracer.scene import fields_doc
from core_tracer.scene import spec as S
from core_tracer.scene.derived import without_defaults
from core_tracer.scene.reading import SceneError
from core_tracer.scene.validate import parse_scene
from core_tracer.study import definition as st

RULE = S.LENS.one_of[0]


def _lens(**lens) -> dict:
    doc = json.loads(BASELINE.read_text())
    for key in RULE.keys:
        doc["lamps"][0]["lens"].pop(key, None)
    doc["lamps"][0]["lens"].update(lens)
    return doc


def test_the_rule_names_the_lens_colour_forms():
    assert [alt.keys for alt in RULE.alternatives] == [("transmitted_color", "reference_thickness"), ("absorption",)]
    assert RULE.default == "absorption"  # what a document without either meant before the rule existed
    assert RULE.preferred == "transmitted_color"  # the colour picker, for new designs
    assert all(S.LENS.may_be_absent(key) for key in RULE.keys)


def test_two_forms_together_are_refused_naming_the_second():
    with pytest.raises(SceneError) as info:
        parse_scene(_lens(absorption=[0.1, 0.1, 0.1], transmitted_color=[0.9, 0.1, 0.1]))
    assert info.value.path == "lamps[0].lens.absorption"
    assert "either transmitted_color (with reference_thickness) or absorption" in info.value.message


def test_a_field_without_the_one_that_picks_its_form_is_refused():
    with pytest.raises(SceneError) as info:
        parse_scene(_lens(reference_thickness=2.0))
    assert info.value.path == "lamps[0].lens.reference_thickness"
    assert "only allowed with transmitted_color" in info.value.message


def test_missing_fields_of_a_form_are_filled_as_declared():
    lens = parse_scene(_lens(transmitted_color=[0.9, 0.1, 0.1]))["lamps"][0]["lens"]
    assert lens["reference_thickness"] == lens["thickness"]  # same_as=("reference_thickness", "thickness")
    assert "absorption" not in lens
    lens = parse_scene(_lens())["lamps"][0]["lens"]
    assert lens["absorption"] == list(S.LENS.fields["absorption"].default) and "transmitted_color" not in lens


def test_study_axes_follow_the_rule():
    base = parse_scene(_lens())
    # a field of a form that only goes with another field: refused while the base uses the other form
    with pytest.raises(SceneError, match="only applies where lens.transmitted_color is given"):
        st.Study.build(base, [{"parameter": "lens.reference_thickness", "values": [2.0]}])
    # two forms of the rule on two axes set the same thing
    with pytest.raises(SceneError, match="the other form of the lens colour"):
        st.Study.build(base, [{"parameter": "lens.absorption", "values": [[0.1, 1, 1]]},
                              {"parameter": "lamps[0].lens.transmitted_color", "values": [[0.9, 0.1, 0.1]]}])


def test_the_scene_format_doc_states_the_rule_from_the_spec():
    table = fields_doc.field_table()
    assert f"- `lamps[].lens`: {RULE.doc.lower()}: {RULE.range_text()}" in table
    assert "| `lamps[].lens.reference_thickness` | mm | (0, 100] | `thickness` |" in table
    assert table in (ROOT / "docs" / "scene-format.md").read_text()


def test_a_defaulted_field_does_not_change_the_thumbnail_hash():
    scene = parse_scene(json.loads(BASELINE.read_text()))
    stripped = without_defaults(scene)
    assert "function" not in stripped["lamps"][0]  # at its default
    assert "absorption" in stripped["lamps"][0]["lens"]  # a form is always kept
    assert parse_scene(stripped) == scene

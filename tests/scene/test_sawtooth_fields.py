"""The cut type's fields: defaults that keep the paper's fish-eye lamp, the tooth angle's limit
that depends on the pitch, and bad input refused in one line naming the field."""

import json
import math

import pytest
from helpers import BASELINE, assert_bad_input, run_cli

from core_tracer.scene.derived import cut_depth, lamp_geometry
from core_tracer.scene.limits import lamp_limits
from core_tracer.scene.reading import SceneError
from core_tracer.scene.validate import parse_scene


def _doc() -> dict:
    return json.loads(BASELINE.read_text())


def test_a_document_without_a_cut_type_has_fisheye_cuts_of_its_height():
    lamp = parse_scene(_doc())["lamps"][0]
    assert lamp["cuts"]["type"] == "fisheye"
    assert cut_depth(lamp["cuts"]) == lamp["cuts"]["height"]


def test_sawtooth_ridges_stand_pitch_tan_angle_high_and_move_the_reflector_back():
    doc = _doc()
    doc["lamps"][0]["cuts"].update(type="sawtooth", pitch=6.0, tooth_angle=30.0)
    lamp = parse_scene(doc)["lamps"][0]
    g = lamp_geometry(lamp)
    assert g["plane_b"] - g["plane_a"] == pytest.approx(6.0 * math.tan(math.radians(30.0)), rel=1e-15)
    assert g["rim"] == g["plane_b"] + lamp["reflector"]["gap"]


def test_a_fisheye_height_beyond_the_hemisphere_is_not_checked_on_a_sawtooth_lamp():
    doc = _doc()
    doc["lamps"][0]["cuts"].update(type="sawtooth", pitch=9.0, height=7.0)  # > 9 / sqrt 2, unused
    parse_scene(doc)


def test_too_steep_teeth_for_the_pitch_name_the_tooth_angle_and_its_range():
    doc = _doc()
    doc["lamps"][0]["cuts"].update(type="sawtooth", pitch=90.0, tooth_angle=55.0)
    with pytest.raises(SceneError) as info:
        parse_scene(doc)
    err = info.value
    assert err.path == "lamps[0].cuts.tooth_angle" and "allowed [0, 48" in err.message, str(err)
    hi = float(err.message.split("allowed [0, ")[1].split("]")[0])
    assert 0 <= math.degrees(math.atan(100 / 90)) - hi < 0.01  # rounded down to 4 digits
    assert lamp_limits(doc, 0)["cuts.tooth_angle"].startswith(f"at most {hi:g} deg")
    doc["lamps"][0]["cuts"]["tooth_angle"] = hi
    doc["lamps"][0]["reflector"]["gap"] = 0.0
    with pytest.raises(SceneError) as info:  # the tall ridges push the reflector back: the body is next
        parse_scene(doc)
    assert "tooth_angle" not in info.value.path


@pytest.mark.slow
@pytest.mark.parametrize("edit, needles", [
    ({"type": "pillow"}, ("lamps[0].cuts.type", '"fisheye", "sawtooth"')),
    ({"type": "sawtooth", "tooth_angle": 75}, ("lamps[0].cuts.tooth_angle", "[0, 60] deg")),
    ({"type": "sawtooth", "orientation": 200}, ("lamps[0].cuts.orientation", "[-180, 180] deg")),
    ({"type": "sawtooth", "pitch": 80, "tooth_angle": 59}, ("lamps[0].cuts.tooth_angle", "allowed [0, 51.34] deg")),
])
def test_the_command_line_refuses_bad_saw_tooth_fields_in_one_line(tmp_path, edit, needles):
    doc = _doc()
    doc["lamps"][0]["cuts"].update(edit)
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(doc))
    assert_bad_input(run_cli("render", path, "-o", tmp_path / "x.png"), *needles)
    assert not (tmp_path / "x.png").exists()


def test_flutes_deeper_than_a_half_cylinder_name_the_height_and_its_range():
    doc = _doc()
    doc["lamps"][0]["cuts"].update(type="flutes", pitch=8.0, height=4.5)  # fine for fish-eye (< 5.657)
    with pytest.raises(SceneError) as info:
        parse_scene(doc)
    assert info.value.path == "lamps[0].cuts.height" and "allowed [0, 4] mm (pitch / 2)" in info.value.message
    assert lamp_limits(doc, 0)["cuts.height"] == "at most 4 mm for pitch 8 mm (pitch / 2)"
    doc["lamps"][0]["cuts"]["height"] = 4.0
    lamp = parse_scene(doc)["lamps"][0]
    assert lamp_geometry(lamp)["plane_b"] == lamp["lens"]["thickness"] + 4.0

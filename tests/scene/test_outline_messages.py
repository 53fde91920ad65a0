"""Rectangular lenses refused with a message that names the field and a range that is not empty,
a value from which makes the design valid again; round designs keep their messages."""

from __future__ import annotations

import copy
import json
import re

import pytest
from helpers import BASELINE, FOUR_LAMPS, NUMBER, allowed_ranges, follow_message, random_lamp_doc

from core_tracer.scene.limits import lamp_limits
from core_tracer.scene.reading import SceneError
from core_tracer.scene.validate import parse_scene


def _square(**lens) -> dict:
    doc = json.loads(BASELINE.read_text())
    doc["lamps"][0]["lens"].update({"outline": "rectangular", "width": 90, "height": 60, "corner_radius": 10,
                                    **lens})
    return doc


def _error(doc: dict) -> SceneError:
    with pytest.raises(SceneError) as info:
        parse_scene(doc)
    return info.value


@pytest.mark.parametrize(("lens", "path", "allowed"), [
    ({"corner_radius": 31}, "lamps[0].lens.corner_radius", (0, 30)),
    ({"width": 230}, "body.size", (230, 1e4)),
    ({"height": 121}, "body.size", (90, 1e4)),
])
def test_an_outline_that_does_not_fit_names_the_field_and_its_range(lens, path, allowed):
    err = _error(_square(**lens))
    assert err.path == path, str(err)
    assert allowed_ranges(err.message)[0] == allowed, str(err)


def test_a_corner_radius_of_half_the_smaller_side_is_allowed():
    parse_scene(_square(corner_radius=30))  # two half circles joined by straight sides
    doc = _square(width=60, corner_radius=30)  # a circle, drawn as a rectangle
    doc["lamps"][0]["bulb"]["radius"] = 5
    doc["lamps"][0]["reflector"]["focal_length"] = 10
    parse_scene(doc)


def test_a_rectangular_lens_moved_out_of_the_body_blames_its_centre():
    doc = _square()
    doc["lamps"][0]["center"] = [70, 0]
    err = _error(doc)
    assert err.path == "lamps[0].center"
    (x_lo, x_hi), (z_lo, z_hi) = allowed_ranges(err.message)
    assert (x_lo, x_hi, z_lo, z_hi) == (-65, 65, -30, 30), str(err)
    doc["lamps"][0]["center"] = [x_hi, z_lo]
    parse_scene(doc)


def test_rectangular_lenses_that_overlap_are_refused_and_corners_may_come_close():
    doc = json.loads(FOUR_LAMPS.read_text())
    doc["lamps"] = doc["lamps"][:2]
    doc["body"]["size"] = [300, 200]
    doc["lamps"][0]["center"], doc["lamps"][1]["center"] = [-50, 0], [50, 0]
    for lamp in doc["lamps"]:
        lamp["lens"].update({"outline": "rectangular", "width": 110, "height": 90, "corner_radius": 20})
    err = _error(doc)
    assert err.path == "lamps[1].center" and "by 10 mm" in err.message and "100 mm apart in x" in err.message, str(err)
    for lamp in doc["lamps"]:
        lamp["lens"]["width"] = 100
    parse_scene(doc)  # side by side, touching
    # rounded corners let two lenses sit closer diagonally than their bounding boxes allow
    for lamp in doc["lamps"]:
        lamp["lens"].update({"width": 90, "height": 90, "corner_radius": 40})
    doc["lamps"][0]["center"], doc["lamps"][1]["center"] = [-40, -40], [35, 35]
    parse_scene(doc)
    doc["lamps"][1]["lens"]["corner_radius"] = 5
    assert "overlaps" in str(_error(doc))


def test_a_pitch_larger_than_the_smaller_side_is_refused():
    doc = _square()
    doc["lamps"][0]["cuts"]["pitch"] = 61
    err = _error(doc)
    assert err.path == "lamps[0].cuts.pitch" and allowed_ranges(err.message)[0][1] == 60, str(err)
    doc["lamps"][0]["cuts"]["pitch"] = 60
    doc["lamps"][0]["cuts"]["height"] = 1
    parse_scene(doc)


def test_a_bulb_against_the_flat_side_wall_is_refused():
    # 60 mm high: a bulb of radius 8 mm moved 25 mm up pokes 3 mm through the top wall, though the
    # paraboloid (reaching the corners) would hold it
    doc = _square()
    doc["lamps"][0]["reflector"]["focal_length"] = 30
    doc["body"]["depth"] = 120
    doc["lamps"][0]["bulb"]["offset"] = [0, 10, 25]
    err = _error(doc)
    assert err.path == "lamps[0].bulb.offset" and "in the direction of x, z" in err.message, str(err)
    limit = float(re.search(rf"up to ({NUMBER}) mm", err.message)[1])
    assert limit <= 22  # the top wall, 30 mm from the axis, less the radius
    y = float(re.search(rf"at y = ({NUMBER}) mm", err.message)[1])
    doc["lamps"][0]["bulb"]["offset"] = [0, y, limit]
    parse_scene(doc)


def test_round_lenses_keep_their_messages():
    doc = json.loads(BASELINE.read_text())
    doc["lamps"][0]["cuts"]["pitch"] = 91
    assert str(_error(doc)) == ("lamps[0].cuts.pitch: 91 is larger than the lens; allowed [0.09, 90] mm "
                                "(at most 1000 cuts across the lens diameter)")


@pytest.mark.slow
@pytest.mark.seed(2026)
def test_random_rectangular_designs_get_a_field_and_a_range_a_value_of_which_clears_it(rng):
    seen = set()
    for _ in range(150):
        doc = random_lamp_doc(_square(), rng)
        lamp_limits(doc, 0)
        for _ in range(12):  # follow the messages until the design is valid
            try:
                parse_scene(copy.deepcopy(doc))
                seen.add("valid")
                break
            except SceneError as e:
                seen.add(e.path)
                assert e.path.startswith(("lamps[0].", "body.")), e
                ranges = allowed_ranges(e.message) if "allowed" in e.message else None
                assert ranges is not None, str(e)
                for lo, hi in ranges:
                    assert lo <= hi, str(e)
                before = str(e)
                follow_message(doc, e)
                try:
                    parse_scene(copy.deepcopy(doc))
                except SceneError as after:
                    assert after.path != e.path, (before, str(after))
        lamp_limits(doc, 0)
    assert {"valid", "lamps[0].lens.corner_radius", "lamps[0].cuts.pitch", "lamps[0].bulb.offset"} <= seen, seen


@pytest.mark.slow
def test_the_command_line_refuses_a_bad_outline_in_one_line(tmp_path):
    from helpers import assert_bad_input, run_cli

    path = tmp_path / "bad.json"
    path.write_text(json.dumps(_square(corner_radius=45)))
    proc = run_cli("render", path, "-o", tmp_path / "out.png")
    line = assert_bad_input(proc, "lamps[0].lens.corner_radius", "allowed [0, 30] mm")
    assert "45 is more than half the lens's smaller side" in line
    assert not (tmp_path / "out.png").exists()

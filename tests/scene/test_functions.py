"""A lamp's function (``lamps[].function``) and the defaults it sets."""

import copy
import json

import pytest
from helpers import BASELINE, PRESETS

from core_tracer.scene import functions as F
from core_tracer.scene import spec as S
from core_tracer.scene.derived import lens_absorption
from core_tracer.scene.validate import load_scene, normalize, parse_scene


def _scene() -> dict:
    return parse_scene(json.loads(BASELINE.read_text()))


def test_old_presets_read_as_custom_lamps():
    """A lamp written without a function (every preset before the field) reads as custom; one that
    names its function (the LED rear combination's) keeps it."""
    named = 0
    for path in PRESETS.glob("*.json"):
        written = json.loads(path.read_text())["lamps"]
        for raw, lamp in zip(written, load_scene(path)["lamps"], strict=True):
            assert lamp["function"] == raw.get("function", "custom")
            named += "function" in raw and raw["function"] != "custom"
    assert named >= 4  # the LED rear combination's tail, stop, turn and reversing lamps
    assert S.LAMP.fields["function"].default == "custom"


@pytest.mark.parametrize("function", sorted(F.DEFAULTS))
def test_every_function_gives_a_valid_lamp(function):
    scene = _scene()
    F.apply_function(scene["lamps"][0], function)
    lamp = normalize(scene)["lamps"][0]
    assert lamp["function"] == function
    assert "absorption" not in lamp["lens"]  # the colour picker's form
    assert lamp["lens"]["reference_thickness"] == lamp["lens"]["thickness"]


def test_signal_colours_and_brightness():
    def absorption(function):
        scene = _scene()
        F.apply_function(scene["lamps"][0], function)
        return lens_absorption(scene["lamps"][0]["lens"]), sum(scene["lamps"][0]["bulb"]["intensity"])

    for red in ("tail", "stop", "fog"):
        (r, g, b), _ = absorption(red)
        assert r < 0.1 < g and r < b
    (r, g, b), _ = absorption("turn")
    assert r < g < b  # amber: red passes most, blue least
    for clear in ("reversing", "position"):
        assert max(absorption(clear)[0]) < 0.02
    assert absorption("stop")[1] > absorption("tail")[1]
    assert absorption("turn")[1] > absorption("position")[1]


def test_custom_changes_nothing_but_the_function():
    scene = _scene()
    before = copy.deepcopy(scene["lamps"][0])
    F.apply_function(scene["lamps"][0], "custom")
    assert scene["lamps"][0] == before


def test_part_labels():
    lamps = [{"function": f} for f in ("tail", "stop", "turn", "turn", "custom")]
    assert [F.lamp_label(lamps, i) for i in range(5)] == ["Tail", "Stop", "Turn 1", "Turn 2", "Lamp 5"]
    assert F.lamp_label([{}], 0) == "Lamp 1"  # a lamp document without the field


def test_suggested_study_values_come_from_the_functions():
    assert F.suggested_values("lens.transmitted_color") == [[0.94, 0.011, 0.008], [0.92, 0.12, 0.005],
                                                            [0.97, 0.97, 0.97]]
    assert F.suggested_values("lens.ior") == []


def test_function_descriptions():
    assert F.describe("stop") == "Red lens, bulb intensity 20/17.5/15"
    assert F.describe("turn").startswith("Amber lens") and F.describe("reversing").startswith("Clear lens")
    assert F.describe("custom") == "Set the lens colour and the bulb yourself"

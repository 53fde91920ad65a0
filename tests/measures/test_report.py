"""What each lamp is for (core_tracer.measures.report.lamp_function) and the regulations each function
is checked against."""

from __future__ import annotations

from core_tracer.measures import regulation_grid, report
from core_tracer.scene import load_scene


def test_four_lamp_preset_lamps_are_tail_stop_turn_reversing(repo_root):
    scene = load_scene(repo_root / "presets" / "four-lamp-night-lit-photometric.json")
    assert [report.lamp_function(lamp) for lamp in scene["lamps"]] == ["tail", "stop", "turn", "reversing"]


def test_a_declared_function_wins_and_others_are_not_measured(repo_root):
    scene = load_scene(repo_root / "presets" / "four-lamp-night-lit-photometric.json")
    lamp = scene["lamps"][3]
    lamp["function"] = "stop"
    assert report.lamp_function(lamp) == "stop"
    lamp["function"] = "fog"
    assert report.lamp_function(lamp) is None


def test_every_function_names_regulations_and_a_colour_that_exist():
    for un, us, colour in report.FUNCTIONS.values():
        assert un in regulation_grid.function_keys() and us in regulation_grid.function_keys()
        assert regulation_grid.function(un)["colour"] == colour == regulation_grid.function(us)["colour"]
        assert (0.0, 0.0) in regulation_grid.directions_for(un)

"""Bulb type and lens material as study axes (issue 22, item 9): accepted on the command line and in
a study document, each variant valid, a named bulb keeping a filament it has."""

from __future__ import annotations

import pytest
from helpers import PRESETS

from core_tracer.scene.reading import SceneError
from core_tracer.scene.validate import load_scene
from core_tracer.study.definition import Study, parse_vary


@pytest.fixture
def stop_lamp() -> dict:
    return load_scene(PRESETS / "photometric-stop-lamp.json")


def test_bulb_type_and_lens_material_from_the_command_line(stop_lamp):
    axes = [parse_vary("bulb.type=P21/5W,R5W,PY21/5W"), parse_vary("lens.material=pmma,polycarbonate")]
    assert axes[0] == {"parameter": "bulb.type", "values": ["P21/5W", "R5W", "PY21/5W"]}
    study = Study.build(stop_lamp, axes)
    assert len(study) == 6
    bulbs = [study.variant_scene(i)["lamps"][0]["bulb"] for i in range(3)]
    assert [(b["type"], b["state"]) for b in bulbs] == [("P21/5W", "stop"), ("R5W", "on"), ("PY21/5W", "stop")]
    assert {study.variant_scene(i)["lamps"][0]["lens"]["material"] for i in range(6)} == {"pmma", "polycarbonate"}


def test_a_filament_axis_applies_after_the_bulb_type(stop_lamp):
    study = Study.build(stop_lamp, [{"parameter": "bulb.state", "values": ["tail", "stop"]},
                                    {"parameter": "bulb.type", "values": ["P21/5W", "PY21/5W"]}])
    assert [study.variant_scene(i)["lamps"][0]["bulb"]["state"] for i in range(4)] == ["tail", "stop"] * 2


def test_a_filament_the_bulb_lacks_is_refused_naming_the_variant(stop_lamp):
    with pytest.raises(SceneError, match="R5W"):
        Study.build(stop_lamp, [{"parameter": "bulb.type", "values": ["R5W"]},
                                {"parameter": "bulb.state", "values": ["tail"]}])


def test_an_unknown_bulb_type_names_the_allowed_ones(stop_lamp):
    with pytest.raises(SceneError, match="P21/5W"):
        Study.build(stop_lamp, [parse_vary("bulb.type=P21W")])

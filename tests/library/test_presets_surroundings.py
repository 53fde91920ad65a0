"""The day, evening and night presets of the four-lamp rear combination, lit and unlit."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import PRESETS

from core_tracer import render_passes
from core_tracer.raytrace import environment
from core_tracer.scene.reading import read_json
from core_tracer.scene.validate import parse_scene

TIMES = {"day": "city", "evening": "sunset", "night": "night"}


def _load(time: str, state: str) -> dict:
    return parse_scene(read_json(PRESETS / f"four-lamp-{time}-{state}.json"))


@pytest.mark.parametrize("time", sorted(TIMES))
def test_each_time_of_day_has_a_lit_and_an_unlit_preset_differing_only_in_the_bulbs(time):
    lit, unlit = _load(time, "lit"), _load(time, "unlit")
    assert lit["environment"]["world"] == TIMES[time]
    assert all(lamp["bulb"]["on"] for lamp in lit["lamps"]) and not any(lamp["bulb"]["on"] for lamp in unlit["lamps"])
    for scene in (lit, unlit):
        for lamp in scene["lamps"]:
            lamp["bulb"]["on"] = True
        scene.pop("name"), scene.pop("description"), scene.pop("tags")
    assert lit == unlit


def test_the_sun_is_high_by_day_low_in_the_evening_and_absent_at_night(world_images):
    day = environment.from_scene(_load("day", "lit")).sun_direction()
    evening = environment.from_scene(_load("evening", "lit")).sun_direction()
    assert np.degrees(np.arcsin(day[2])) > 40 and 0 < np.degrees(np.arcsin(evening[2])) < 6
    assert day[1] < 0 and evening[1] < 0  # in front of the lamp: its light reaches the reflectors
    assert _load("night", "lit")["light"]["strength"] == 0.0


@pytest.mark.slow
def test_the_low_evening_sun_lights_the_unlit_lamps_and_the_night_does_not(world_images):
    size = (96, 60)
    evening = render_passes(_load("evening", "unlit"), *size, samples=1).passes["reflector_scatter"]
    night = render_passes(_load("night", "unlit"), *size, samples=1).passes["reflector_scatter"]
    assert evening.max() > 0.05 and not night.any()

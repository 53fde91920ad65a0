"""The LED presets (issue 32 item 5): the LED stop lamp, the light-guide tail lamp, the LED stop lamp
behind a free-form lens and the four-function LED rear combination. Each validates and renders small
from the command line, is listed by the preset browser, and carries what its description says."""

from __future__ import annotations

from pathlib import Path

import pytest
from helpers import PRESETS, run_cli

from core_tracer.freeform.loading import load_meshes
from core_tracer.images import imageio
from core_tracer.library import presets as P
from core_tracer.scene.validate import load_scene

LED_PRESETS = ("led-stop-lamp", "led-light-guide-tail-lamp", "led-stop-lamp-freeform-lens-photometric",
               "led-rear-combination-photometric")


@pytest.mark.slow
@pytest.mark.parametrize("stem", LED_PRESETS)
def test_validates_and_renders_small_from_the_cli(stem, tmp_path):
    path = PRESETS / f"{stem}.json"
    proc = run_cli("validate", path)
    assert proc.returncode == 0, proc.stderr
    out = tmp_path / "small.png"
    # 4 samples: one a pixel of a 40-pixel frame can miss every lit point of a lamp lit as sparse points (the
    # guide tail's LED images broken up by its pillow optics: 0.09 at its brightest with 1 sample, 14.8 with 4)
    proc = run_cli("render", path, "-o", out, "--width", "40", "--height", "40", "--samples", "4")
    assert proc.returncode == 0, proc.stderr
    image, _ = imageio.read_image(out)
    assert image.shape == (40, 40, 3)
    assert image.max() > 0.2  # the lit lamp shows at night, not a black frame


def test_the_preset_browser_lists_them():
    entries, warnings = P.list_presets([P.builtin_library()])
    assert warnings == []
    listed = {Path(entry.file).stem: entry for entry in entries}
    assert set(LED_PRESETS) <= set(listed)
    assert all("photometric" in listed[stem].tags and "LED" in listed[stem].tags for stem in LED_PRESETS)


def test_the_rear_combination_sets_each_lamps_function():
    scene = load_scene(PRESETS / "led-rear-combination-photometric.json")
    lamps = scene["lamps"]
    assert [lamp["function"] for lamp in lamps] == ["tail", "stop", "turn", "reversing"]
    assert all(lamp["source"] == "led" for lamp in lamps)
    assert lamps[0]["light_guide"]["enabled"] and not any(lamp["light_guide"]["enabled"] for lamp in lamps[1:])
    assert [lamp["lens"]["filter"] for lamp in lamps] == ["red", "red", "amber", "clear"]
    assert [lamp["led"]["spectrum"] for lamp in lamps[1:]] == ["red_led", "amber_led", "white_led"]


def test_the_free_form_lamp_is_lit_by_its_led_dies():
    """The free-form LED stop lamp's source is its lamp's LED dies (traced beside the meshes,
    ``freeform/leds.py``), as the parametric LED stop lamp's: no bulb part, the package boxes a socket
    part behind the dies (in the .glb, with the lens, reflector, side wall and body)."""
    path = PRESETS / "led-stop-lamp-freeform-lens-photometric.json"
    scene = load_scene(path)
    lamp = scene["lamps"][0]
    assert lamp["source"] == "led" and lamp["led"]["spectrum"] == "red_led" and lamp["bulb"]["on"]
    parts = {part["object"]: part for part in scene["freeform"]["parts"]}
    assert sorted(part["role"] for part in parts.values()) == ["body", "lens", "reflector", "side_wall", "socket"]
    assert parts["Lamp 1 LED Packages (Free-form)"]["role"] == "socket"
    packages = load_meshes(path, scene)["Lamp 1 LED Packages (Free-form)"]
    assert packages.vertices[:, 1].min() > lamp["led"]["position"][1]  # behind the dies' plane

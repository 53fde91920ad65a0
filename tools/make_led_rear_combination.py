"""Make ``presets/led-rear-combination-photometric.json``: a four-function LED rear combination.

    .venv/bin/python tools/make_led_rear_combination.py [--out presets]

Its lamps are the shipped LED lamps set side by side in one body, so each is a lamp already measured
alone: the tail is the light-guide tail lamp of ``presets/led-light-guide-tail-lamp.json`` (a red
LED at the end of a clear PMMA guide behind a red lens), the stop the LED stop lamp of
``presets/led-stop-lamp.json`` (nine red dies of 35 lm behind the red fish-eye lens), and the turn and
reversing lamps that stop lamp with amber dies behind an amber lens and white dies behind a clear one.
Each lamp's ``function`` is set, so ``measure`` grades each by its own regulation.
"""

from __future__ import annotations

import argparse
import copy
import json
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from core_tracer.scene.validate import load_scene, parse_scene  # noqa: E402

NAME = "led-rear-combination-photometric"
# Lamp centres [x, z] in the body (mm): the guide's 180 mm lens at the outer end, then three round lenses.
CENTRES = {"tail": [-175.0, 0.0], "stop": [-25.0, 0.0], "turn": [85.0, 0.0], "reversing": [195.0, 0.0]}
# The turn and reversing lamps' dies (lm each): the stop lamp's array with another colour.
TURN_LM, REVERSING_LM = 40.0, 45.0


def _preset(stem: str) -> dict:
    with open(os.path.join(ROOT, "presets", stem + ".json"), encoding="utf-8") as f:
        return json.load(f)


def design() -> dict:
    stop_scene, guide_scene = _preset("led-stop-lamp"), _preset("led-light-guide-tail-lamp")
    scene = copy.deepcopy(stop_scene)
    tail = copy.deepcopy(guide_scene["lamps"][0])
    stop = copy.deepcopy(stop_scene["lamps"][0])
    turn, reversing = copy.deepcopy(stop), copy.deepcopy(stop)
    turn["lens"].update(filter="amber", diffuse_color=[0.05, 0.02, 0.0])
    turn["led"].update(spectrum="amber_led", flux_lm=TURN_LM)
    reversing["lens"].update(filter="clear", diffuse_color=[0.03, 0.03, 0.03], side_wall_color=[0.03, 0.03, 0.03])
    reversing["led"].update(spectrum="white_led", flux_lm=REVERSING_LM)
    for function, lamp in (("tail", tail), ("stop", stop), ("turn", turn), ("reversing", reversing)):
        lamp["function"] = function
        lamp["center"] = CENTRES[function]
    scene["lamps"] = [tail, stop, turn, reversing]
    scene["body"] = {**stop_scene["body"], "center": [-10.0, 0.0], "size": [560.0, 130.0]}
    scene["camera"] = {**stop_scene["camera"], "position": [180.0, -1500.0, 300.0], "target": [-10.0, 0.0, 0.0],
                       "fov_deg": 23.0}
    scene["image"] = {"width": 480, "height": 200, "samples": 4}
    scene["name"] = "LED rear combination: tail, stop, turn, reversing (photometric)"
    scene["description"] = (
        "Four LED lamps in one body, each a shipped LED lamp with its function set: the tail a red LED "
        "(625 nm, 12 lm) at the end of a clear PMMA light guide 150 mm long behind a red lens 180 x 50 mm "
        "(the light-guide tail lamp); the stop nine red dies of 35 lm behind the red fish-eye lens (the LED stop "
        f"lamp); the turn nine amber dies of {TURN_LM:g} lm behind an amber lens; the reversing lamp nine white "
        f"dies of {REVERSING_LM:g} lm behind a clear lens. At night (3 lx), every lamp lit, EV100 15, as the LED "
        "stop lamp.")
    scene["tags"] = ["photometric", "LED", "light guide", "tail", "stop", "turn", "reversing", "combination"]
    return scene


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=os.path.join(ROOT, "presets"), help="folder to write into")
    args = parser.parse_args(argv)
    scene = design()
    parse_scene(scene)  # refused here, in one line, rather than in the preset browser
    path = os.path.join(args.out, NAME + ".json")
    with open(path, "w", encoding="utf-8") as f:
        json.dump(scene, f, indent=2)
        f.write("\n")
    load_scene(path)
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

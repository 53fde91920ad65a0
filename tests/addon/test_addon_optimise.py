"""The Optimise section of the add-on: an optimisation file without a base starts from the scene's
design, the search writes its results beside the file, and one click applies the best design."""

from __future__ import annotations

import json

import pytest
from helpers import BASELINE

import core_tracer
from core_tracer.images import glare
from core_tracer.images.imageio import write_image
from core_tracer.raytrace.engine import render_passes
from core_tracer.scene.validate import parse_scene

pytestmark = [pytest.mark.blender, pytest.mark.slow]
SIZE = 24


@pytest.fixture
def design(lamp_addon, bl_scene, tmp_path, monkeypatch):
    monkeypatch.setenv("LAMP_STYLING_CACHE", str(tmp_path / "cache"))
    with open(BASELINE, encoding="utf-8") as f:
        doc = json.load(f)
    lamp_addon.design.properties.scene_to_design(bl_scene, core_tracer.parse_scene(doc))
    # The reference: the same design with cuts 3 mm high.
    ref = {**doc, "image": {"width": SIZE, "height": SIZE}}
    ref["lamps"] = [dict(doc["lamps"][0], cuts={**doc["lamps"][0]["cuts"], "height": 3.0})]
    scene = parse_scene(ref)
    write_image(tmp_path / "ref.exr", glare.apply(render_passes(scene, SIZE, SIZE, keep_passes=False).image, scene))
    (tmp_path / "opt.json").write_text(json.dumps({
        "schema": "lamp-optimise/1", "parameters": [{"parameter": "cuts.height", "range": [0.5, 4.0]}],
        "objectives": [{"measure": "ssim", "goal": "maximise", "reference": "ref.exr"}],
        "size": [SIZE, SIZE], "trials": 6, "seed": 2}))
    bl_scene.lamp_optimise.file = str(tmp_path / "opt.json")
    return bl_scene


def test_optimise_then_apply_the_best_design(design, lamp_addon, tmp_path):
    import bpy

    assert not bpy.ops.lamp.optimise_apply.poll()
    assert bpy.ops.lamp.optimise_run() == {"FINISHED"}
    outcome = lamp_addon.optimise.settings.last()
    number, values, scores = outcome.best[0]
    assert set(values) == {"cuts.height"} and 0.5 <= values["cuts.height"] <= 4.0
    assert {"best.json", "sheet.png", "history.png", "trials.json"} <= {p.name for p in
                                                                          (tmp_path / "opt-results").iterdir()}
    trials = json.loads((tmp_path / "opt-results" / "trials.json").read_text())["trials"]
    assert trials[0]["design"] == {"cuts.height": 1.5}  # trial 0: the scene's design as it was
    assert scores[0] >= trials[0]["values"][0]
    assert bpy.ops.lamp.optimise_apply() == {"FINISHED"}
    applied = lamp_addon.design.properties.design_to_scene(design)
    assert applied["lamps"][0]["cuts"]["height"] == pytest.approx(values["cuts.height"])


def test_a_bad_file_is_one_line_naming_the_path(design, lamp_addon, tmp_path):
    import bpy

    (tmp_path / "bad.json").write_text(json.dumps({"schema": "lamp-optimise/1",
                                                    "parameters": [{"parameter": "cuts.height", "range": [4, 1]}],
                                                    "objectives": [{"measure": "lens_luminance"}]}))
    design.lamp_optimise.file = str(tmp_path / "bad.json")
    with pytest.raises(RuntimeError, match=r"bad.json: parameters\[0\].range: .*allowed lo < hi"):
        bpy.ops.lamp.optimise_run()


def test_without_optuna_the_optimiser_says_so_in_one_line(design, lamp_addon, monkeypatch):
    """A real Blender's Python has no Optuna (nor the extension's wheels): one line naming the command
    that can run it, before any work (before: ModuleNotFoundError from the search thread)."""
    import sys

    import bpy

    monkeypatch.setitem(sys.modules, "optuna", None)
    one_line = r"^Error: Optimise: needs Optuna.*python -m core_tracer optimise\n$"
    with pytest.raises(RuntimeError, match=one_line):
        bpy.ops.lamp.optimise_run()

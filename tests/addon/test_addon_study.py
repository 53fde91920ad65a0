"""The Study section of the add-on: settings -> study -> worker processes -> the "Lamp Study" image."""

from __future__ import annotations

import json
import os
import re
import sys

import numpy as np
import pytest
from helpers import BASELINE, whole_report
from study_axes import one_axis

import core_tracer
from core_tracer.images import display
from core_tracer.study import definition as st
from core_tracer.study import sheet as study_sheet
from core_tracer.study.parameters import study_parameters

pytestmark = pytest.mark.blender

PRESET = str(BASELINE)


@pytest.fixture
def design(lamp_addon, bl_scene):
    with open(PRESET, encoding="utf-8") as f:
        scene = core_tracer.parse_scene(json.load(f))
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    lamp_addon.design.lamp_camera.ensure_lamp_camera(bl_scene, frame=False)
    settings = bl_scene.lamp_study
    settings.width, settings.height, settings.fit_lamp = 32, 32, False  # cells of exactly that size
    settings.workers = 2
    return bl_scene


def test_every_study_parameter_is_offered(lamp_addon):
    offered = [item[0] for item in lamp_addon.study.settings.PARAMETER_ITEMS]
    # a free-form design's parts too, under their role (tests/addon/test_addon_study_freeform.py)
    assert offered == study_parameters()
    assert "lens.transmitted_color" in offered and "cuts.height" in offered
    labels = dict((item[0], item[1]) for item in lamp_addon.study.settings.PARAMETER_ITEMS)
    assert labels["freeform.parts[].lens.filter"].startswith("Free-form Lens: ")


@pytest.mark.slow
def test_run_study_operator_makes_the_sheet_image(design, lamp_addon):
    import bpy

    one_axis(design.lamp_study)
    assert bpy.ops.lamp.study_run() == {"FINISHED"}
    image = bpy.data.images["Lamp Study"]
    study = lamp_addon.study.settings.last_study()
    assert len(study) == 2 and study.size == (32, 32)
    # The sheet in Blender has the layout core_tracer computes, and each cell is the variant's render.
    # (labelled in the panel's words: ``study.settings.worded``)
    lay = study_sheet.layout(lamp_addon.study.settings.worded(st.Study.from_json(study.to_json())))
    assert tuple(image.size) == (lay.width, lay.height)
    pixels = lamp_addon.image_view.image_to_array(image)
    renders = [core_tracer.render(v.scene, 32, 32) for v in study.variants]
    # One automatic exposure for every variant, shown through the scene's view transform.
    exposure = display.auto_exposure(renders)
    assert exposure < -2 and image["lamp_exposure"] == exposure and image.use_view_as_render
    for expected, rect in zip(renders, lay.cells, strict=True):
        cell = pixels[rect.y:rect.y + rect.h, rect.x:rect.x + rect.w]
        np.testing.assert_allclose(cell, expected * np.float32(2.0 ** exposure), rtol=1e-6)
    assert study.variants[0].scene["lamps"][0]["lens"]["ior"] == 1.45
    # The image carries its study, so it can be re-run.
    assert json.loads(image["lamp_study"])["axes"] == [{"parameter": "lens.ior", "values": [1.45, 1.6]}]


def test_range_settings_and_one_lamp(design, lamp_addon):
    settings = design.lamp_study
    settings.axis_1.parameter = "cuts.height"  # the update suggests a range around the default
    assert settings.axis_1.mode == "RANGE" and settings.axis_1.start < 1.5 < settings.axis_1.stop
    settings.axis_1.start, settings.axis_1.stop, settings.axis_1.steps = 0.5, 2.0, 4
    settings.axis_1.lamp = "0"
    settings.use_axis_2 = True
    settings.axis_2.parameter = "lens.transmitted_color"
    assert settings.axis_2.mode == "LIST"
    settings.axis_2.values = "0.9/0.1/0.1, 0.9/0.5/0.05"
    study = lamp_addon.study.settings.study_from_settings(design)
    assert [a.parameter.text for a in study.axes] == ["lamps[0].cuts.height", "lens.transmitted_color"]
    assert (study.columns, study.rows) == (4, 2)


def test_bad_settings_are_reported_without_rendering(design, lamp_addon, addon_core):
    import bpy

    settings = design.lamp_study
    one_axis(settings)
    settings.axis_1.values = "1.45, 3.5"
    run_module = f"{addon_core.__name__}.study_run"
    before = getattr(sys.modules.get(run_module), "workers_started", 0)
    with pytest.raises(RuntimeError, match=r"lens.ior: 3.5 is out of range; allowed \[1, 3\]"):
        bpy.ops.lamp.study_run()
    assert "Lamp Study" not in bpy.data.images
    assert getattr(sys.modules.get(run_module), "workers_started", 0) == before


@pytest.mark.slow
def test_apply_variant_sets_the_varied_parameter(design, lamp_addon):
    import bpy

    one_axis(design.lamp_study)
    bpy.ops.lamp.study_run()
    design.lamp_study.variant = 2
    assert bpy.ops.lamp.study_apply_variant() == {"FINISHED"}
    scene = lamp_addon.design.properties.design_to_scene(design)
    assert scene["lamps"][0]["lens"]["ior"] == 1.6


@pytest.mark.slow
def test_save_sheet_writes_the_study_into_the_file(design, lamp_addon, tmp_path):
    import bpy

    one_axis(design.lamp_study)
    bpy.ops.lamp.study_run()
    path = tmp_path / "sheet.exr"
    assert bpy.ops.lamp.study_save_sheet(filepath=str(path)) == {"FINISHED"}
    again = st.Study.load(path)
    assert again.to_json() == lamp_addon.study.settings.last_study().to_json()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sheet.exr"]


@pytest.mark.slow
def test_keep_variant_saves_a_preset_in_the_user_library(design, lamp_addon, addon_core):
    import bpy

    library, why = lamp_addon.presets.library.user_library()
    assert library is not None, why
    one_axis(design.lamp_study)
    bpy.ops.lamp.study_run()
    design.lamp_study.variant = 1
    before = set(os.listdir(library.folder))
    try:
        assert bpy.ops.lamp.study_keep_variant() == {"FINISHED"}
        added = set(os.listdir(library.folder)) - before
        assert len(added) == 1
        path = os.path.join(library.folder, added.pop())
        saved = addon_core.scene.load_scene(path)
        assert saved["name"].endswith("(lens.ior=1.45)")
        assert saved["lamps"][0]["lens"]["ior"] == 1.45
    finally:
        for name in set(os.listdir(library.folder)) - before:
            os.unlink(os.path.join(library.folder, name))


@pytest.mark.slow
def test_a_study_of_lamp_types_runs_in_blender(design, lamp_addon):
    import bpy
    from test_addon_panels import draw

    settings = design.lamp_study
    settings.axis_1.parameter = "cuts.type"  # a choice: the list of every name it allows is suggested
    settings.use_axis_2 = True
    settings.axis_2.parameter = "collection"
    assert (settings.axis_1.mode, settings.axis_1.values) == ("LIST", "fisheye, sawtooth, flutes")
    assert (settings.axis_2.mode, settings.axis_2.values) == ("LIST", "reflector, prism_plate")
    log = draw(lamp_addon.study.panel.LAMP_PT_study, design).log
    assert ("label", 'One of "fisheye", "sawtooth", "flutes"', "NONE") in log  # the names the list may hold
    assert bpy.ops.lamp.study_run() == {"FINISHED"}
    study = lamp_addon.study.settings.last_study()
    assert (study.columns, study.rows) == (3, 2)
    assert study.variants[5].label(study) == "cuts.type=flutes  collection=prism_plate"
    # The cells of the sheet differ from each other (mean absolute difference over 5 % of their mean).
    pixels = lamp_addon.image_view.image_to_array(bpy.data.images["Lamp Study"])
    lay = study_sheet.layout(lamp_addon.study.settings.worded(study))
    cells = [pixels[r.y:r.y + r.h, r.x:r.x + r.w] for r in lay.cells]
    for a in range(len(cells)):
        for b in range(a):
            assert np.abs(cells[a] - cells[b]).mean() > 0.05 * 0.5 * (cells[a].mean() + cells[b].mean()), (a, b)
    design.lamp_study.variant = 5
    assert bpy.ops.lamp.study_apply_variant() == {"FINISHED"}
    lamp = lamp_addon.design.properties.design_to_scene(design)["lamps"][0]
    assert (lamp["cuts"]["type"], lamp["collection"]) == ("sawtooth", "prism_plate")


def test_a_combination_the_scene_refuses_is_reported_without_rendering(design, lamp_addon, capfd):
    import bpy

    settings = design.lamp_study
    settings.axis_1.parameter = "collection"
    settings.use_axis_2 = True
    settings.axis_2.parameter = "lens.outline"
    capfd.readouterr()
    with pytest.raises(RuntimeError) as raised:
        bpy.ops.lamp.study_run()
    assert re.search(r"lamps\[0\]\.lens\.outline: a prism plate sits behind a round lens; allowed \"round\".*"
                     r"collection=prism_plate, lens\.outline=rectangular",
                     whole_report(str(raised.value), capfd.readouterr().out))
    assert "Lamp Study" not in bpy.data.images


def test_sheet_labels_use_panel_words_and_rounded_values(design, lamp_addon):
    """A range of 4 steps from 0.5 to 1.5 gives 0.8333, not 0.833333; the sheet names the fields as the
    panel does (the study's own JSON keeps the paths)."""
    settings = design.lamp_study
    settings.axis_1.parameter = "cuts.height"
    settings.axis_1.mode, settings.axis_1.start, settings.axis_1.stop, settings.axis_1.steps = "RANGE", 0.5, 1.5, 4
    settings.use_axis_2 = True
    settings.axis_2.parameter, settings.axis_2.mode, settings.axis_2.values = "bulb.on", "LIST", "on, off"
    settings.axis_2.lamp = "0"
    study = lamp_addon.study.settings.study_from_settings(design)
    assert study.axes[0].values == (0.5, 0.8333, 1.167, 1.5)
    lay = study_sheet.layout(lamp_addon.study.settings.worded(study))
    texts = [box.text for box in lay.texts]
    assert "Cuts Height=0.8333 mm" in texts and "Bulb On=off" in texts  # each value with its unit
    assert any("columns: Cuts › Height" in t and "rows: Lamp 1 › Bulb › On" in t for t in texts), texts
    assert [a.parameter.text for a in study.axes] == ["cuts.height", "lamps[0].bulb.on"]

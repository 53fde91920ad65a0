"""The Measures section of the add-on: the ``measure`` command run from Blender, its table, its page."""

from __future__ import annotations

import json
import os
import time

import pytest
from helpers import PRESETS
from test_addon_panels import draw

pytestmark = pytest.mark.blender


@pytest.fixture
def stop_lamp(lamp_addon, addon_core, bl_scene):
    scene = addon_core.scene.load_scene(PRESETS / "photometric-stop-lamp.json")
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    return bl_scene


def test_paper_designs_get_one_line(lamp_addon, addon_core, bl_scene):
    import bpy

    scene = addon_core.scene.load_scene(PRESETS / "paper-baseline.json")
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    layout = draw(bpy.types.LAMP_PT_measures, bl_scene)
    assert layout.labels() == ["Measures need the Photometric light model (Design: Light Model)"]
    assert not bpy.types.LAMP_OT_measures_run.poll(bpy.context)


def test_registration_is_symmetric_and_repeatable(lamp_addon, stop_lamp):
    import bpy

    for _ in range(2):
        lamp_addon.measures.unregister()
        assert not hasattr(bpy.types.Scene, "lamp_measures") and not hasattr(bpy.types, "LAMP_PT_measures")
        lamp_addon.measures.register()
        assert hasattr(bpy.types.Scene, "lamp_measures") and hasattr(bpy.types, "LAMP_OT_measures_run")


def test_output_folder_is_next_to_the_blend_or_temporary(lamp_addon, tmp_path):
    folder = lamp_addon.measures.settings.output_folder
    assert folder(str(tmp_path / "rear lamp.blend"), "/tmp/x") == str(tmp_path / "rear lamp_measures")
    assert folder("", "/tmp/x") == "/tmp/x"


@pytest.mark.slow
def test_measure_design_writes_the_table_and_opens_the_page(lamp_addon, stop_lamp, tmp_path):
    import bpy

    blend = tmp_path / "stop.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend))
    objects = sorted(o.name for o in bpy.data.objects)
    assert bpy.ops.lamp.measures_run() == {"FINISHED"}
    folder = tmp_path / "stop_measures"
    assert stop_lamp.lamp_measures.folder == str(folder)
    assert sorted(os.listdir(folder)) == ["measures.json", "measures.png"]  # no beam files unless asked
    assert sorted(os.listdir(tmp_path)) == ["stop.blend", "stop_measures"]  # nothing else next to the .blend
    assert sorted(o.name for o in bpy.data.objects) == objects  # the user's objects untouched
    with open(folder / "measures.json", encoding="utf-8") as f:
        measured = json.load(f)
    assert measured["verdicts"] == {"R148 S1": True, "FMVSS stop": True}
    layout = draw(bpy.types.LAMP_PT_measures, stop_lamp)
    labels = layout.labels()
    assert labels[0] == "Stop: pass"
    # The table: headings, then the figures (every grid row passes, so only homogeneity and colour show).
    at = labels.index("Function")
    assert labels[at:at + 6] == ["Function", "Test point / measure", "Required", "Simulated", "Margin", "Pass"]
    assert "Lmin/Lmax (lit lens)" in labels and "colour xy (red)" in labels
    stop_lamp.lamp_measures.show_all = True
    every = draw(bpy.types.LAMP_PT_measures, stop_lamp).labels()
    assert "S1 H-V min" in every and "FMVSS stop H-V min" in every
    assert "lamp.measures_open_report" in layout.operators()
    assert bpy.ops.lamp.measures_open_report() == {"FINISHED"}
    image = bpy.data.images["Lamp Measures"]
    assert image.size[0] > 1000 and os.path.samefile(bpy.path.abspath(image.filepath), folder / "measures.png")


@pytest.mark.slow
def test_cancel_stops_the_worker_and_leaves_no_folder(lamp_addon, stop_lamp, tmp_path):
    ops = lamp_addon.measures.ops
    scene = ops.measured_scene(stop_lamp)
    run = ops.MeasureRun(scene, str(tmp_path / "out"), beam_files=False)
    run.start()
    deadline = time.monotonic() + 120
    while run.fraction == 0.0 and time.monotonic() < deadline:  # under way: a direction measured
        assert not run.poll(timeout=0.1)
    assert run.fraction > 0.0 and run.stage.startswith("intensity")
    start = time.monotonic()
    run.cancel()
    assert run.poll() and time.monotonic() - start < 10
    assert run.error() is not None  # ended by SIGTERM, not finished
    run.close()
    assert not (tmp_path / "out").exists()
    assert os.listdir(tmp_path) == []

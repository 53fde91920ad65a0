"""Reports of at most one line (``lamp_addon.reports``): the designer's loop from the startup file,
every operator's report recorded (background Blender prints each as "Info: ...", "Warning: ...",
"Error: ..."), none longer than ``reports.LINE`` characters. What a report leaves out is in the
Info editor as lines of their own."""

from __future__ import annotations

import re

import pytest
from helpers import PRESETS

pytestmark = [pytest.mark.blender, pytest.mark.slow]

REPORT = re.compile(r"^(Info|Warning|Error): (.*)$")


def _apply(bpy, name: str):
    wm = bpy.context.window_manager
    wm.lamp_presets_index = next(i for i, item in enumerate(wm.lamp_presets) if item.file.endswith(name))
    return bpy.ops.lamp.preset_apply()


def test_no_report_of_the_designers_loop_is_longer_than_one_line(lamp_addon, addon, capfd, tmp_path):
    import bpy

    bpy.ops.wm.read_homefile(use_factory_startup=True)
    bl_scene = bpy.context.scene
    capfd.readouterr()
    bpy.ops.lamp.preset_refresh()
    assert bpy.ops.lamp.lamp_add() == {"FINISHED"}
    bl_scene.lamp_design.image.width, bl_scene.lamp_design.image.height = 64, 40
    assert bpy.ops.lamp.build() == {"FINISHED"}
    assert bpy.ops.lamp.frame_design() == {"FINISHED"}
    assert bpy.ops.lamp.hide_others() == {"FINISHED"}
    for name in ("paper-lamp-off.json", "paper-baseline.json", "four-lamp-rear-combination.json",
                 "sawtooth-stop-lamp.json", "four-lamp-evening-lit.json"):
        assert _apply(bpy, name) == {"FINISHED"}
    bl_scene.lamp_design.image.width, bl_scene.lamp_design.image.height = 64, 40
    assert bpy.ops.lamp.build() == {"FINISHED"}
    assert bpy.ops.lamp.exposure_from_design() == {"FINISHED"}
    assert bpy.ops.lamp.render_tracer() == {"FINISHED"}
    assert bpy.ops.lamp.compare_cycles(samples=1) == {"FINISHED"}
    settings = bl_scene.lamp_study
    settings.width, settings.height, settings.workers = 32, 24, 1
    settings.axis_1.parameter, settings.axis_1.mode, settings.axis_1.values = "lens.ior", "LIST", "1.45, 1.6"
    settings.use_axis_2 = False
    assert bpy.ops.lamp.study_run() == {"FINISHED"}
    bl_scene.lamp_design.lamps[0].cuts.height = 100.0  # an error the designer makes
    for operator in (bpy.ops.lamp.build, bpy.ops.lamp.render_tracer, bpy.ops.render.render):
        with pytest.raises(RuntimeError):
            operator()
    with pytest.raises(RuntimeError):
        bpy.ops.lamp.preset_import(filepath=str(tmp_path / "a file that is not there, with a long name.json"))
    bl_scene.lamp_design.lamps[0].cuts.height = 1.0
    assert bpy.ops.lamp.preset_export(filepath=str(tmp_path / "exported.json")) == {"FINISHED"}
    assert _apply(bpy, "freeform-sculpted-wrap-lamp.json") == {"FINISHED"}
    out = capfd.readouterr().out
    recorded = [m[2] for m in map(REPORT.match, out.splitlines()) if m]
    assert len(recorded) > 30
    (tmp_path / "reports.txt").write_text("\n".join(recorded))
    too_long = [line for line in recorded if len(line) > lamp_addon.reports.LINE]
    assert too_long == [], too_long
    assert PRESETS.is_dir()

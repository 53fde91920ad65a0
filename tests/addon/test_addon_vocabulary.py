"""One vocabulary (``lamp_addon.design.validity``): every message a designer sees in Blender names
fields by their panel labels ("Lamp 1 › Cuts › Height"), the same words in the panel and from F12,
Build, Compare and Render with Lamp Tracer; the field highlighted is the one whose change fixes the
design (the one just changed), the field the rule names offered second. The command line keeps the
JSON paths.

The errors a designer can reach from the panel are the spec's cross-field rules, one edit each
(``test_addon_panels.INVALID_EDITS``, plus the lens too large for the body).
"""

from __future__ import annotations

import re

import pytest
from helpers import BASELINE, run_cli, whole_report
from test_addon_panels import INVALID_EDITS, _status

import core_tracer

pytestmark = pytest.mark.blender

EDITS = {
    **{case: (edit, field) for case, (edit, field, _words) in INVALID_EDITS.items()},
    "lens radius 80": (lambda d: setattr(d.lamps[0].lens, "radius", 80.0), "lamps[0].lens.radius"),
}
JSON_PATH = re.compile(r"lamps\[\d+\]|\b(?:lens|cuts|bulb|body|reflector|socket|prism_plate|camera)\.[a-z_]+")


def _design(lamp_addon, bl_scene):
    scene = core_tracer.load_scene(str(BASELINE))
    scene["image"] = {"width": 24, "height": 16}
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    lamp_addon.design.lamp_camera.ensure_lamp_camera(bl_scene)
    bl_scene.render.engine = "LAMP_TRACER"
    bl_scene.lamp_design.auto_build = False
    return bl_scene.lamp_design


def _error_of(operator, capfd, **kwargs) -> str:
    capfd.readouterr()
    with pytest.raises(RuntimeError) as raised:
        operator(**kwargs)
    return whole_report(str(raised.value), capfd.readouterr().out)


@pytest.mark.parametrize("case", sorted(EDITS))
def test_the_panel_and_every_operator_say_the_same_words(lamp_addon, bl_scene, capfd, case):
    import bpy

    edit, field = EDITS[case]
    design = _design(lamp_addon, bl_scene)
    assert _status(bl_scene).alerts() == ([], [])  # the panel drawn while the design is valid
    edit(design)
    props, labels = _status(bl_scene).alerts()
    assert props == [field]  # the field just changed is the one to change back
    problem = lamp_addon.design.validity.status(bl_scene).problem
    text = problem.text()
    assert labels[0] == problem.label() and " ".join(labels[1:]) == problem.explanation()
    assert " › " in problem.label() or problem.label() in ("Body › Size",)
    assert not JSON_PATH.search(text), text  # panel words only
    with open("/tmp/vocab.txt", "a", encoding="utf-8") as f:
        f.write(f"{case}: {text}\n")

    said = {
        "Build": _error_of(bpy.ops.lamp.build, capfd),
        "F12": _error_of(bpy.ops.render.render, capfd),
        "Render with Lamp Tracer": _error_of(bpy.ops.lamp.render_tracer, capfd),
        "Compare": _error_of(bpy.ops.lamp.compare_cycles, capfd, samples=1),
    }
    for where, error in said.items():
        assert text in error, (where, error)


def test_the_lens_too_large_for_the_body_highlights_the_lens_and_offers_the_body(lamp_addon, bl_scene):
    design = _design(lamp_addon, bl_scene)
    _status(bl_scene)
    design.lamps[0].lens.radius = 80.0
    problem = lamp_addon.design.validity.status(bl_scene).problem
    assert problem.path == "body.size"  # the rule names the body ...
    assert problem.property_path == "lamps[0].lens.radius"  # ... the field changed is the one highlighted
    assert problem.text().startswith("Lamp 1 › Lens › Radius: ")
    assert "Radius: Body › Size [220.0, 120.0] cannot hold the lens of Lamp 1 (radius 80 mm)" in problem.text()
    assert "a smaller Lamp 1 › Lens › Radius, at most 60 mm" in problem.text()


@pytest.mark.slow
def test_the_command_line_keeps_the_json_paths(tmp_path):
    scene = core_tracer.load_scene(str(BASELINE))
    scene["lamps"][0]["cuts"]["height"] = 8.0
    path = tmp_path / "bad.json"
    path.write_text(core_tracer.scene_to_json(scene), encoding="utf-8")
    done = run_cli("validate", path)
    assert done.returncode != 0 and "lamps[0].cuts.height: 8 is more than a hemisphere" in done.stdout + done.stderr


@pytest.mark.parametrize("then", ["Apply Preset", "Build"])
def test_an_edit_made_before_the_panel_draws_still_highlights_the_field_changed(lamp_addon, bl_scene, capfd, then):
    """Apply Preset and Build remember the valid design they leave (``validity.remember``): a lens
    radius set too large right after them, with no panel drawn in between (a script, a headless walk),
    is named first by Build, not the body the rule names (the issue-24 walk's finding)."""
    import bpy

    lamp_addon.design.validity._memo["valid"].clear()  # no design seen valid yet in this file
    scene = core_tracer.load_scene(str(BASELINE))
    scene["image"] = {"width": 24, "height": 16}
    lamp_addon.presets.apply.apply_preset_whole(bl_scene, scene, str(BASELINE))
    bl_scene.lamp_design.auto_build = False
    if then == "Build":
        lamp_addon.design.validity._memo["valid"].clear()
        bpy.ops.lamp.build()
    bl_scene.lamp_design.lamps[0].lens.radius = 80.0
    error = _error_of(bpy.ops.lamp.build, capfd)
    assert "Lamp 1 › Lens › Radius: Body › Size" in error, error

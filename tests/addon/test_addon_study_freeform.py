"""A study of a free-form design from Blender's Study panel, as the command line's ``study`` makes it:
the shipped photometric free-form example applied from the preset browser, its parts' values varied
(the lens filter, the bulb's state), the meshes written once beside the study (``study.meshes``), the
sheet saved with its .glb beside it, and the command line re-running the study from that sheet."""

from __future__ import annotations

import json

import numpy as np
import pytest
from helpers import PRESETS, applied_preset, run_cli

pytestmark = pytest.mark.blender

TWIN = PRESETS / "freeform-sculpted-wrap-lamp-photometric.json"


def _cell_means(lamp_addon, image, study) -> list[np.ndarray]:
    """The mean scene-linear RGB of the brightest tenth of each cell's pixels (the lit lens)."""
    from core_tracer.study import sheet as study_sheet

    lay = study_sheet.layout(lamp_addon.study.settings.worded(study))
    pixels = lamp_addon.image_view.image_to_array(image)
    means = []
    for rect in lay.cells:
        cell = pixels[rect.y:rect.y + rect.h, rect.x:rect.x + rect.w, :3].reshape(-1, 3)
        bright = cell[cell.sum(axis=1) >= np.quantile(cell.sum(axis=1), 0.9)]
        means.append(bright.mean(axis=0))
    return means


@pytest.mark.slow  # worker processes
def test_run_study_of_the_free_form_photometric_example_and_save_its_sheet(lamp_addon, addon, tmp_path):
    import bpy

    bl_scene = applied_preset(TWIN)
    settings = bl_scene.lamp_study
    settings.axis_1.parameter = "freeform.parts[].lens.filter"
    settings.axis_1.values = "red, amber"
    settings.axis_2.parameter = "freeform.parts[].bulb.state"
    settings.axis_2.values = "tail, stop"
    settings.use_axis_2, settings.width, settings.height, settings.workers = True, 64, 48, 2
    assert bpy.ops.lamp.study_run() == {"FINISHED"}

    study = lamp_addon.study.settings.last_study()
    mesh_file = study.base["freeform"]["mesh_file"]
    # the study names its meshes by a plain name (of their bytes), as an exported pair does
    assert mesh_file.startswith("lamp-study-") and "/" not in mesh_file and len(study) == 4
    assert study.size == (62, 50)  # the render's aspect (320 x 256) at about 64 x 48 pixels
    (red_tail, amber_tail), (red_stop, amber_stop) = np.reshape(
        _cell_means(lamp_addon, bpy.data.images["Lamp Study"], study), (2, 2, 3))
    print("cell means (R, G, B):", red_tail, amber_tail, red_stop, amber_stop)
    for tail, stop in ((red_tail, red_stop), (amber_tail, amber_stop)):
        assert stop.sum() > 3 * tail.sum()  # the stop filament: 440 lm against the tail's 35
    for red, amber in ((red_tail, amber_tail), (red_stop, amber_stop)):
        assert red[0] > 4 * red[1]  # a red lens passes no green
        assert amber[1] / amber[0] > 3 * red[1] / red[0]  # an amber one does

    sheet = tmp_path / "sheet.png"
    assert bpy.ops.lamp.study_save_sheet(filepath=str(sheet)) == {"FINISHED"}
    print("sheet:", sheet)
    assert (tmp_path / mesh_file).is_file()  # the meshes beside the sheet
    # the command line re-runs the sheet's study, reading the .glb beside it
    done = run_cli("study", "--study", sheet, "-o", tmp_path / "again.exr", "--workers", "2")
    assert done.returncode == 0, done.stderr
    again = json.loads(json.dumps(study.to_doc()))
    assert again["base"]["freeform"]["mesh_file"] == mesh_file

    # Apply to Design sets the parts' values of the chosen variant (4: amber, stop)
    settings.variant = 4
    assert bpy.ops.lamp.study_apply_variant() == {"FINISHED"}
    parts = {o.lamp_role.role: o for o in lamp_addon.freeform.properties.role_objects(bl_scene)}
    assert parts["lens"].lamp_role.lens.filter == "amber" and parts["bulb"].lamp_role.bulb.state == "stop"


def test_a_lamp_parameter_of_a_free_form_design_is_refused_in_one_line(lamp_addon, addon):
    import bpy

    bl_scene = applied_preset(TWIN)
    bl_scene.lamp_study.axis_1.parameter = "lens.ior"
    bl_scene.lamp_study.use_axis_2 = False
    with pytest.raises(RuntimeError, match="parametric lamps, which a free-form design does not trace") as err:
        bpy.ops.lamp.study_run()
    assert "\n" not in str(err.value).strip()

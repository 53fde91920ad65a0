"""Measures in Blender's Study section: the settings (Measures, Sort By, Filter), the sheet they make."""

from __future__ import annotations

import time

import pytest
from helpers import PRESETS
from study_axes import one_axis

pytestmark = pytest.mark.blender


@pytest.fixture
def stop_study(lamp_addon, addon_core, bl_scene):
    scene = addon_core.scene.load_scene(PRESETS / "photometric-stop-lamp.json")
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    one_axis(bl_scene.lamp_study, "cuts.height", "0.5, 3", width=24, height=16, fit_lamp=False, workers=1)
    return bl_scene


def test_the_settings_give_the_study_fields(lamp_addon, stop_study):
    settings = stop_study.lamp_study
    study_settings = lamp_addon.study.settings
    assert study_settings.study_from_settings(stop_study).to_doc().keys() == {"schema", "base", "axes", "size"}
    settings.measures = "homogeneity.lmin_lmax, intensity.hv_cd@stop"
    settings.sort_by = "-homogeneity.lmin_lmax"
    settings.filter = "grid.pass==1"
    doc = study_settings.study_from_settings(stop_study).to_doc()
    assert (doc["measures"], doc["sort"], doc["filter"]) == (
        ["homogeneity.lmin_lmax", "intensity.hv_cd@stop"], "-homogeneity.lmin_lmax", ["grid.pass==1"])


@pytest.mark.parametrize(("field", "text", "words"), [
    ("measures", "homogeneity.evenness", "Measures"), ("sort_by", "-grid.passes", "Sort By"),
    ("filter", "grid.pass=1", "Filter")])
def test_bad_settings_are_named_in_panel_words(lamp_addon, addon_core, stop_study, field, text, words):
    setattr(stop_study.lamp_study, field, text)
    with pytest.raises(addon_core.scene.reading.SceneError) as e:
        lamp_addon.study.settings.study_from_settings(stop_study)
    assert e.value.path == words and "homogeneity.lmin_lmax" in e.value.message


def test_the_panel_offers_the_measures_for_photometric_designs_only(lamp_addon, stop_study):
    import bpy
    from test_addon_panels import draw

    props = {p for _, _, p, _ in draw(bpy.types.LAMP_PT_study, stop_study).props()}
    assert {"measures", "sort_by", "filter"} <= props
    stop_study.lamp_design.light_model = "paper"
    props = {p for _, _, p, _ in draw(bpy.types.LAMP_PT_study, stop_study).props()}
    assert not {"measures", "sort_by", "filter"} & props


@pytest.mark.slow
def test_a_study_with_measures_runs_and_the_worker_path_gives_the_same_values(lamp_addon, stop_study):
    import bpy

    settings = stop_study.lamp_study
    assert bpy.ops.lamp.study_run() == {"FINISHED"}
    plain = tuple(bpy.data.images["Lamp Study"].size)
    settings.measures = "homogeneity.lmin_lmax, intensity.hv_cd"
    settings.sort_by = "intensity.hv_cd"
    assert bpy.ops.lamp.study_run() == {"FINISHED"}  # background: measured in this process
    image = bpy.data.images["Lamp Study"]
    assert image.size[1] > plain[1]  # two more lines under each cell and the order line
    study = lamp_addon.study.settings.last_study()
    assert study.measured.names == ("homogeneity.lmin_lmax", "intensity.hv_cd")
    # The modal operator's path: one measure worker process per variant.
    measures = lamp_addon.study.ops.VariantMeasures(study)
    try:
        deadline = time.monotonic() + 300
        while not measures.poll():
            assert time.monotonic() < deadline
            time.sleep(0.2)
    finally:
        measures.close()
    from importlib import import_module

    measured = import_module(lamp_addon.__name__.rsplit(".", 1)[0] + ".core_tracer.study.measured")
    direct = measured.measure_variants([v.scene for v in study.variants], study.measured.names)
    for by_worker, here in zip(measures.values, direct, strict=True):
        for name in study.measured.names:
            assert by_worker[name] == pytest.approx(here[name], rel=1e-6), name
    assert direct[0]["intensity.hv_cd"] != direct[1]["intensity.hv_cd"]  # the variants differ


def test_closing_the_measures_under_way_stops_the_worker_and_removes_its_folder(lamp_addon, stop_study):
    import os

    stop_study.lamp_study.measures = "grid.pass"
    study = lamp_addon.study.settings.study_from_settings(stop_study)
    measures = lamp_addon.study.ops.VariantMeasures(study)
    assert not measures.poll()  # the first variant's worker started
    process = measures._run._process
    folder = measures._folder
    measures.close()  # what Esc does
    assert process.poll() is not None and not os.path.exists(folder)
    assert measures.values == []

"""The Study panel's scheduler field: "local" keeps this computer's worker processes; a Dask
scheduler's address renders the variants as tasks on that cluster (a real local cluster here, its
workers finding the add-on's ``bl_ext...core_tracer`` names as the checkout's ``core_tracer``),
with the same sheet, and a re-run comes from the cell cache."""

from __future__ import annotations

import json

import numpy as np
import pytest
from helpers import BASELINE
from study_axes import one_axis

import core_tracer
from core_tracer.cluster import engine

pytestmark = [pytest.mark.blender, pytest.mark.slow]


@pytest.fixture
def design(lamp_addon, bl_scene, tmp_path, monkeypatch):
    monkeypatch.setenv("LAMP_STYLING_CACHE", str(tmp_path / "cache"))
    with open(BASELINE, encoding="utf-8") as f:
        scene = core_tracer.parse_scene(json.load(f))
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    lamp_addon.design.lamp_camera.ensure_lamp_camera(bl_scene, frame=False)
    one_axis(bl_scene.lamp_study, width=32, height=32, fit_lamp=False)
    return bl_scene


def test_a_scheduler_address_renders_the_study_on_that_cluster(design, lamp_addon):
    import bpy

    assert design.lamp_study.scheduler == "local" and not lamp_addon.study.settings.uses_cluster(design.lamp_study)
    assert bpy.ops.lamp.study_run() == {"FINISHED"}
    local = lamp_addon.image_view.image_to_array(bpy.data.images["Lamp Study"]).copy()
    with engine.connect(workers=2, memory_limit=engine.worker_memory([])) as client:
        design.lamp_study.scheduler = client.scheduler.address
        assert lamp_addon.study.settings.uses_cluster(design.lamp_study)
        assert bpy.ops.lamp.study_run() == {"FINISHED"}
        on_cluster = lamp_addon.image_view.image_to_array(bpy.data.images["Lamp Study"]).copy()
        tasks = client.run_on_scheduler(lambda dask_scheduler: len(dask_scheduler.transition_log))
        # Again: every variant from the cell cache, no task sent.
        assert bpy.ops.lamp.study_run() == {"FINISHED"}
        again = client.run_on_scheduler(lambda dask_scheduler: len(dask_scheduler.transition_log))
    assert tasks > 0 and again == tasks
    np.testing.assert_array_equal(on_cluster, local)


def test_an_address_without_a_scheduler_is_reported(design, lamp_addon):
    import bpy

    design.lamp_study.scheduler = "tcp://127.0.0.1:9"
    with pytest.raises(RuntimeError, match="Lamp Study failed"):
        bpy.ops.lamp.study_run()

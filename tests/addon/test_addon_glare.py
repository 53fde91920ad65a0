"""Glare in Blender: the engine's F12 result and the Lamp Tracer image hold the same pixels as the
command line's render of the same scene."""

from __future__ import annotations

import json

import numpy as np
import pytest
from helpers import FOUR_LAMPS, run_cli

import core_tracer
from core_tracer.images import glare, imageio

pytestmark = pytest.mark.blender


def _glare_scene(size=(48, 32)) -> dict:
    doc = json.loads(FOUR_LAMPS.read_text())
    doc["image"] = {"width": size[0], "height": size[1]}
    doc["glare"] = {"on": True, "threshold": 2.0, "strength": 0.75}
    return core_tracer.parse_scene(doc)


def _load_design(lamp_addon, bl_scene, scene: dict) -> None:
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    lamp_addon.design.lamp_camera.ensure_lamp_camera(bl_scene, frame=False)


def _cli_exr(scene: dict, tmp_path) -> np.ndarray:
    path = tmp_path / "scene.json"
    path.write_text(core_tracer.scene_to_json(scene))
    out = tmp_path / "cli.exr"
    proc = run_cli("render", path, "-o", out)
    assert proc.returncode == 0, proc.stderr
    return imageio.read_image(out)[0]


@pytest.mark.slow
def test_engine_glare_equals_the_command_line(lamp_addon, bl_scene, tmp_path):
    import bpy
    import OpenImageIO as oiio

    _load_design(lamp_addon, bl_scene, _glare_scene())
    assert bl_scene.lamp_design.glare.on
    bl_scene.render.engine = "LAMP_TRACER"
    settings = bl_scene.render.image_settings
    settings.file_format, settings.color_depth = "OPEN_EXR", "32"
    bpy.ops.render.render()
    path = tmp_path / "engine.exr"
    bpy.data.images["Render Result"].save_render(str(path), scene=bl_scene)
    buf = oiio.ImageBuf(str(path))
    engine = np.asarray(buf.get_pixels(oiio.FLOAT)).reshape(32, 48, -1)[:, :, :3]

    seen = lamp_addon.design.camera.scene_for_render(bl_scene)
    assert seen["glare"] == {"on": True, "threshold": 2.0, "strength": 0.75}
    cli = _cli_exr(seen, tmp_path)
    np.testing.assert_array_equal(engine, cli)  # pixel for pixel
    plain = core_tracer.render(seen)
    assert not np.array_equal(engine, plain)  # the glare is there ...
    np.testing.assert_allclose(engine.sum(axis=(0, 1), dtype=np.float64),
                               plain.sum(axis=(0, 1), dtype=np.float64), rtol=1e-6)  # ... and moves light only


def test_lamp_tracer_image_and_job_hold_the_glare(lamp_addon, bl_scene):
    import bpy

    scene = _glare_scene()
    _load_design(lamp_addon, bl_scene, scene)
    assert bpy.ops.lamp.render_tracer() == {"FINISHED"}
    seen = lamp_addon.design.camera.scene_for_render(bl_scene)
    expected = glare.apply(core_tracer.render(seen), seen)
    image = bpy.data.images["Lamp Tracer"]
    assert image["lamp_exposure"] == 0.0  # shown at the view's exposure, as F12
    np.testing.assert_array_equal(lamp_addon.image_view.image_to_array(image), expected)
    job = lamp_addon.render.ops.TracerJob(seen).start()  # the modal render's worker
    assert job.wait(60.0) and job.error is None
    np.testing.assert_array_equal(job.rows, expected)

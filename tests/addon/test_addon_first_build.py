"""The first build of a design sets the file up to show the lamp (``lamp_addon.design.setup``).

In Blender's startup file the first Build makes the Lamp Camera (framing every lens) the scene
camera, switches EEVEE to Lamp Tracer and sets the scene's exposure to the design's automatic
exposure, each said in the report; the startup Camera object is never touched. Later builds change
none of what the user chose afterwards, the exposure included (``test_addon_exposure_policy``).
Compare rebuilds only objects that are out of date.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import BASELINE
from test_addon_framing import rims_in_image

import core_tracer

pytestmark = pytest.mark.blender

SIZE = (64, 48)


def _baseline(size=SIZE) -> dict:
    scene = core_tracer.load_scene(str(BASELINE))
    scene["image"] = {"width": size[0], "height": size[1]}
    return scene


def _object_state(ob) -> tuple:
    return (ob.name, ob.parent, tuple(tuple(r) for r in ob.matrix_world), ob.data.lens, ob.data.type,
            ob.hide_render, dict(ob.items()))


def test_first_build_in_the_startup_file_sets_the_scene_up_for_the_lamp(lamp_addon, startup_scene, capfd):
    import bpy

    camera = startup_scene.objects["Camera"]
    before = _object_state(camera)
    lamp_addon.design.properties.scene_to_design(startup_scene, _baseline())
    capfd.readouterr()
    assert bpy.ops.lamp.build() == {"FINISHED"}
    report = capfd.readouterr().out

    lamp_camera = startup_scene.camera
    assert lamp_addon.design.camera.is_lamp_camera(lamp_camera) and lamp_camera.name == "Lamp Camera"
    assert lamp_camera.parent == lamp_addon.design.root.find_root(startup_scene)  # moves with the lamp
    assert _object_state(camera) == before  # the user's camera object: untouched
    assert rims_in_image(lamp_addon, startup_scene) == [True]
    assert startup_scene.render.engine == "LAMP_TRACER"
    expected = lamp_addon.image_view.design_exposure(lamp_addon.design.camera.scene_for_render(startup_scene))
    assert expected < -1.0  # a lit lens is many times display white
    assert startup_scene.view_settings.exposure == pytest.approx(expected, abs=1e-6)
    view = core_tracer.images.display.LAMP_VIEW  # lit red and amber keep their hue (issue 31)
    assert startup_scene.view_settings.view_transform == view
    for said in ('Made the scene camera "Lamp Camera"', 'your "Camera" is kept as it was',
                 "Render engine Lamp Tracer (was EEVEE", f"Exposure {expected:+.1f} EV",
                 f"View transform {view} (was AgX, Blender's default)",
                 f'Built 6 objects; it is inside "Cube": Hide Other Objects shows it; set up "Lamp Camera", '
                 f"Lamp Tracer, {view}, {expected:+.1f} EV"):
        assert said in report, (said, report)
    assert all(len(line) <= len("Info: ") + 120 for line in report.splitlines())  # each report one line


def test_later_builds_keep_what_the_user_chose(lamp_addon, startup_scene, capfd):
    import bpy

    lamp_addon.design.properties.scene_to_design(startup_scene, _baseline())
    assert bpy.ops.lamp.build() == {"FINISHED"}
    startup_scene.camera = startup_scene.objects["Camera"]  # the user's choices after the first build
    startup_scene.render.engine = "CYCLES"
    startup_scene.view_settings.exposure = 1.5
    startup_scene.view_settings.view_transform = "AgX"
    startup_scene.lamp_design.lamps[0].lens.ior = 1.6  # an edit: the objects are out of date
    capfd.readouterr()
    assert bpy.ops.lamp.build() == {"FINISHED"}
    report = capfd.readouterr().out
    assert startup_scene.camera.name == "Camera" and startup_scene.render.engine == "CYCLES"
    assert startup_scene.view_settings.exposure == 1.5 and startup_scene.view_settings.view_transform == "AgX"
    assert "scene camera" not in report and "engine" not in report and "exposure" not in report


def test_a_file_set_up_otherwise_is_left_alone(lamp_addon, startup_scene):
    """A render engine other than EEVEE and an exposure other than 0 are the user's choices."""
    import bpy

    startup_scene.render.engine = "CYCLES"
    startup_scene.view_settings.exposure = -1.0
    lamp_addon.design.properties.scene_to_design(startup_scene, _baseline())
    assert bpy.ops.lamp.build() == {"FINISHED"}
    assert startup_scene.render.engine == "CYCLES" and startup_scene.view_settings.exposure == -1.0
    assert lamp_addon.design.camera.is_lamp_camera(startup_scene.camera)


def test_the_first_lamp_added_sets_the_scene_up(lamp_addon, startup_scene):
    """A new design's first lamp is built by Auto Build (a timer, in the interface): Add Lamp sets the
    scene up, with the lamp framed."""
    import bpy

    assert len(startup_scene.lamp_design.lamps) == 0 and startup_scene.lamp_design.auto_build
    assert bpy.ops.lamp.lamp_add() == {"FINISHED"}
    assert lamp_addon.design.camera.is_lamp_camera(startup_scene.camera)
    assert startup_scene.render.engine == "LAMP_TRACER" and startup_scene.view_settings.exposure < -1.0
    assert rims_in_image(lamp_addon, startup_scene) == [True]
    # The build the timer makes (tests have no event loop: the same build called here).
    assert startup_scene.camera.parent is None  # made before the root
    lamp_addon.design.builder.build_lamp(startup_scene, lamp_addon.design.properties.design_to_scene(startup_scene))
    startup_scene.view_layers[0].update()  # the depsgraph update after the timer's build
    assert startup_scene.camera.parent == lamp_addon.design.root.find_root(startup_scene)


def test_the_lamp_camera_moves_with_the_root(lamp_addon, startup_scene):
    """Moving the root (the lamp onto a car) carries the lamp's own view along: the design's camera
    stays valid and the lens stays framed."""
    import bpy
    from mathutils import Euler

    lamp_addon.design.properties.scene_to_design(startup_scene, _baseline())
    assert bpy.ops.lamp.build() == {"FINISHED"}
    view = dict(lamp_addon.design.camera.scene_for_render(startup_scene)["camera"])
    root = lamp_addon.design.root.find_root(startup_scene)
    root.location = (1.2, 2.5, 0.7)
    root.rotation_euler = Euler((0.0, 0.0, math.radians(180)))
    startup_scene.view_layers[0].update()
    assert bpy.ops.lamp.build() == {"FINISHED"}
    moved = lamp_addon.design.camera.scene_for_render(startup_scene)["camera"]
    np.testing.assert_allclose(moved["position"], view["position"], atol=1e-3)
    np.testing.assert_allclose(moved["target"], view["target"], atol=1e-3)
    assert rims_in_image(lamp_addon, startup_scene) == [True]


# ---------------------------------------------------------------------------------------------
# Compare rebuilds only what is out of date


def test_compare_needs_a_build_only_when_the_objects_are_out_of_date(lamp_addon, addon_core, bl_scene):
    compare, builder = lamp_addon.compare.scope, lamp_addon.design.builder
    lamp_addon.design.properties.scene_to_design(bl_scene, _baseline())
    assert compare.needs_build(bl_scene)  # not built
    scene = lamp_addon.design.properties.design_to_scene(bl_scene)
    builder.build_lamp(bl_scene, scene)
    assert not compare.needs_build(bl_scene)
    bl_scene.lamp_design.lamps[0].lens.ior = 1.6
    assert compare.needs_build(bl_scene)  # out of date
    builder.build_lamp(bl_scene, lamp_addon.design.properties.design_to_scene(bl_scene), preview=True)
    assert builder.build_status(bl_scene) in (builder.UP_TO_DATE, builder.PREVIEW)
    assert compare.needs_build(bl_scene) == (builder.build_status(bl_scene) == builder.PREVIEW)


def _lens_ior_input(lamp_addon, bl_scene):
    lens = next(o for o in bl_scene.objects if o.get("lamp_part") == "lamps[0].lens")
    return lens.data.materials[0].node_tree.nodes["Lens BSDF"].inputs["IOR"]


@pytest.mark.slow
def test_compare_renders_up_to_date_objects_as_they_are(lamp_addon, bl_scene):
    """Up to date: no rebuild, so a value the designer typed on the material (a driven one) is what
    Cycles renders (a rebuild would have put the design's back)."""
    import bpy

    lamp_addon.design.properties.scene_to_design(bl_scene, _baseline((24, 20)))
    assert bpy.ops.lamp.build() == {"FINISHED"}
    ior = _lens_ior_input(lamp_addon, bl_scene)
    ior.default_value = 1.7
    lamp_addon.compare.comparison.compare_design(bl_scene, samples=1)
    assert _lens_ior_input(lamp_addon, bl_scene).default_value == pytest.approx(1.7)


@pytest.mark.slow
def test_compare_rebuilds_out_of_date_objects(lamp_addon, bl_scene):
    import bpy

    lamp_addon.design.properties.scene_to_design(bl_scene, _baseline((24, 20)))
    assert bpy.ops.lamp.build() == {"FINISHED"}
    bl_scene.lamp_design.auto_build = False
    bl_scene.lamp_design.lamps[0].lens.ior = 1.6
    assert not lamp_addon.design.builder.is_up_to_date(bl_scene)
    lamp_addon.compare.comparison.compare_design(bl_scene, samples=1)
    assert _lens_ior_input(lamp_addon, bl_scene).default_value == pytest.approx(1.6)
    assert lamp_addon.design.builder.is_up_to_date(bl_scene)


@pytest.mark.slow
def test_the_first_build_keeps_a_view_that_shows_the_body_and_frames_one_that_does_not(lamp_addon, startup_scene):
    import bpy

    scene = _baseline()
    lamp_addon.design.properties.scene_to_design(startup_scene, scene)
    assert lamp_addon.design.setup.design_view_shows_body(startup_scene)
    assert bpy.ops.lamp.build() == {"FINISHED"}
    seen = lamp_addon.design.camera.scene_for_render(startup_scene)["camera"]
    np.testing.assert_allclose(seen["position"], scene["camera"]["position"], atol=1e-3)  # the preset's view
    np.testing.assert_allclose(seen["target"], scene["camera"]["target"], atol=1e-3)

    bpy.ops.wm.read_homefile(use_factory_startup=True)
    startup_scene = bpy.context.scene
    close = {**scene, "camera": {**scene["camera"], "position": [60.0, -150.0, 20.0]}}  # too close to hold the body
    lamp_addon.design.properties.scene_to_design(startup_scene, close)
    assert not lamp_addon.design.setup.design_view_shows_body(startup_scene)
    assert bpy.ops.lamp.build() == {"FINISHED"}
    assert rims_in_image(lamp_addon, startup_scene) == [True]
    seen = lamp_addon.design.camera.scene_for_render(startup_scene)["camera"]
    assert lamp_addon.design.setup.design_view_shows_body(startup_scene)  # the design's fields follow the framing
    direction = np.subtract(seen["target"], seen["position"])
    wanted = np.subtract(close["camera"]["target"], close["camera"]["position"])
    cosine = direction @ wanted / np.linalg.norm(direction) / np.linalg.norm(wanted)
    assert cosine > 0.999  # framed from the design's own direction


def test_a_preset_applied_in_the_startup_file_sets_the_scene_up(lamp_addon, startup_scene):
    """A new user's other first step: a built-in preset applied in the startup file (Auto Build makes
    its lamp a moment later) shows the preset's view through the Lamp Camera, with Lamp Tracer and the
    design's exposure; the startup Camera object is untouched."""
    import bpy

    camera_before = _object_state(startup_scene.objects["Camera"])
    wm = bpy.context.window_manager
    bpy.ops.lamp.preset_refresh()
    wm.lamp_presets_index = next(i for i, item in enumerate(wm.lamp_presets) if item.file.endswith(BASELINE.name))
    assert bpy.ops.lamp.preset_apply() == {"FINISHED"}
    assert lamp_addon.design.camera.is_lamp_camera(startup_scene.camera)
    assert startup_scene.render.engine == "LAMP_TRACER" and startup_scene.view_settings.exposure < -1.0
    assert rims_in_image(lamp_addon, startup_scene) == [True]
    assert _object_state(startup_scene.objects["Camera"]) == camera_before

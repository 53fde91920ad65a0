"""Whatever else is in the file, the lamp is what renders, framed.

From Blender's startup file (Cube, Camera, Light) or with a large object around the lamp, Compare shows
the same lamp in both halves as in an empty file; the objects it left out of Cycles are named. Adding
lamps keeps every lens in the Lamp Camera's image; a camera of the user's is never moved.

A lens pixel is a red one (R above 1.5 times G and B, and above 0.02): the baseline's red lens, lit or
not, against the grey body, the grey startup Cube and the black background.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import BASELINE

import core_tracer

SIZE = (48, 40)
SAMPLES = 4


def lens_share(image: np.ndarray) -> float:
    r, g, b = image[..., 0], image[..., 1], image[..., 2]
    return float(np.mean((r > 1.5 * g) & (r > 1.5 * b) & (r > 0.02)))


def _baseline(size=SIZE) -> dict:
    scene = core_tracer.load_scene(str(BASELINE))
    scene["image"] = {"width": size[0], "height": size[1]}
    return scene


def _clean_comparison(lamp_addon, bl_scene) -> dict:
    lamp_addon.design.properties.scene_to_design(bl_scene, _baseline())
    return lamp_addon.compare.comparison.compare_design(bl_scene, samples=SAMPLES)


@pytest.fixture
def clean(lamp_addon, bl_scene):
    """The baseline compared in an empty file: the shares every other file must give."""
    result = _clean_comparison(lamp_addon, bl_scene)
    shares = {name: lens_share(result[name]) for name in ("tracer", "cycles")}
    assert shares["tracer"] > 0.05 and shares["cycles"] > 0.05  # the lens is plainly there
    return shares, result


def _assert_same_lamp(result, clean_shares) -> dict:
    shares = {name: lens_share(result[name]) for name in ("tracer", "cycles")}
    print(f"\nlens-pixel share: {shares} (empty file: {clean_shares})")
    assert shares["tracer"] == pytest.approx(clean_shares["tracer"], abs=1e-9)  # the very same tracer image
    assert shares["cycles"] == pytest.approx(clean_shares["cycles"], rel=0.05)  # Cycles' noise at 4 samples
    return shares


@pytest.mark.slow
def test_startup_file_build_then_compare_shows_the_lamp_in_both_halves(lamp_addon, clean, tmp_path):
    import bpy

    clean_shares, clean_result = clean
    bpy.ops.wm.read_homefile(use_factory_startup=True)
    bl_scene = bpy.context.scene
    assert {"Cube", "Camera", "Light"} <= set(bl_scene.objects.keys()) and hasattr(bl_scene, "lamp_design")
    startup_camera = bl_scene.objects["Camera"]
    before = tuple(startup_camera.location), tuple(startup_camera.rotation_euler), startup_camera.data.lens
    lamp_addon.design.properties.scene_to_design(bl_scene, _baseline())
    assert bpy.ops.lamp.build() == {"FINISHED"}
    assert lamp_addon.design.camera.is_lamp_camera(bl_scene.camera)  # the first Build made it the scene camera
    assert bpy.ops.lamp.compare_cycles(samples=SAMPLES) == {"FINISHED"}
    result = lamp_addon.compare.comparison.compare_design(bl_scene, samples=SAMPLES)
    _assert_same_lamp(result, clean_shares)
    assert sorted(result["left_out"]) == ["Cube", "Light"]
    assert lamp_addon.compare.scope.left_out_text(result["left_out"]) == "left out of the Cycles half: Cube, Light"
    # Put back exactly: the Cube and the Light render again; the startup camera never moved.
    assert not bl_scene.objects["Cube"].hide_render and not bl_scene.objects["Light"].hide_render
    assert (tuple(startup_camera.location), tuple(startup_camera.rotation_euler), startup_camera.data.lens) == before
    assert lamp_addon.design.camera.is_lamp_camera(bl_scene.camera)
    # The render size is the design's, not the startup file's 1920 x 1080.
    assert (bl_scene.render.resolution_x, bl_scene.render.resolution_y) == SIZE
    lamp_addon.compare.comparison.write_comparison(str(tmp_path / "startup-compare.png"), result)


@pytest.mark.slow
def test_a_large_object_enclosing_the_lamp_is_left_out(lamp_addon, clean, bl_scene):
    import bpy

    clean_shares, _ = clean
    bpy.ops.wm.read_homefile(use_empty=True)
    bl_scene = bpy.context.scene
    lamp_addon.design.properties.scene_to_design(bl_scene, _baseline())
    bpy.ops.mesh.primitive_cube_add(size=4.0)  # a 4 m "car" around the lamp and the camera
    car = bpy.context.active_object
    car.name = "Car Body"
    light = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
    bl_scene.collection.objects.link(light)
    light.hide_render = True  # already out of the render: not reported
    props = bpy.data.collections.new("Props")  # nor what a collection hidden from render holds
    bl_scene.collection.children.link(props)
    props.hide_render = True
    props.objects.link(bpy.data.objects.new("Wheel", bpy.data.meshes.new("Wheel")))
    result = lamp_addon.compare.comparison.compare_design(bl_scene, samples=SAMPLES)
    _assert_same_lamp(result, clean_shares)
    assert result["left_out"] == ["Car Body"]
    assert not car.hide_render and light.hide_render


def test_a_cancelled_comparison_puts_the_left_out_objects_back(lamp_addon, bl_scene):
    import bpy

    compare = lamp_addon.compare.comparison
    bpy.ops.wm.read_homefile(use_factory_startup=True)
    bl_scene = bpy.context.scene
    lamp_addon.design.properties.scene_to_design(bl_scene, _baseline())
    with compare.CompareRun(bl_scene, samples=1) as run:
        run.prepare()
        assert bl_scene.objects["Cube"].hide_render and bl_scene.objects["Light"].hide_render
        run.start(compare.CYCLES)
        run.report_end("cancel")
        with pytest.raises(compare.CompareCancelled):
            run.collect()
    assert not bl_scene.objects["Cube"].hide_render and not bl_scene.objects["Light"].hide_render


def rims_in_image(lamp_addon, bl_scene) -> list[bool]:
    """For each lamp: whether its whole lens rim projects inside the image the tracer renders."""
    seen = lamp_addon.design.camera.scene_for_render(bl_scene)
    size = (seen["image"]["width"], seen["image"]["height"])
    inside = []
    for lamp in seen["lamps"]:
        (x, z), r = lamp["center"], lamp["lens"]["radius"]
        rim = [(x + r * math.cos(a), 0.0, z + r * math.sin(a)) for a in np.linspace(0, 2 * math.pi, 73)]
        points = np.array(lamp_addon.convert.camera.project(seen["camera"], size, rim))
        inside.append(bool((points[:, 0] > 0).all() and (points[:, 0] < size[0]).all()
                           and (points[:, 1] > 0).all() and (points[:, 1] < size[1]).all()
                           and (points[:, 2] > 0).all()))  # and in front of the camera
    return inside


@pytest.mark.slow
def test_four_lamps_added_in_the_startup_file_are_all_in_the_image(lamp_addon, bl_scene):
    """The first Build in the startup file makes the Lamp Camera the scene camera; Add Lamp keeps it
    framed, so all four lamps are in the image."""
    import bpy

    bpy.ops.wm.read_homefile(use_factory_startup=True)
    bl_scene = bpy.context.scene
    lamp_addon.design.properties.scene_to_design(bl_scene, _baseline())
    assert bpy.ops.lamp.build() == {"FINISHED"}
    for _ in range(3):
        assert bpy.ops.lamp.lamp_add() == {"FINISHED"}
    assert bpy.ops.lamp.build() == {"FINISHED"}
    assert lamp_addon.design.camera.is_lamp_camera(bl_scene.camera)
    assert rims_in_image(lamp_addon, bl_scene) == [True] * 4


@pytest.mark.slow
def test_four_lamps_after_add_lamp_are_all_in_the_image(lamp_addon, bl_scene):
    import bpy

    lamp_addon.design.properties.scene_to_design(bl_scene, _baseline())
    assert bpy.ops.lamp.build() == {"FINISHED"}  # an empty file: Build makes the Lamp Camera
    assert lamp_addon.design.camera.is_lamp_camera(bl_scene.camera)
    for _ in range(3):
        assert bpy.ops.lamp.lamp_add() == {"FINISHED"}
    assert bpy.ops.lamp.build() == {"FINISHED"}
    assert len(bl_scene.lamp_design.lamps) == 4
    assert rims_in_image(lamp_addon, bl_scene) == [True] * 4
    # What the tracer renders holds every lens: a red lens pixel near each lens centre.
    seen = lamp_addon.design.camera.scene_for_render(bl_scene)
    image = core_tracer.render(seen)
    size = (seen["image"]["width"], seen["image"]["height"])
    for lamp in seen["lamps"]:
        col, row, _ = lamp_addon.convert.camera.project(seen["camera"], size, [(lamp["center"][0], 0.0,
                                                                                lamp["center"][1])])[0]
        assert lens_share(image[int(row) - 1:int(row) + 2, int(col) - 1:int(col) + 2]) > 0.5
    # Removing a lamp keeps the body, so the view; a smaller body is framed closer.
    far = math.dist(seen["camera"]["position"], seen["camera"]["target"])
    bl_scene.lamp_design.active_lamps_index = 3
    assert bpy.ops.lamp.lamp_remove() == {"FINISHED"}
    assert rims_in_image(lamp_addon, bl_scene) == [True] * 3
    bl_scene.lamp_design.body.size = (320.0, 110.0)
    bl_scene.lamp_design.body.center = (95.0, 0.0)
    assert lamp_addon.design.lamp_camera.keep_framed(bl_scene)
    near = lamp_addon.design.camera.scene_for_render(bl_scene)["camera"]
    assert math.dist(near["position"], near["target"]) < 0.8 * far
    assert rims_in_image(lamp_addon, bl_scene) == [True] * 3


def test_without_reframing_the_fourth_lamp_leaves_the_image(lamp_addon, bl_scene):
    """What the issue saw: the body grown by Add Lamp x3 under the baseline camera. The test above is
    meaningful only because this one does not hold every lens."""
    import copy

    from_ops = lamp_addon.design.ops
    doc = copy.deepcopy(_baseline())
    for _ in range(3):
        doc = from_ops.design_with_new_lamp(doc, 0)
    lamp_addon.design.properties.scene_to_design(bl_scene, doc)
    lamp_addon.design.lamp_camera.ensure_lamp_camera(bl_scene)
    assert rims_in_image(lamp_addon, bl_scene) != [True] * 4


def test_frame_lamp_moves_only_the_lamp_camera(lamp_addon, bl_scene):
    import bpy

    lamp_addon.design.properties.scene_to_design(bl_scene, _baseline())
    mine = bpy.data.objects.new("Mine", bpy.data.cameras.new("Mine"))
    bl_scene.collection.objects.link(mine)
    mine.location = (3.0, -9.0, 2.0)
    bl_scene.camera = mine
    before = tuple(mine.location), tuple(mine.rotation_euler), mine.data.lens
    bl_scene.lamp_design.body.size = (400.0, 150.0)
    bl_scene.lamp_design.body.center = (90.0, 0.0)
    assert bpy.ops.lamp.frame_design() == {"FINISHED"}
    assert (tuple(mine.location), tuple(mine.rotation_euler), mine.data.lens) == before
    assert lamp_addon.design.camera.is_lamp_camera(bl_scene.camera)  # framing shows the lamp
    seen = lamp_addon.design.camera.scene_for_render(bl_scene)
    assert seen["camera"]["target"] == pytest.approx([90.0, 40.0, 0.0], abs=1e-3)  # the body box's centre
    body = lamp_addon.convert.camera.body_box(seen)
    size = (seen["image"]["width"], seen["image"]["height"])
    points = np.array(lamp_addon.convert.camera.project(seen["camera"], size,
                                                        lamp_addon.convert.camera.box_corners(*body)))
    assert (points[:, 0] > 0).all() and (points[:, 0] < size[0]).all()
    # The margin leaves about 1/11 of the half image free on the widest side.
    assert min(points[:, 0].min(), size[0] - points[:, 0].max()) == pytest.approx(size[0] / 2 / 11, rel=1e-3)


def test_applying_a_preset_to_a_built_lamp_rebuilds_it(lamp_addon, bl_scene):
    import bpy
    from helpers import FOUR_LAMPS

    lamp_addon.design.properties.scene_to_design(bl_scene, _baseline())
    assert bpy.ops.lamp.build() == {"FINISHED"}
    report = lamp_addon.presets.apply.apply_preset(bl_scene, core_tracer.load_scene(str(FOUR_LAMPS)))
    assert "Rebuilt the lamp objects" in report.details
    lenses = [ob for ob in bl_scene.objects if str(ob.get("lamp_part", "")).endswith(".lens")]
    assert len(lenses) == 4  # the objects are the preset's


@pytest.mark.slow
def test_the_design_fov_reaches_both_halves_of_compare(lamp_addon, bl_scene):
    lamp_addon.design.properties.scene_to_design(bl_scene, _baseline((24, 20)))
    narrow = lamp_addon.compare.comparison.compare_design(bl_scene, samples=1)
    bl_scene.lamp_design.camera.fov_deg = 40.0  # the edit: 16 -> 40
    wide = lamp_addon.compare.comparison.compare_design(bl_scene, samples=1)
    assert narrow["scene"]["camera"]["fov_deg"] == pytest.approx(16.0, abs=1e-4)
    assert wide["scene"]["camera"]["fov_deg"] == pytest.approx(40.0, abs=1e-4)
    assert lamp_addon.design.camera.scene_camera_to_dict(bl_scene)["fov_deg"] == pytest.approx(40.0, abs=1e-4)
    # Cycles sees it too: the lens covers a smaller share of the wider view, in both halves.
    for half in ("tracer", "cycles"):
        assert lens_share(wide[half]) < 0.5 * lens_share(narrow[half]), half
    assert (bl_scene.render.resolution_x, bl_scene.render.resolution_y) == (24, 20)


def test_the_camera_area_says_which_camera_renders(lamp_addon, bl_scene):
    import bpy
    from test_addon_panels import draw

    lamp_addon.design.properties.scene_to_design(bl_scene, _baseline())
    panel = bpy.types.LAMP_PT_camera_view
    assert panel.bl_parent_id == "LAMP_PT_camera"
    layout = draw(panel, bl_scene)
    assert layout.operators() == ["lamp.frame_design"]
    assert any("No scene camera" in entry[1] for entry in layout.log if entry[0] == "label")
    bpy.ops.lamp.frame_design()
    layout = draw(panel, bl_scene)
    assert any('"Lamp Camera"' in entry[1] and "its view" in entry[1] for entry in layout.log if entry[0] == "label")
    mine = bpy.data.objects.new("Mine", bpy.data.cameras.new("Mine"))
    bl_scene.collection.objects.link(mine)
    bl_scene.camera = mine
    layout = draw(panel, bl_scene)
    assert layout.operators() == ["lamp.frame_design", "lamp.camera_to_design"]
    assert any('"Mine"' in entry[1] and "not used" in entry[1] for entry in layout.log if entry[0] == "label")
    assert "lamp.frame_design" in [idname for idname, *_ in lamp_addon.actions.ACTION_OPERATORS]

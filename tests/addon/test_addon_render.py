"""The scene camera, the Lamp Tracer render engine and the Render with Lamp Tracer operator.

The camera conversion is checked three ways: the pure conversion formulas, a round trip
scene camera -> Blender camera -> scene camera, and Blender's own projection
(``bpy_extras.object_utils.world_to_camera_view``) against the tracer's eye rays. The engine
and the operator must give ``core_tracer.render``'s image pixel for pixel.
"""

from __future__ import annotations

import json
import math
import os
import re
import subprocess
import sys

import numpy as np
import pytest
from helpers import BASELINE, ROOT, render_engine_exr, whole_report

import core_tracer
import core_tracer.raytrace.camera  # the projection tests use it; the package loads its modules lazily
from core_tracer.images import imageio

pytestmark = pytest.mark.blender

PRESET = str(BASELINE)

CAMERAS = {
    "perspective-auto": {"type": "perspective", "position": [12.5, -800.25, 30.0], "target": [5.0, 0.0, -10.0],
                         "up": [0, 0, 1], "fov_deg": 16.0, "sensor_fit": "auto", "shift": [0.1, -0.05]},
    "perspective-horizontal": {"type": "perspective", "position": [300.0, -700.0, 200.0],
                               "target": [0.0, 10.0, 0.0], "up": [0.1, 0.0, 1.0], "fov_deg": 23.7,
                               "sensor_fit": "horizontal", "shift": [0.0, 0.2]},
    "perspective-vertical": {"type": "perspective", "position": [-40.0, -650.0, -90.0], "target": [0.0, 0.0, 0.0],
                             "up": [0, 0, 1], "fov_deg": 31.25, "sensor_fit": "vertical", "shift": [-0.15, 0.0]},
    "orthographic-auto": {"type": "orthographic", "position": [0.0, -800.0, 0.0], "target": [0.0, 0.0, 0.0],
                          "up": [0, 0, 1], "width": 263.5, "sensor_fit": "auto", "shift": [0.2, 0.3]},
    "orthographic-horizontal": {"type": "orthographic", "position": [100.0, -500.0, 50.0],
                                "target": [10.0, 20.0, 0.0], "up": [0, 0, 1], "width": 180.0,
                                "sensor_fit": "horizontal", "shift": [0.0, 0.0]},
    "orthographic-vertical": {"type": "orthographic", "position": [0.0, -900.0, 0.0], "target": [0.0, 0.0, 0.0],
                              "up": [0.2, 0.0, 1.0], "width": 150.0, "sensor_fit": "vertical", "shift": [0.1, 0.1]},
}
SIZES = [(48, 32), (32, 48)]  # landscape and portrait: AUTO fits a different side in each


def _preset_scene(camera: dict | None = None, size=(48, 32)) -> dict:
    with open(PRESET, encoding="utf-8") as f:
        doc = json.load(f)
    if camera is not None:
        doc["camera"] = {**doc.get("camera", {}), **camera}
    doc["image"] = {"width": size[0], "height": size[1]}
    return core_tracer.parse_scene(doc)


def _load_design(lamp_addon, bl_scene, scene: dict) -> None:
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    lamp_addon.design.lamp_camera.ensure_lamp_camera(bl_scene, frame=False)


def _axes(cam, camera_module):
    return np.array(camera_module.convert.camera.look_at_axes(cam["position"], cam["target"], cam["up"]))


# ---------------------------------------------------------------------------------------------
# Camera: scene camera -> Blender camera -> scene camera


@pytest.mark.parametrize("size", SIZES, ids=lambda s: f"{s[0]}x{s[1]}")
@pytest.mark.parametrize("name", sorted(CAMERAS))
def test_camera_round_trip(lamp_addon, bl_scene, name, size):
    scene = _preset_scene(CAMERAS[name], size)
    _load_design(lamp_addon, bl_scene, scene)
    # What the renderers see: the camera as the depsgraph evaluates it (location + rotation, float32)
    back = lamp_addon.design.camera.scene_camera_to_dict(bl_scene, lamp_addon.design.camera.evaluated_camera(bl_scene))
    want = scene["camera"]
    assert back["type"] == want["type"]
    assert back["sensor_fit"] == want["sensor_fit"]
    assert back["position"] == pytest.approx(want["position"], abs=1e-4)
    # Orientation to 1e-4 degrees; the target keeps its distance to 1e-4 mm. The target point itself
    # is only as exact as a float32 rotation at ~1 m allows (1e-7 rad is 1e-4 mm at 800 mm).
    for got, wanted in zip(_axes(back, lamp_addon), _axes(want, lamp_addon), strict=True):
        assert math.degrees(math.acos(min(1.0, float(np.dot(got, wanted))))) < 1e-4
    assert math.dist(back["position"], back["target"]) == pytest.approx(
        math.dist(want["position"], want["target"]), abs=1e-4)
    assert back["target"] == pytest.approx(want["target"], abs=1e-3)
    assert back["shift"] == pytest.approx(want["shift"], abs=1e-6)
    if want["type"] == "perspective":
        assert back["fov_deg"] == pytest.approx(want["fov_deg"], abs=1e-4)
    else:
        assert back["width"] == pytest.approx(want["width"], abs=1e-4)
    rendered = lamp_addon.design.camera.scene_for_render(bl_scene)
    assert rendered["image"] == {"width": size[0], "height": size[1], "samples": 1, "edge_samples": 0}
    # The scene camera shows the design's own view (to single precision): the render takes the design's
    # numbers, free of float32 (issue 24), which are what the camera object gives back, within it.
    assert rendered["camera"] == lamp_addon.design.properties.design_to_scene(bl_scene)["camera"]
    assert lamp_addon.design.camera.same_view(rendered["camera"], back)


def _tracer_projection(cam: dict, width: int, height: int, point) -> tuple[float, float]:
    """Where the tracer's camera (core_tracer.raytrace.camera) puts a world point: (x, y) in [0, 1] from the
    image's bottom-left corner, Blender's convention."""
    c = core_tracer.raytrace.camera.make_camera(cam, width, height)
    rel = np.asarray(point, float) - c.position
    u, v, depth = rel @ c.right, rel @ c.up, rel @ c.forward
    if not c.orthographic:
        u, v = u / depth, v / depth
    return ((u - c.shift[0]) / c.half_width + 1) / 2, ((v - c.shift[1]) / c.half_height + 1) / 2


@pytest.mark.parametrize("size", SIZES, ids=lambda s: f"{s[0]}x{s[1]}")
@pytest.mark.parametrize("name", sorted(CAMERAS))
def test_tracer_camera_projects_like_blender(lamp_addon, bl_scene, name, size):
    """Blender's own projection of the Blender camera and the tracer's projection of the scene
    camera read from it put the lamp's corners at the same place in the image."""
    import bpy  # noqa: F401 (bpy_extras needs it first)
    from bpy_extras.object_utils import world_to_camera_view
    from mathutils import Vector

    scene = _preset_scene(CAMERAS[name], size)
    _load_design(lamp_addon, bl_scene, scene)
    read = lamp_addon.design.camera.scene_camera_to_dict(bl_scene)
    for point in ([-110, 0, -60], [110, 0, 60], [45, 30, -20], [0, 80, 0]):
        blender = world_to_camera_view(bl_scene, bl_scene.camera, Vector(point) * 0.001)
        tracer = _tracer_projection(read, size[0], size[1], point)
        # 1e-5 of the image side: far below a pixel at any size this project renders
        assert tracer == pytest.approx((blender.x, blender.y), abs=1e-5), point


def test_camera_refuses_what_the_tracer_cannot_render(lamp_addon, addon_core, bl_scene):
    with pytest.raises(addon_core.SceneError, match="no camera"):
        lamp_addon.design.camera.scene_camera_to_dict(bl_scene)
    _load_design(lamp_addon, bl_scene, _preset_scene())
    bl_scene.render.pixel_aspect_x = 2.0
    with pytest.raises(addon_core.SceneError, match="pixel aspect 2:1"):
        lamp_addon.design.camera.scene_camera_to_dict(bl_scene)
    bl_scene.render.pixel_aspect_x = 1.0
    bl_scene.camera.data.type = "PANO"
    with pytest.raises(addon_core.SceneError, match='camera.type: "pano"'):
        lamp_addon.design.camera.scene_camera_to_dict(bl_scene)


def _user_camera(lamp_addon, bl_scene, scene: dict):
    """A camera of the user's ("My Camera") at the scene's view, made the scene camera."""
    import bpy

    ob = bpy.data.objects.new("My Camera", bpy.data.cameras.new("My Camera"))
    bl_scene.collection.objects.link(ob)
    lamp_addon.design.camera.apply_camera(ob, scene["camera"], bl_scene)
    lamp_addon.design.camera.set_render_size(bl_scene, scene["image"])
    bl_scene.camera = ob
    return ob


def test_the_design_view_is_the_lamp_camera_and_the_render_size(lamp_addon, bl_scene):
    """Editing the design's Camera & Image fields moves the Lamp Camera and sets the resolution;
    moving the Lamp Camera or changing the resolution writes the design: one view, one size."""
    import bpy

    rc, lc, link = lamp_addon.design.camera, lamp_addon.design.lamp_camera, lamp_addon.design.view_link
    scene = _preset_scene(CAMERAS["perspective-vertical"], (40, 30))
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    ob, made = lc.ensure_lamp_camera(bl_scene, frame=False)
    assert bl_scene.camera == ob and rc.is_lamp_camera(ob) and "Lamp Camera" in made
    assert (bl_scene.render.resolution_x, bl_scene.render.resolution_y) == (40, 30)
    assert rc.scene_camera_to_dict(bl_scene)["fov_deg"] == pytest.approx(31.25, abs=1e-4)
    # The design's FOV reaches the render (16 -> 40 in the issue; here 31.25 -> 40).
    bl_scene.lamp_design.camera.fov_deg = 40.0
    assert link.sync_view(bl_scene) == "blender"
    assert rc.scene_camera_to_dict(bl_scene)["fov_deg"] == pytest.approx(40.0, abs=1e-4)
    assert bpy.ops.lamp.render_tracer() == {"FINISHED"}
    image = bpy.data.images["Lamp Tracer"]
    # What renders is the design's view up to Blender's single-precision camera.
    rendered = lamp_addon.image_view.image_to_array(image)
    np.testing.assert_allclose(rendered, core_tracer.render(lamp_addon.design.properties.design_to_scene(bl_scene)),
                               atol=1e-4, rtol=1e-5)
    # The design's image size is the render size.
    bl_scene.lamp_design.image.width = 48
    link.sync_view(bl_scene)
    assert (bl_scene.render.resolution_x, bl_scene.render.resolution_y) == (48, 30)
    # The user moves the Lamp Camera 50 mm to the right and sets the resolution: the design follows.
    ob.location.x += 0.05
    bl_scene.render.resolution_y = 36
    bpy.context.view_layer.update()  # Blender's depsgraph update: the add-on's handler writes the design
    design = lamp_addon.design.properties.design_to_scene(bl_scene)
    assert design["camera"]["position"][0] == pytest.approx(scene["camera"]["position"][0] + 50.0, abs=1e-3)
    assert design["image"] == {"width": 48, "height": 36, "samples": 1, "edge_samples": 0}
    assert link.sync_view(bl_scene) == ""  # both sides agree now
    # F12 renders the design's samples and edge samples at Blender's size
    bl_scene.lamp_design.image.samples, bl_scene.lamp_design.image.edge_samples = 4, 8
    rendered = lamp_addon.design.camera.scene_for_render(bl_scene)["image"]
    assert rendered == {"width": 48, "height": 36, "samples": 4, "edge_samples": 8}


def test_a_users_camera_is_rendered_as_it_is_and_never_moved(lamp_addon, bl_scene):
    import bpy

    rc, lc, link = lamp_addon.design.camera, lamp_addon.design.lamp_camera, lamp_addon.design.view_link
    scene = _preset_scene(CAMERAS["perspective-vertical"], (40, 30))
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    lc.ensure_lamp_camera(bl_scene, frame=False)
    lamp = bl_scene.camera
    mine = _user_camera(lamp_addon, bl_scene, _preset_scene({"position": [60.0, -700.0, 40.0]}, (40, 30)))
    before = tuple(mine.location), tuple(mine.rotation_euler), mine.data.lens
    assert "not used" in link.view_status(bl_scene)[0] and "My Camera" in link.view_status(bl_scene)[0]
    bl_scene.lamp_design.camera.fov_deg = 20.0  # drives the Lamp Camera, not mine
    link.sync_view(bl_scene)
    assert lc.keep_framed(bl_scene)  # frames the Lamp Camera ...
    assert (tuple(mine.location), tuple(mine.rotation_euler), mine.data.lens) == before  # ... never mine
    assert rc.scene_camera_to_dict(bl_scene, lamp)["fov_deg"] == pytest.approx(20.0, abs=1e-4)
    assert bpy.ops.lamp.camera_to_design() == {"FINISHED"}  # my view into the design: the Lamp Camera takes it
    assert (tuple(mine.location), tuple(mine.rotation_euler), mine.data.lens) == before
    design = lamp_addon.design.properties.design_to_scene(bl_scene)
    assert design["camera"]["position"] == pytest.approx([60.0, -700.0, 40.0], abs=1e-3)
    assert rc.scene_camera_to_dict(bl_scene, lamp)["position"] == pytest.approx([60.0, -700.0, 40.0], abs=1e-3)
    bl_scene.camera = lamp
    assert not bpy.ops.lamp.camera_to_design.poll()  # the Lamp Camera's view already is the design's


def test_an_out_of_date_design_camera_does_not_block_a_render(lamp_addon, addon_core, bl_scene):
    """Through a camera of the user's, the design's own camera fields are not used: an invalid one
    does not stop the render."""
    import bpy

    scene = _preset_scene(size=(24, 16))
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    _user_camera(lamp_addon, bl_scene, scene)
    bl_scene.lamp_design.camera.position = (0.0, 500.0, 0.0)  # the design's own camera: behind the lamp
    with pytest.raises(addon_core.SceneError, match=r"camera\.position: y = 500"):
        lamp_addon.design.properties.design_to_scene(bl_scene)
    # The Blender camera renders, and it replaces the design's camera before the scene is checked.
    seen = lamp_addon.design.camera.scene_for_render(bl_scene)
    assert seen["camera"]["position"] == pytest.approx(scene["camera"]["position"], abs=1e-3)
    assert bpy.ops.lamp.render_tracer() == {"FINISHED"}
    _assert_shown(lamp_addon, bpy.data.images["Lamp Tracer"], core_tracer.render(seen))
    bl_scene.render.engine = "LAMP_TRACER"
    assert bpy.ops.render.render() == {"FINISHED"}  # the engine reports no error
    assert bpy.ops.lamp.camera_to_design() == {"FINISHED"}  # and the design camera can be brought up to date
    assert lamp_addon.design.properties.design_to_scene(bl_scene)["camera"]["position"] == pytest.approx(
        seen["camera"]["position"], abs=1e-3)


# ---------------------------------------------------------------------------------------------
# The render engine



def test_engine_equals_core_render(lamp_addon, bl_scene, tmp_path):
    scene = _preset_scene(size=(48, 32))
    _load_design(lamp_addon, bl_scene, scene)
    bl_scene.render.engine = "LAMP_TRACER"
    rgba = render_engine_exr(bl_scene, tmp_path / "engine.exr")
    seen = lamp_addon.design.camera.scene_for_render(bl_scene)
    # The scene the engine rendered is the preset's, camera included (up to Blender's float32 storage).
    assert seen["camera"]["position"] == pytest.approx(scene["camera"]["position"], abs=1e-4)
    assert seen["camera"]["fov_deg"] == pytest.approx(scene["camera"]["fov_deg"], abs=1e-4)
    expected = core_tracer.render(seen)
    assert rgba.shape == (32, 48, 4)
    np.testing.assert_array_equal(rgba[:, :, :3], expected)  # pixel for pixel, top row first
    np.testing.assert_array_equal(rgba[:, :, 3], 1.0)
    assert expected.max() > 1.0 and expected[0, 0].sum() == 0.0  # a real image: bulb and background


@pytest.mark.slow
def test_engine_traces_its_bands_in_the_worker_processes(lamp_addon, addon_core, bl_scene, tmp_path):
    # F12 hands its bands to the add-on's band pool (worker processes, no interpreter lock between
    # them): the same pixels as the tracer alone; unregistering the engine ends the workers.
    band_pool = addon_core.raytrace.band_pool
    pool = band_pool.shared()
    assert pool is not None and pool.ready(30)
    renders = pool.renders
    scene = _preset_scene(size=(320, 240))  # several bands of rows
    _load_design(lamp_addon, bl_scene, scene)
    bl_scene.render.engine = "LAMP_TRACER"
    bl_scene.render.threads_mode = "FIXED"
    bl_scene.render.threads = 2
    rgba = render_engine_exr(bl_scene, tmp_path / "engine.exr")
    assert pool.renders == renders + 1
    expected = core_tracer.render(lamp_addon.design.camera.scene_for_render(bl_scene))
    np.testing.assert_array_equal(rgba[:, :, :3], expected)
    lamp_addon.render.engine.unregister()
    try:
        assert pool.broken == "closed" and all(p.poll() is not None for p in pool._processes)
    finally:
        lamp_addon.render.engine.register()


def test_engine_renders_percentage_and_writes_still(lamp_addon, bl_scene, tmp_path):
    import bpy

    _load_design(lamp_addon, bl_scene, _preset_scene(size=(64, 40)))
    bl_scene.render.engine = "LAMP_TRACER"
    bl_scene.render.resolution_percentage = 50
    bl_scene.render.filepath = str(tmp_path / "still.png")
    bl_scene.render.image_settings.file_format = "PNG"
    assert bpy.ops.render.render(write_still=True) == {"FINISHED"}
    image, _ = imageio.read_image(tmp_path / "still.png")
    assert image.shape == (20, 32, 3)
    expected = core_tracer.render(lamp_addon.design.camera.scene_for_render(bl_scene))
    assert expected.shape == (20, 32, 3)
    # PNG: 8-bit sRGB under the scene's view transform; compare where the view is the identity
    bl_scene.view_settings.view_transform = "Standard"
    bpy.ops.render.render(write_still=True)
    image, _ = imageio.read_image(tmp_path / "still.png")
    low = expected.max(axis=2) < 1.0  # not clipped
    assert np.abs(image[low] - expected[low]).max() < 0.01


@pytest.mark.parametrize("crop", [False, True], ids=["region", "crop"])
@pytest.mark.parametrize("border", [(0.25, 0.75, 0.1, 0.6), (0.0, 0.33, 0.55, 1.0)])
def test_engine_render_region(lamp_addon, bl_scene, tmp_path, border, crop):
    _load_design(lamp_addon, bl_scene, _preset_scene(size=(64, 48)))
    bl_scene.render.engine = "LAMP_TRACER"
    full = render_engine_exr(bl_scene, tmp_path / "full.exr")
    render = bl_scene.render
    render.use_border, render.use_crop_to_border = True, crop
    render.border_min_x, render.border_max_x, render.border_min_y, render.border_max_y = border
    got = render_engine_exr(bl_scene, tmp_path / "region.exr")
    x0, x1, y0, y1 = int(border[0] * 64), int(border[1] * 64), int(border[2] * 48), int(border[3] * 48)
    want = full[48 - y1:48 - y0, x0:x1]  # rows top-first, the region counted from the bottom
    if not crop:
        assert got.shape == full.shape
        assert got[:, :, 3].sum() == want[:, :, 3].sum()  # nothing outside the region
        got = got[48 - y1:48 - y0, x0:x1]
    np.testing.assert_array_equal(got, want)


def test_engine_film_transparent_alpha_is_the_lamp(lamp_addon, bl_scene, tmp_path):
    scene = _preset_scene(size=(48, 32))
    _load_design(lamp_addon, bl_scene, scene)
    bl_scene.render.engine = "LAMP_TRACER"
    bl_scene.render.film_transparent = True
    rgba = render_engine_exr(bl_scene, tmp_path / "alpha.exr")
    alpha = rgba[:, :, 3]
    assert set(np.unique(alpha)) == {0.0, 1.0}
    assert alpha[16, 24] == 1.0 and alpha[0, 0] == 0.0
    # The body (220 x 120 mm) seen from 800 mm with a 16 degree lens across 48 px: its outline.
    mm_per_px = 2 * 800 * math.tan(math.radians(8)) / 48
    assert alpha.sum() == pytest.approx((220 / mm_per_px) * (120 / mm_per_px), rel=0.1)
    assert np.all(rgba[alpha == 0, :3] == 0.0)


def test_engine_reports_design_errors_without_traceback(lamp_addon, bl_scene, tmp_path):
    import bpy

    _load_design(lamp_addon, bl_scene, _preset_scene(size=(16, 16)))
    bl_scene.camera.location.y = 0.5  # behind the lamp's front
    bl_scene.render.engine = "LAMP_TRACER"
    with pytest.raises(RuntimeError, match=r"Lamp Tracer: Camera & Image › Position: y = 500(\.0)? is not in front"):
        bpy.ops.render.render()
    bl_scene.render.image_settings.file_format = "OPEN_EXR"
    bpy.data.images["Render Result"].save_render(str(tmp_path / "black.exr"), scene=bl_scene)
    image, _ = imageio.read_image(tmp_path / "black.exr")
    assert image.shape == (16, 16, 3) and not image.any()  # a black result, not a stale one


@pytest.mark.slow
def test_engine_panels_are_compatible_and_registration_is_symmetric(lamp_addon):
    import bpy

    panels = (bpy.types.RENDER_PT_format, bpy.types.RENDER_PT_output, bpy.types.DATA_PT_lens,
              bpy.types.DATA_PT_camera, bpy.types.RENDER_PT_color_management)
    assert all("LAMP_TRACER" in p.COMPAT_ENGINES for p in panels)
    assert lamp_addon.render.engine.LampTracerEngine.is_registered
    assert "LAMP_TRACER" not in bpy.types.CYCLES_RENDER_PT_sampling.COMPAT_ENGINES
    lamp_addon.render.engine.unregister()
    try:
        assert not any("LAMP_TRACER" in p.COMPAT_ENGINES for p in panels)
        assert not lamp_addon.render.engine.LampTracerEngine.is_registered
    finally:
        lamp_addon.render.engine.register()
    assert all("LAMP_TRACER" in p.COMPAT_ENGINES for p in panels)
    assert lamp_addon.render.engine.LampTracerEngine.is_registered


# ---------------------------------------------------------------------------------------------
# The engine's contribution passes (docs/model.md §5.2) as Blender render passes

LABELS = {"lens_surface": "Lamp Lens Surface", "bulb": "Lamp Bulb", "reflector_constant": "Lamp Reflector Constant",
          "reflector_scatter": "Lamp Reflector Scatter", "socket": "Lamp Socket", "side_wall": "Lamp Side Wall",
          "body": "Lamp Body", "background": "Lamp Background"}


def _lit_background_scene(size=(40, 24)) -> dict:
    """The baseline with a coloured background, so that every one of the eight passes has pixels."""
    scene = _preset_scene(size=size)
    scene["background"] = [0.05, 0.1, 0.2]
    return core_tracer.normalize(scene)


def _render_multilayer_exr(bl_scene, path) -> dict[str, dict[str, np.ndarray]]:
    """Render, save the Render Result as a multilayer OpenEXR and read it back with OpenImageIO:
    {view layer: {pass: (H, W, channels) top row first}}. Blender writes one EXR part per pass,
    with channels named ``<view layer>.<pass>.<R|G|B|A>``."""
    import bpy

    settings = bl_scene.render.image_settings
    settings.media_type = "MULTI_LAYER_IMAGE"
    assert settings.file_format == "OPEN_EXR_MULTILAYER"
    settings.color_depth = "32"
    bpy.ops.render.render()
    bpy.data.images["Render Result"].save_render(str(path), scene=bl_scene)
    return _read_multilayer_exr(path)


def _read_multilayer_exr(path) -> dict[str, dict[str, np.ndarray]]:
    import OpenImageIO as oiio

    channels: dict[tuple[str, str], dict[str, np.ndarray]] = {}
    inp = oiio.ImageInput.open(str(path))
    assert inp, oiio.geterror()
    try:
        part = 0
        while inp.seek_subimage(part, 0):
            pixels = inp.read_image(oiio.FLOAT)
            for i, name in enumerate(inp.spec().channelnames):
                layer, pass_name, channel = name.rsplit(".", 2)
                channels.setdefault((layer, pass_name), {})[channel] = pixels[:, :, i]
            part += 1
    finally:
        inp.close()
    layers: dict[str, dict[str, np.ndarray]] = {}
    for (layer, pass_name), by_channel in channels.items():
        order = "RGBA" if "A" in by_channel else "RGB"
        assert set(by_channel) == set(order), (layer, pass_name, sorted(by_channel))
        layers.setdefault(layer, {})[pass_name] = np.dstack([by_channel[c] for c in order])
    return layers


def _assert_passes_sum_to_combined(passes: dict[str, np.ndarray]) -> None:
    total = np.sum([passes[label] for label in LABELS.values()], axis=0, dtype=np.float64)
    np.testing.assert_allclose(total, passes["Combined"][:, :, :3], rtol=1e-6, atol=1e-7)


def test_engine_writes_contribution_passes_to_multilayer_exr(lamp_addon, bl_scene, tmp_path):
    _load_design(lamp_addon, bl_scene, _lit_background_scene())
    bl_scene.render.engine = "LAMP_TRACER"
    bl_scene.view_layers["ViewLayer"].lamp_contribution_passes = True
    layers = _render_multilayer_exr(bl_scene, tmp_path / "passes.exr")
    assert set(layers) == {"ViewLayer"}
    got = layers["ViewLayer"]
    assert set(got) == {"Combined", *LABELS.values()}
    expected = core_tracer.render_passes(lamp_addon.design.camera.scene_for_render(bl_scene))
    assert got["Combined"].shape == (24, 40, 4)
    np.testing.assert_array_equal(got["Combined"][:, :, :3], expected.image)
    np.testing.assert_array_equal(got["Combined"][:, :, 3], 1.0)
    for name, label in LABELS.items():
        assert got[label].shape == (24, 40, 3)
        np.testing.assert_array_equal(got[label], expected.passes[name], err_msg=label)  # top row first
        assert got[label].any(), f"{label} is black: the test would not see a misplaced pass"
    _assert_passes_sum_to_combined(got)


def test_engine_without_contribution_passes_writes_combined_only(lamp_addon, bl_scene, tmp_path):
    _load_design(lamp_addon, bl_scene, _preset_scene(size=(40, 24)))
    bl_scene.render.engine = "LAMP_TRACER"
    assert not bl_scene.view_layers["ViewLayer"].lamp_contribution_passes  # off by default
    layers = _render_multilayer_exr(bl_scene, tmp_path / "combined.exr")
    assert {layer: set(passes) for layer, passes in layers.items()} == {"ViewLayer": {"Combined"}}
    np.testing.assert_array_equal(layers["ViewLayer"]["Combined"][:, :, :3],
                                  core_tracer.render(lamp_addon.design.camera.scene_for_render(bl_scene)))


def test_engine_contribution_passes_are_per_view_layer(lamp_addon, bl_scene, tmp_path):
    """Each view layer gets its own result: the second layer is rendered too (it stayed black when
    the engine wrote every layer into the first), and only the layer with the toggle has passes."""
    _load_design(lamp_addon, bl_scene, _lit_background_scene())
    bl_scene.render.engine = "LAMP_TRACER"
    bl_scene.view_layers.new("Plain")
    bl_scene.view_layers["ViewLayer"].lamp_contribution_passes = True
    layers = _render_multilayer_exr(bl_scene, tmp_path / "layers.exr")
    assert set(layers["ViewLayer"]) == {"Combined", *LABELS.values()}
    assert set(layers["Plain"]) == {"Combined"}
    expected = core_tracer.render(lamp_addon.design.camera.scene_for_render(bl_scene))
    np.testing.assert_array_equal(layers["Plain"]["Combined"][:, :, :3], expected)
    np.testing.assert_array_equal(layers["ViewLayer"]["Combined"][:, :, :3], expected)


def test_engine_contribution_passes_follow_transparency_and_region(lamp_addon, bl_scene, tmp_path):
    """With Film › Transparent the passes are premultiplied like Combined (they still sum to it);
    with a cropped render region they cover the region only."""
    _load_design(lamp_addon, bl_scene, _lit_background_scene((48, 32)))
    bl_scene.render.engine = "LAMP_TRACER"
    bl_scene.view_layers["ViewLayer"].lamp_contribution_passes = True
    render = bl_scene.render
    render.film_transparent = True
    render.use_border, render.use_crop_to_border = True, True
    render.border_min_x, render.border_max_x, render.border_min_y, render.border_max_y = 0.0, 0.33, 0.55, 1.0
    got = _render_multilayer_exr(bl_scene, tmp_path / "region.exr")["ViewLayer"]
    x0, x1, y0, y1 = 0, 15, 17, 32  # the border in whole pixels, rows counted from the bottom
    alpha = got["Combined"][:, :, 3]
    assert set(np.unique(alpha)) == {0.0, 1.0}  # the lamp's outline cuts the region
    expected = core_tracer.render_passes(lamp_addon.design.camera.scene_for_render(bl_scene))
    for name, label in LABELS.items():
        want = expected.passes[name][32 - y1:32 - y0, x0:x1] * alpha[:, :, None]
        np.testing.assert_array_equal(got[label], want, err_msg=label)
    assert expected.passes["background"][32 - y1:32 - y0, x0:x1][alpha == 0].any()  # was there to remove
    _assert_passes_sum_to_combined(got)


def test_engine_contribution_passes_are_black_after_a_design_error(lamp_addon, bl_scene, tmp_path):
    import bpy

    _load_design(lamp_addon, bl_scene, _preset_scene(size=(16, 16)))
    bl_scene.render.engine = "LAMP_TRACER"
    bl_scene.view_layers["ViewLayer"].lamp_contribution_passes = True
    bl_scene.render.film_transparent = True
    bl_scene.camera.location.y = 0.5  # behind the lamp's front
    with pytest.raises(RuntimeError, match=r"Lamp Tracer: Camera & Image › Position"):
        _render_multilayer_exr(bl_scene, tmp_path / "unused.exr")
    path = tmp_path / "black.exr"
    bpy.data.images["Render Result"].save_render(str(path), scene=bl_scene)
    got = _read_multilayer_exr(path)["ViewLayer"]
    assert set(got) == {"Combined", *LABELS.values()}  # every pass there, and black, not stale
    assert all(not p[:, :, :3].any() for p in got.values())


def test_contribution_passes_in_the_compositor(lamp_addon, bl_scene, tmp_path):
    """The Render Layers node offers the passes while the toggle is on, and a pass composited to
    the output is what the render result then holds."""
    import bpy

    _load_design(lamp_addon, bl_scene, _preset_scene(size=(40, 24)))
    bl_scene.render.engine = "LAMP_TRACER"
    layer = bl_scene.view_layers["ViewLayer"]
    tree = bpy.data.node_groups.new("Lamp passes", "CompositorNodeTree")
    tree.interface.new_socket("Image", in_out="OUTPUT", socket_type="NodeSocketColor")
    bl_scene.compositing_node_group = tree
    render_layers = tree.nodes.new("CompositorNodeRLayers")

    def offered() -> set[str]:
        return {socket.name for socket in render_layers.outputs if socket.enabled}

    assert offered() == {"Image", "Alpha"}
    layer.lamp_contribution_passes = True  # the update callback asks the engine for its passes again
    assert offered() == {"Image", "Alpha", *LABELS.values()}
    tree.links.new(render_layers.outputs["Lamp Bulb"], tree.nodes.new("NodeGroupOutput").inputs[0])
    rgba = render_engine_exr(bl_scene, tmp_path / "bulb.exr")
    bulb = core_tracer.render_passes(lamp_addon.design.camera.scene_for_render(bl_scene)).passes["bulb"]
    assert bulb.max() > 1.0
    np.testing.assert_array_equal(rgba[:, :, :3], bulb)
    layer.lamp_contribution_passes = False
    assert offered() == {"Image", "Alpha"}


class _RecordingLayout:
    """Just what the passes panel calls: records ``prop`` after checking the property exists."""

    def __init__(self, log: list):
        self.log, self.use_property_split, self.use_property_decorate = log, False, True

    def column(self, **_kw):
        return _RecordingLayout(self.log)

    def prop(self, data, prop, **_kw):
        assert prop in data.bl_rna.properties.keys(), prop
        self.log.append((data, prop))


@pytest.mark.slow
def test_contribution_passes_panel_and_symmetric_registration(lamp_addon, bl_scene):
    from types import SimpleNamespace

    import bpy

    engine = lamp_addon.render.engine
    layer = bl_scene.view_layers["ViewLayer"]
    panel = bpy.types.LAMP_PT_view_layer_passes
    assert panel.bl_context == "view_layer" and panel.bl_parent_id == "VIEWLAYER_PT_layer_passes"
    assert "LAMP_TRACER" in bpy.types.VIEWLAYER_PT_layer_passes.COMPAT_ENGINES  # the parent shows too
    assert panel.poll(SimpleNamespace(engine="LAMP_TRACER"))
    assert not panel.poll(SimpleNamespace(engine="CYCLES"))
    log = []
    panel.draw(SimpleNamespace(layout=_RecordingLayout(log)), SimpleNamespace(view_layer=layer))
    assert log == [(layer, "lamp_contribution_passes")]
    assert bpy.types.ViewLayer.bl_rna.properties["lamp_contribution_passes"].name == "Contribution Passes"
    layer.lamp_contribution_passes = True

    def registered() -> tuple[bool, bool, bool]:
        return ("lamp_contribution_passes" in bpy.types.ViewLayer.bl_rna.properties,
                hasattr(bpy.types, "LAMP_PT_view_layer_passes"),
                "LAMP_TRACER" in bpy.types.VIEWLAYER_PT_layer_passes.COMPAT_ENGINES)

    for _ in range(2):  # the engine module alone, then the whole add-on's chain
        for module in (engine, lamp_addon):
            module.unregister()
            try:
                assert registered() == (False, False, False)
                assert not hasattr(layer, "lamp_contribution_passes")
            finally:
                module.register()
            assert registered() == (True, True, True)
            assert layer.lamp_contribution_passes  # the value is kept in the file across a disable


def test_user_guide_names_the_contribution_passes(lamp_addon, repo_root):
    assert lamp_addon.render.engine.PASS_LABELS == LABELS
    text = " ".join((repo_root / "docs" / "user-guide.md").read_text().split())
    assert "Contribution Passes" in text
    assert all(f"*{label}*" in text for label in LABELS.values())


# ---------------------------------------------------------------------------------------------
# The Render with Lamp Tracer operator and its worker


def test_render_operator_image_equals_core_render(lamp_addon, bl_scene):
    import bpy

    _load_design(lamp_addon, bl_scene, _preset_scene(size=(48, 32)))
    assert bpy.ops.lamp.render_tracer() == {"FINISHED"}
    image = bpy.data.images["Lamp Tracer"]
    assert image.is_float and tuple(image.size) == (48, 32)
    assert image.colorspace_settings.name == lamp_addon.image_view.scene_linear_colorspace()
    expected = core_tracer.render(lamp_addon.design.camera.scene_for_render(bl_scene))
    _assert_shown(lamp_addon, image, expected)
    # Again at another size: the same data-block, resized, still exact.
    bl_scene.render.resolution_x = 24
    assert bpy.ops.lamp.render_tracer() == {"FINISHED"}
    again = bpy.data.images["Lamp Tracer"]
    assert again == image and tuple(again.size) == (24, 32)
    _assert_shown(lamp_addon, again, core_tracer.render(lamp_addon.design.camera.scene_for_render(bl_scene)))


def _assert_shown(lamp_addon, image, expected) -> None:
    """The image holds the tracer's render as F12 does, shown through the scene's view transform at the
    scene's exposure like a render (the exposure belongs to the view)."""
    assert image.use_view_as_render and image["lamp_exposure"] == 0.0
    np.testing.assert_array_equal(lamp_addon.image_view.image_to_array(image), expected)


def test_render_operator_refuses_without_camera(lamp_addon, bl_scene):
    import bpy

    lamp_addon.design.properties.scene_to_design(bl_scene, _preset_scene())
    assert not bpy.ops.lamp.render_tracer.poll()
    with pytest.raises(RuntimeError, match="no camera; Frame Lamp .* or Build Lamp makes one"):
        bpy.ops.lamp.render_tracer()
    # ... and both do: Build in a file without a camera makes the Lamp Camera.
    assert bpy.ops.lamp.build() == {"FINISHED"}
    assert lamp_addon.design.camera.is_lamp_camera(bl_scene.camera) and bpy.ops.lamp.render_tracer.poll()


def test_tracer_job_runs_on_a_thread_and_equals_core_render(lamp_addon):
    scene = _preset_scene(size=(40, 24))
    job = lamp_addon.render.ops.TracerJob(scene).start()
    assert job.wait(60.0)
    assert job.error is None and not job.cancelled
    assert job.progress == 1.0 and job.rows_done == 24
    np.testing.assert_array_equal(job.rows, core_tracer.render(scene))


def test_tracer_job_cancels_through_should_stop(lamp_addon):
    scene = _preset_scene(size=(256, 256))  # several bands of rows
    job = lamp_addon.render.ops.TracerJob(scene)
    job.stop()  # Esc before the first band is polled
    job.start()
    assert job.wait(60.0)
    assert job.cancelled and job.error is None
    assert job.rows_done < 256


def test_render_passes_stops_between_bands(monkeypatch):
    monkeypatch.setattr(core_tracer.raytrace.engine.sampling, "TILE_RAYS", 256 * 64)  # 64 rows a band: 4 bands
    scene = _preset_scene(size=(256, 256))
    bands = []

    def stop_after_first() -> bool:
        return len(bands) >= 1

    with pytest.raises(core_tracer.RenderCancelled):
        core_tracer.render_passes(scene, on_rows=lambda a, b, rows: bands.append((a, b)),
                                  should_stop=stop_after_first, threads=1)
    assert len(bands) == 1


# ---------------------------------------------------------------------------------------------
# The headless main job


def _run_tool(args, tmp_path):
    env = {k: v for k, v in os.environ.items() if k != "BLENDER_USER_RESOURCES"}
    tool = str(ROOT / "tools" / "compare_preset.py")
    return subprocess.run([sys.executable, tool, *args], capture_output=True, text=True, env=env,
                          cwd=tmp_path, timeout=300)


@pytest.mark.slow
def test_headless_job_writes_the_side_by_side_image(tmp_path):
    out = tmp_path / "out" / "compare.png"
    done = _run_tool([PRESET, "-o", str(out), "--samples", "2", "--size", "40x32"], tmp_path)
    assert done.returncode == 0, done.stderr
    image, scene = imageio.read_image(out)
    assert image.shape[1] == 3 * 40 + 2 * 2 and image.shape[0] > 32  # tracer, Cycles, |difference|
    assert scene["image"] == {"width": 40, "height": 32, "samples": 1, "edge_samples": 0}
    assert "Lamp Tracer:  40x32 in" in done.stdout and "2 samples per pixel" in done.stdout
    assert "mean difference" in done.stdout
    assert "lens mean difference" in done.stdout and "lens RMS difference" in done.stdout


@pytest.mark.slow
@pytest.mark.parametrize("args, message", [
    (["missing.json"], "compare_preset: missing.json: cannot read the file"),
    ([PRESET, "-o", "x.jpg"], "compare_preset: x.jpg: .jpg is not an image format this writes"),
])
def test_headless_job_bad_input_is_one_line_and_exit_2(tmp_path, args, message):
    done = _run_tool(args, tmp_path)
    assert done.returncode == 2
    assert done.stderr.strip().splitlines() == [done.stderr.strip()]
    assert done.stderr.startswith(message)
    assert "Traceback" not in done.stderr + done.stdout


@pytest.mark.slow
def test_engine_renders_the_designs_samples(lamp_addon, bl_scene, tmp_path, capfd):
    import bpy

    scene = _preset_scene(size=(32, 24))
    _load_design(lamp_addon, bl_scene, scene)
    bl_scene.lamp_design.image.samples = 4
    bl_scene.render.engine = "LAMP_TRACER"
    rgba = render_engine_exr(bl_scene, tmp_path / "engine.exr")
    seen = lamp_addon.design.camera.scene_for_render(bl_scene)
    assert seen["image"]["samples"] == 4
    np.testing.assert_array_equal(rgba[:, :, :3], core_tracer.render(seen))
    assert not np.array_equal(rgba[:, :, :3], core_tracer.render({**seen, "image": {**seen["image"], "samples": 1}}))
    # Too many eye rays for one render: refused with the field and the range, as in the CLI.
    bl_scene.render.resolution_x = bl_scene.render.resolution_y = 4096
    bl_scene.lamp_design.image.samples = 256
    capfd.readouterr()
    with pytest.raises(RuntimeError) as raised:
        bpy.ops.render.render()
    assert re.search(r"Camera & Image › Samples: .* 1 to 64 samples", whole_report(str(raised.value),
                                                                             capfd.readouterr().out))


def test_engine_film_transparent_alpha_is_the_covered_fraction_with_samples(lamp_addon, bl_scene, tmp_path):
    # With samples the silhouette is smooth: alpha is the fraction of the pixel's rays that hit the
    # body, and the rays that miss leave the (premultiplied) colour, background and all.
    scene = _preset_scene(size=(48, 32))
    scene["background"] = [0.2, 0.3, 0.4]
    _load_design(lamp_addon, bl_scene, scene)
    bl_scene.lamp_design.image.samples = 16
    bl_scene.render.engine = "LAMP_TRACER"
    bl_scene.render.film_transparent = True
    rgba = render_engine_exr(bl_scene, tmp_path / "alpha.exr")
    seen = lamp_addon.design.camera.scene_for_render(bl_scene)
    alpha = rgba[:, :, 3]
    edge = (alpha > 0) & (alpha < 1)
    assert edge.sum() > 40  # the outline's pixels
    assert alpha[16, 24] == 1.0 and alpha[0, 0] == 0.0
    np.testing.assert_allclose(rgba[alpha == 0, :3], 0.0, atol=1e-6)
    full = core_tracer.render(seen)
    np.testing.assert_allclose(rgba[:, :, :3], full - (1 - alpha)[:, :, None] * np.float32([0.2, 0.3, 0.4]),
                               atol=1e-6)
    # Where all a pixel's rays hit the body, nothing is taken away.
    np.testing.assert_array_equal(rgba[alpha == 1, :3], full[alpha == 1])

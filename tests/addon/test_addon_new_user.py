"""A new user's first minute, end to end, from Blender's startup file (Cube, Camera, Light).

Add Lamp twice, Build; then: the scene camera frames every lens; F12 with the Lamp Tracer (written
as Blender writes a still: the scene's view transform and exposure) shows the lit lens unclipped in
its cut pattern; the viewport's draw path, orbited to a three-quarter view, shows the lit lamp; an
edit of the design, a renamed lens and a moved root all survive an Auto Build; Compare shows the
lamp in both halves. Each step's time is printed (``-s`` shows them); none is asserted.

"Unclipped in its cut pattern" is the measure of ``tests/images/test_display.py``: over the lit-lens
pixels (a lens is hit and the bulb's light comes through), fewer than 1 % have a channel at display
code 255, and the 5th to 95th percentile of the brightest channel's code spans at least 30 codes.
"""

from __future__ import annotations

import time

import numpy as np
import pytest
from test_addon_framing import rims_in_image
from test_addon_viewport import _display, _draw_viewport, _three_quarter_view

import core_tracer

pytestmark = [pytest.mark.blender, pytest.mark.slow]

SIZE = (160, 120)  # the design's image: the render resolution
VIEWPORT = (160, 120)
MAX_CLIPPED = 0.01
MIN_SPREAD = 30


def lit_lens_mask(scene: dict) -> np.ndarray:
    """Pixels whose eye ray meets a lens and that receive the bulb's light (the tracer's passes)."""
    width, height = scene["image"]["width"], scene["image"]["height"]
    passes = core_tracer.render_passes(scene, width, height).passes
    lens = passes["lens_surface"].max(axis=2) > 0
    return lens & ((passes["bulb"] + passes["reflector_scatter"]).max(axis=2) > 0)


def lens_reading(codes: np.ndarray, mask: np.ndarray) -> tuple[float, float]:
    """(clipped fraction, 5-95 % spread in codes) of the 8-bit display ``codes`` over ``mask``."""
    lit = codes[mask].astype(int)
    p5, p95 = np.percentile(lit.max(axis=1), [5, 95])
    return float((lit == 255).any(axis=1).mean()), float(p95 - p5)


def f12_codes(bl_scene, path) -> np.ndarray:
    """F12 with the scene's engine, written as a still (8-bit PNG through the scene's colour management)."""
    import bpy
    from OpenImageIO import UINT8, ImageBuf

    settings = bl_scene.render.image_settings
    settings.file_format, settings.color_mode, settings.color_depth = "PNG", "RGB", "8"
    bl_scene.render.filepath = str(path)
    assert bpy.ops.render.render(write_still=True) == {"FINISHED"}
    return np.asarray(ImageBuf(str(path)).get_pixels(format=UINT8))[:, :, :3]


class Stopwatch:
    def __init__(self):
        self.times: dict[str, float] = {}
        self._last = time.perf_counter()

    def lap(self, name: str) -> None:
        now = time.perf_counter()
        self.times[name] = now - self._last
        self._last = now


def test_a_new_user_in_the_startup_file(lamp_addon, gpu_context, tmp_path):
    import bpy

    watch = Stopwatch()
    bpy.ops.wm.read_homefile(use_factory_startup=True)
    bl_scene = bpy.context.scene
    assert any(a.module.endswith(".lamp_styling") for a in bpy.context.preferences.addons)  # still enabled
    design = bl_scene.lamp_design
    assert len(design.lamps) == 0 and bl_scene.camera.name == "Camera"
    startup_camera = bl_scene.objects["Camera"]
    camera_before = startup_camera.matrix_world.copy(), startup_camera.data.lens
    watch.lap("open the startup file")

    # The first minute: two lamps, a build.
    assert bpy.ops.lamp.lamp_add() == {"FINISHED"}
    design.image.width, design.image.height = SIZE  # small, to keep the test quick (the user keeps 512 x 512)
    assert bpy.ops.lamp.lamp_add() == {"FINISHED"}
    assert bpy.ops.lamp.build() == {"FINISHED"}
    watch.lap("Add Lamp x2 + Build")
    assert lamp_addon.design.camera.is_lamp_camera(bl_scene.camera)
    assert (startup_camera.matrix_world, startup_camera.data.lens) == camera_before
    assert bl_scene.render.engine == "LAMP_TRACER"
    assert (bl_scene.render.resolution_x, bl_scene.render.resolution_y) == SIZE
    assert rims_in_image(lamp_addon, bl_scene) == [True, True]

    # F12: the lit lens through AgX at the scene's (the design's) exposure.
    seen = lamp_addon.design.camera.scene_for_render(bl_scene)
    lit = lit_lens_mask(seen)
    assert lit.sum() > 0.02 * lit.size  # the lenses are plainly in the picture
    codes = f12_codes(bl_scene, tmp_path / "f12.png")
    watch.lap("F12")
    clipped, spread = lens_reading(codes, lit)
    exposure = bl_scene.view_settings.exposure
    print(f"\nF12 at {exposure:+.1f} EV ({bl_scene.view_settings.view_transform}): lit lens clipped "
          f"{clipped:.2%}, spread {spread:.0f} codes over {int(lit.sum())} px")
    assert clipped < MAX_CLIPPED and spread >= MIN_SPREAD
    bl_scene.view_settings.exposure = 0.0  # what a new user got before: a flat or clipped disk
    clipped_0, spread_0 = lens_reading(f12_codes(bl_scene, tmp_path / "f12-ev0.png"), lit)
    print(f"F12 at +0.0 EV: lit lens clipped {clipped_0:.2%}, spread {spread_0:.0f} codes")
    assert clipped_0 >= MAX_CLIPPED or spread_0 < MIN_SPREAD
    bl_scene.view_settings.exposure = exposure
    watch.lap("F12 at EV 0 (the measure's control)")

    # Edits that survive an Auto Build: the design's IOR, the user's name and placement.
    auto = lamp_addon.design.autobuild
    root = lamp_addon.design.root.find_root(bl_scene)
    lens = next(o for o in bl_scene.objects if o.get("lamp_part") == "lamps[0].lens")
    lens.name = "My Stop Lens"
    root.location = (0.4, -1.5, 0.6)
    design.lamps[0].lens.ior = 1.58
    edited = auto._edits[bl_scene.name]
    assert auto.tick(now=edited + auto.SETTLE_SECONDS) is None  # the timer, after the edits settle
    watch.lap("Auto Build after an edit")
    assert lens.name == "My Stop Lens" and tuple(root.location) == pytest.approx((0.4, -1.5, 0.6))
    glass = lens.data.materials[0].node_tree.nodes["Lens BSDF"]
    assert glass.inputs["IOR"].default_value == pytest.approx(1.58)
    assert lamp_addon.design.builder.is_up_to_date(bl_scene)
    assert rims_in_image(lamp_addon, bl_scene) == [True, True]  # the Lamp Camera moved with the root

    # Compare: the lamp in both halves, the Cube and the Light left out of Cycles.
    assert bpy.ops.lamp.compare_cycles(samples=4) == {"FINISHED"}
    watch.lap("Compare (Cycles 4 spp)")
    compare = bpy.data.images[lamp_addon.compare.comparison.COMPARE_IMAGE]
    shown = lamp_addon.image_view.image_to_array(compare)  # labels strip on top, a gap between the halves
    seen = lamp_addon.design.camera.scene_for_render(bl_scene)
    lit = lit_lens_mask(seen)
    height, width = lit.shape
    below = shown[shown.shape[0] - height:]
    gap = max(2, width // 128)
    for name, half in (("tracer", below[:, :width]), ("cycles", below[:, width + gap:2 * width + gap])):
        lens_mean, body_mean = half[lit].max(axis=1).mean(), half[~lit].max(axis=1).mean()
        print(f"Compare {name} half: lit lens mean {lens_mean:.2f}, elsewhere {body_mean:.2f}")
        assert lens_mean > 3.0 * body_mean
    assert not bl_scene.objects["Cube"].hide_render  # put back after the comparison
    # The viewport orbited to a three-quarter view: the draw path into an offscreen shows the lamp.
    window, view = _three_quarter_view(*VIEWPORT)  # around the origin: orbit where the root now is
    drawn = _draw_viewport(lamp_addon, bl_scene, *VIEWPORT, window, view @ root.matrix_world.inverted())
    assert lamp_addon.design.camera.is_lamp_camera(bl_scene.camera) and bl_scene.render.resolution_x == SIZE[0]
    watch.lap("viewport: coarse + full stages, drawn")
    pixels = drawn["pixels"][::-1, :, :3]  # top row first
    background = np.asarray(drawn["scene"]["background"], np.float32)
    lamp = np.abs(pixels - background).max(axis=2) > 1e-3
    lit_view = lit_lens_mask(drawn["scene"])
    print(f"viewport: lamp on {lamp.mean():.1%} of the region, lit lens {lit_view.mean():.1%}; "
          f"lit lens max {pixels[lit_view].max():.1f}")
    assert lamp.mean() > 0.05 and lit_view.mean() > 0.01
    assert pixels[lit_view].max(axis=1).min() > 0.0 and np.median(pixels[lit_view].max(axis=1)) > 1.0
    # As Blender shows the drawn region: the scene's AgX at the design's exposure keeps the cut pattern.
    viewport_codes = _display(bl_scene, drawn["pixels"], tmp_path / "viewport.png")
    clipped_v, spread_v = lens_reading(viewport_codes, lit_view)
    print(f"viewport at {bl_scene.view_settings.exposure:+.1f} EV: lit lens clipped {clipped_v:.2%}, "
          f"spread {spread_v:.0f} codes")
    assert clipped_v < MAX_CLIPPED and spread_v >= MIN_SPREAD

    print("times: " + ", ".join(f"{name} {seconds:.2f} s" for name, seconds in watch.times.items()))
    assert sum(watch.times.values()) < 60.0  # "within a minute": the user's clicks cost less than that

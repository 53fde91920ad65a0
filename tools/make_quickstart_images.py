"""Make the pictures of the README's quick start (docs/quickstart-*.png), as a new user gets them.

    xvfb-run -a .venv/bin/python tools/make_quickstart_images.py [--out docs] [--samples 16]

Every step starts where the one before ended, in Blender's factory startup file (Cube, Camera, Light)
with the add-on enabled from this source tree, through the add-on's own operators; F12 pictures are
written as Blender writes a still (the scene's view transform and exposure):

1. the first lamp: *Add Lamp* in the startup file, then F12 (the exposure the first lamp set);
2. a preset: *Apply Preset* "Four-lamp rear combination", F12 at the same exposure (the policy: the
   exposure belongs to the view, so brighter bulbs look brighter);
3. *Compare with Cycles*: the two renderers and their difference, as the operator writes it;
4. a study: *Run Study* of the lamp's function (tail, stop) by its bulb (on, off), as saved from Blender;
5. the free-form example: *Apply Preset* "Free-form: sculpted wrap-around tail lamp", F12.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SIDE = 384  # px: the longer side of each F12 picture


def f12(bpy, bl_scene, path: str) -> None:
    """F12 with the scene's engine, written as a still (8-bit PNG through the colour management)."""
    render = bl_scene.render
    scale = SIDE / max(render.resolution_x, render.resolution_y)
    render.resolution_percentage = max(1, min(100, round(100 * scale)))
    settings = render.image_settings
    settings.file_format, settings.color_mode, settings.color_depth = "PNG", "RGB", "8"
    render.filepath = path
    assert bpy.ops.render.render(write_still=True) == {"FINISHED"}
    render.resolution_percentage = 100
    print(f"F12 at {bl_scene.view_settings.exposure:+.1f} EV -> {path}")


def apply_preset(bpy, file_name: str) -> None:
    wm = bpy.context.window_manager
    wm.lamp_presets_index = next(i for i, item in enumerate(wm.lamp_presets) if item.file.endswith(file_name))
    assert bpy.ops.lamp.preset_apply() == {"FINISHED"}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=os.path.join(ROOT, "docs"), help="folder to write into (default docs/)")
    parser.add_argument("--samples", type=int, default=16, help="Cycles samples of the Compare picture")
    args = parser.parse_args(argv)
    os.makedirs(args.out, exist_ok=True)
    os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="lamp-quickstart-"))
    sys.path.insert(0, ROOT)
    import bpy

    from tools import dev_extension

    def out(name: str) -> str:
        return os.path.join(args.out, f"quickstart-{name}.png")

    with dev_extension.enabled_from_source(bpy, "lamp_quickstart") as package:
        addon = sys.modules[f"{package}.lamp_addon"]
        bpy.ops.wm.read_homefile(use_factory_startup=True)
        bl_scene = bpy.context.scene
        bpy.ops.lamp.preset_refresh()

        assert bpy.ops.lamp.lamp_add() == {"FINISHED"}  # the first lamp: framed, exposed once
        assert bpy.ops.lamp.build() == {"FINISHED"}  # what Auto Build does a moment later in the interface
        f12(bpy, bl_scene, out("1-first-lamp"))

        apply_preset(bpy, "four-lamp-rear-combination.json")
        assert bpy.ops.lamp.build() == {"FINISHED"}
        f12(bpy, bl_scene, out("2-preset"))

        bl_scene.render.resolution_percentage = 50  # the README shows it at half size anyway
        assert bpy.ops.lamp.compare_cycles(samples=args.samples, filepath=out("3-compare")) == {"FINISHED"}
        bl_scene.render.resolution_percentage = 100

        settings = bl_scene.lamp_study
        settings.width, settings.height, settings.workers = 192, 128, 2
        settings.axis_1.lamp = settings.axis_2.lamp = "0"
        settings.axis_1.parameter, settings.axis_1.mode, settings.axis_1.values = "function", "LIST", "tail, stop"
        settings.use_axis_2 = True
        settings.axis_2.parameter, settings.axis_2.mode, settings.axis_2.values = "bulb.on", "LIST", "on, off"
        assert bpy.ops.lamp.study_run() == {"FINISHED"}
        assert bpy.ops.lamp.study_save_sheet(filepath=out("4-study")) == {"FINISHED"}

        apply_preset(bpy, "freeform-sculpted-wrap-lamp.json")
        f12(bpy, bl_scene, out("5-freeform"))
        print("parts:", ", ".join(o.name for o in addon.freeform.properties.role_objects(bl_scene)))
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""The Light Panel in Blender (issue 23 item 5: "re-weighting lighting states in Blender is instant,
< 50 ms at 512²"): the time from a switch's change to the "Lamp Light Panel" image updated (the sum of
the passes, XYZ to the scene-linear display, glare, the pixels into Blender's image).

    xvfb-run -a .venv/bin/python benchmarks/bench_light_panel.py [--size 512] [--changes 40]

It also times Render Light States against one F12 of the same design (Lamp Tracer, the design's samples;
an F12 first, untimed, so that both find the band pool's workers started).
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
USER = tempfile.mkdtemp(prefix="lamp-bench-user-")
os.environ["BLENDER_USER_RESOURCES"] = USER  # before bpy loads


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=512)
    parser.add_argument("--changes", type=int, default=40)
    parser.add_argument("--preset", default="four-lamp-night-lit-photometric.json")
    args = parser.parse_args()
    import bpy

    from tools import dev_extension

    try:
        with dev_extension.enabled_from_source(bpy, "lamp_dev", reuse_enabled=False, strict=True) as name:
            addon = sys.modules[f"{name}.lamp_addon"]
            core = sys.modules[f"{name}.core_tracer"]
            bpy.ops.wm.read_homefile(use_empty=True)
            scene = core.scene.load_scene(ROOT / "presets" / args.preset)
            scene["image"]["width"] = scene["image"]["height"] = args.size
            bl_scene = bpy.context.scene
            addon.design.properties.scene_to_design(bl_scene, scene)
            bl_scene.lamp_design.auto_build = False
            addon.design.lamp_camera.ensure_lamp_camera(bl_scene)
            bl_scene.render.engine = "LAMP_TRACER"
            bpy.ops.render.render()  # the band pool's workers started
            start = time.perf_counter()
            bpy.ops.render.render()
            f12 = time.perf_counter() - start
            start = time.perf_counter()
            bpy.ops.lamp.light_states_render()
            rendered = time.perf_counter() - start
            items = list(bl_scene.lamp_light_panel.states)
            walls, inner = [], []
            for k in range(args.changes):
                item = items[1 + k % (len(items) - 1)]
                start = time.perf_counter()
                item.on = not item.on  # the update re-weights and fills the image
                walls.append(1000 * (time.perf_counter() - start))
                inner.append(addon.measures.light_panel.held(bl_scene)["ms"])
            print(f"{args.preset} at {args.size}x{args.size}: {len(items) - 1} states rendered in {rendered:.1f} s, "
                  f"one F12 {f12:.1f} s ({rendered / f12:.2f}x); load average {os.getloadavg()[0]:.2f}")
            print(f"  a switch to the image updated: median {statistics.median(walls):.1f} ms, max {max(walls):.1f} ms "
                  f"(re-weighting and display {statistics.median(inner):.1f} ms) over {args.changes} changes")
    finally:
        shutil.rmtree(USER, True)


if __name__ == "__main__":
    main()

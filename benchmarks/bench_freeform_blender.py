"""The Blender side of free-form parts on the four-lamp preset (about 55,000 triangles as meshes).

    .venv/bin/python benchmarks/bench_freeform_blender.py [--size 512] [--repeat 3]

Times, each the minimum of ``--repeat`` runs, with the machine's load average: Convert to Free-form;
reading the parts' meshes from the evaluated objects; F12 at ``--size``² through the free-form tracer
the first time (meshes read, acceleration structure built) and again (both reused); the export of the
JSON + .glb (Blender's glTF exporter and the checks before writing).
"""

from __future__ import annotations

import argparse
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

PRESET = ROOT / "presets" / "four-lamp-rear-combination.json"


def _timed(fn, *args, **kwargs) -> float:
    start = time.perf_counter()
    fn(*args, **kwargs)
    return time.perf_counter() - start


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=512)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    resources = tempfile.mkdtemp(prefix="lamp-bench-")
    os.environ["BLENDER_USER_RESOURCES"] = resources
    try:
        import bpy

        from tools import dev_extension

        with dev_extension.enabled_from_source(bpy, "lamp_bench") as package:
            addon = sys.modules[f"{package}.lamp_addon"]
            core = sys.modules[f"{package}.core_tracer"]
            figures: dict[str, list[float]] = {}
            out = tempfile.mkdtemp(prefix="lamp-bench-export-")
            for _ in range(args.repeat):
                bpy.ops.wm.read_homefile(use_empty=True)
                bl_scene = bpy.context.scene
                scene = core.scene.load_scene(PRESET)
                scene["image"] = {"width": args.size, "height": args.size, "samples": 1}
                addon.design.properties.scene_to_design(bl_scene, scene)
                addon.design.lamp_camera.ensure_lamp_camera(bl_scene, frame=False)
                addon.design.builder.build_lamp(bl_scene, addon.design.properties.design_to_scene(bl_scene))
                bl_scene.render.engine = "LAMP_TRACER"
                addon.freeform.geometry.forget()
                figures.setdefault("convert", []).append(
                    _timed(addon.freeform.conversion.convert_to_freeform, bl_scene))
                parts = addon.freeform.properties.role_objects(bl_scene)
                depsgraph = bpy.context.evaluated_depsgraph_get()
                figures.setdefault("read meshes", []).append(
                    _timed(addon.freeform.meshes.scene_meshes, bl_scene, depsgraph, parts))
                figures.setdefault("F12 first (read + build + render)", []).append(_timed(bpy.ops.render.render))
                figures.setdefault("F12 again (reused)", []).append(_timed(bpy.ops.render.render))
                figures.setdefault("export JSON + glb", []).append(_timed(
                    addon.freeform.export.export_pair, bl_scene, os.path.join(out, "lamp.json"), overwrite=True))
            triangles = sum(m.triangle_count for m in addon.freeform.meshes.scene_meshes(
                bl_scene, bpy.context.evaluated_depsgraph_get(), parts).values())
            shutil.rmtree(out, ignore_errors=True)
    finally:
        shutil.rmtree(resources, ignore_errors=True)
    print(f"four-lamp preset as {len(parts)} parts, {triangles} triangles, F12 at {args.size}x{args.size}, "
          f"minimum of {args.repeat}, load average {os.getloadavg()[0]:.1f}")
    for name, values in figures.items():
        print(f"  {name:36s} {min(values):.3f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())

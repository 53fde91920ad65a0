"""What Convert to Free-form costs: its time on a built preset, the converted parts' triangles, the
exported .glb's size, and the free-form mesh limits they stay within (``core_tracer.freeform.meshes``).

    .venv/bin/python benchmarks/bench_freeform_convert.py [--tree PATH] [--repeat 3] [PRESET ...]

``--tree``: the source tree whose add-on converts (another worktree, to compare an old tree with this
one in one run: run both in turn in one command). Times: the first conversion of a freshly built lamp
(the build before it not timed), and the least of ``--repeat`` - 1 more, each of the lamp built afresh,
where the meshes made before may still be in ``design.parts.shapes``.
"""

from __future__ import annotations

import argparse
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

PRESETS = ["photometric-stop-lamp", "four-lamp-rear-combination"]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tree", type=Path, default=Path(__file__).resolve().parent.parent)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("presets", nargs="*", default=PRESETS)
    args = parser.parse_args()
    sys.path.insert(0, str(args.tree.resolve()))
    resources = tempfile.mkdtemp(prefix="lamp-bench-")
    os.environ["BLENDER_USER_RESOURCES"] = resources
    out = tempfile.mkdtemp(prefix="lamp-bench-export-")
    try:
        import bpy

        from tools import dev_extension

        with dev_extension.enabled_from_source(bpy, "lamp_bench") as package:
            addon = sys.modules[f"{package}.lamp_addon"]
            core = sys.modules[f"{package}.core_tracer"]
            limits = sys.modules[f"{package}.core_tracer.freeform.meshes"]
            print(f"tree {args.tree}, load average {os.getloadavg()[0]:.1f}")
            for name in args.presets:
                times = []
                for _ in range(args.repeat):
                    bpy.ops.wm.read_homefile(use_empty=True)
                    bl_scene = bpy.context.scene
                    addon.design.properties.scene_to_design(bl_scene, core.scene.load_scene(
                        args.tree / "presets" / f"{name}.json"))
                    # the Lamp Camera moved from render/ to design/ (issue 35): either tree
                    seen = getattr(addon.design, "lamp_camera", None) or addon.render.lamp_camera
                    seen.ensure_lamp_camera(bl_scene, frame=False)
                    addon.design.builder.build_lamp(bl_scene, addon.design.properties.design_to_scene(bl_scene))
                    start = time.perf_counter()
                    addon.freeform.conversion.convert_to_freeform(bl_scene)
                    times.append(time.perf_counter() - start)
                parts = addon.freeform.properties.role_objects(bl_scene)
                meshes = addon.freeform.meshes.scene_meshes(bl_scene, bpy.context.evaluated_depsgraph_get(), parts)
                counts = {key: m.triangle_count for key, m in meshes.items()}
                total, most = sum(counts.values()), max(counts.values())
                addon.freeform.export.export_pair(bl_scene, os.path.join(out, f"{name}.json"), overwrite=True)
                glb = sum(p.stat().st_size for p in Path(out).glob(f"{name}*.glb"))
                again = min(times[1:] or times)
                print(f"  {name}: Convert first {times[0]:.3f} s, again {again:.3f} s; {len(parts)} parts, "
                      f"{total:,} triangles (largest part {most:,}; limits {limits.MAX_TRIANGLES_PER_MESH:,} a mesh, "
                      f"{limits.MAX_TRIANGLES:,} in all); .glb {glb / 1e6:.2f} MB")
    finally:
        shutil.rmtree(resources, ignore_errors=True)
        shutil.rmtree(out, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())

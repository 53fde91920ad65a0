"""Build time per design edit (Auto Build): target <= 0.2 s per edit of the four-lamp preset.

    .venv/bin/python benchmarks/bench_build.py [--repeat N]

Applies the four-lamp rear combination preset, builds it once (cold: every mesh is made), then makes
one edit at a time through the design's properties, as a designer would, and times what Auto Build
does after it: read the design, check it, rebuild what changed (``design.autobuild._step``). Edits
of lens colour, IOR, bulb and body colour remake no mesh; a lens radius remakes that lamp's lens,
reflector, socket and the body. Deep cuts are timed apart: a cut height near its limit pitch/sqrt 2
gives ~190,000 faces; given are the preview build (while dragging, on the UI thread), the making of
the full lens (when the edits stop, in Auto Build's worker thread) and the build that copies it into
Blender (UI thread). Each figure is the median of ``--repeat`` runs, each with a value not built before (as each step
of a drag is), with the machine's load average (other work slows every figure).
"""

from __future__ import annotations

import argparse
import importlib
import math
import os
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

PRESET = ROOT / "presets" / "four-lamp-rear-combination.json"
TARGET_SECONDS = 0.2

# (what the designer does, property path under lamp_design, first value, step): run k sets
# first + k * step, a value not built before, as each step of a drag is.
EDITS = (
    ("lens IOR (lamp 2)", "lamps[1].lens.ior", 1.50, 0.01),
    ("lens absorption (lamp 1)", "lamps[0].lens.absorption", (0.03, 1.4, 1.5), (0.01, 0.02, 0.02)),
    ("bulb intensity (lamp 2)", "lamps[1].bulb.intensity", (9.0, 8.0, 7.0), (0.5, 0.5, 0.5)),
    ("body colour", "body.color", (0.5, 0.5, 0.52), (0.01, 0.01, 0.01)),
    ("light direction", "light.direction", (0.2, -1.0, 0.5), (0.02, 0.0, 0.02)),
    ("bulb radius (lamp 3)", "lamps[2].bulb.radius", 7.0, 0.1),
    ("focal length (lamp 4)", "lamps[3].reflector.focal_length", 17.0, 0.1),
    ("lamp position (lamp 1)", "lamps[0].center", (-182.0, 0.0), (0.2, 0.0)),
    ("lens radius (lamp 1)", "lamps[0].lens.radius", 44.0, 0.1),
    ("cut height (lamp 1)", "lamps[0].cuts.height", 1.6, 0.05),
)


def _value(first, step, k: int):
    if isinstance(first, tuple):
        return tuple(a + k * b for a, b in zip(first, step, strict=True))
    return first + k * step


def _set(design, path: str, value) -> None:
    *parents, leaf = path.split(".")
    target = design
    for part in parents:
        name, _, index = part.partition("[")
        target = getattr(target, name)
        if index:
            target = target[int(index[:-1])]
    setattr(target, leaf, value)


def _time_edit(bl_scene, auto, path: str, first, step, repeat: int) -> float:
    times = []
    for k in range(repeat):
        _set(bl_scene.lamp_design, path, _value(first, step, k))
        start = time.perf_counter()
        auto._step(bl_scene, settled=False)
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=6, help="runs per edit (default 6)")
    args = parser.parse_args()
    resources = tempfile.mkdtemp(prefix="lamp-blender-user-")
    os.environ["BLENDER_USER_RESOURCES"] = resources
    try:
        import bpy

        from tools import dev_extension  # enables this source tree as a development extension

        bpy.ops.wm.read_homefile(use_empty=True)
        with dev_extension.enabled_from_source(bpy, "lamp_bench") as package:
            return run(bpy, package, args.repeat)
    finally:
        shutil.rmtree(resources, ignore_errors=True)


def run(bpy, package: str, repeat: int) -> int:
    props = importlib.import_module(f"{package}.lamp_addon.design.properties")
    builder = importlib.import_module(f"{package}.lamp_addon.design.builder")
    parts = importlib.import_module(f"{package}.lamp_addon.design.parts")
    auto = importlib.import_module(f"{package}.lamp_addon.design.autobuild")
    core = importlib.import_module(f"{package}.core_tracer.scene")
    bl_scene = bpy.context.scene
    props.scene_to_design(bl_scene, core.load_scene(PRESET))
    start = time.perf_counter()
    auto._step(bl_scene, settled=True)
    cold = time.perf_counter() - start
    print(f"{PRESET.name}: first build (every mesh made) {cold:.3f} s")
    start = time.perf_counter()
    for _ in range(20):
        builder.is_up_to_date(bl_scene)
    print(f"is_up_to_date (the panel's status check): {(time.perf_counter() - start) / 20 * 1000:.1f} ms")

    print(f"\nper edit, median of {repeat} (target <= {TARGET_SECONDS} s)")
    worst = 0.0
    for label, path, first, step in EDITS:
        seconds = _time_edit(bl_scene, auto, path, first, step, repeat)
        worst = max(worst, seconds)
        print(f"  {label:28s} {seconds:7.3f} s")
    print(f"  worst {worst:.3f} s: {'within' if worst <= TARGET_SECONDS else 'ABOVE'} the target")

    pitch = bl_scene.lamp_design.lamps[0].cuts.pitch
    limit = pitch / math.sqrt(2.0)
    print(f"\ndeep cuts, lamp 1 (pitch {pitch:g} mm, height limit {limit:.3f} mm)")
    lens = next(o for o in bl_scene.objects if o.get("lamp_part") == "lamps[0].lens")
    for fraction in (0.9, 0.95, 0.98):
        height = round(fraction * limit, 3)
        preview = _time_edit(bl_scene, auto, "lamps[0].cuts.height", height, -0.002, repeat)
        preview_faces = len(lens.data.polygons)
        scene = props.design_to_scene(bl_scene)
        start = time.perf_counter()
        parts.make_lenses(scene)
        made = time.perf_counter() - start
        start = time.perf_counter()
        builder.build_lamp(bl_scene, scene)
        copied = time.perf_counter() - start
        print(f"  h = {height:.3f} mm ({fraction:.0%} of the limit): preview {preview:.3f} s ({preview_faces} faces); "
              f"full lens made in {made:.3f} s (worker), copied in {copied:.3f} s ({len(lens.data.polygons)} faces)")
    print(f"\nload average: {', '.join(f'{x:.2f}' for x in os.getloadavg())}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

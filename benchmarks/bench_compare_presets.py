"""Compare (the tracer against Cycles, ``lamp_addon.compare``) on every preset of the paper's light model:
the lens mean luminance of both renders, their difference in % of Cycles', and Cycles' noise on it.

    .venv/bin/python benchmarks/bench_compare_presets.py [--size 128x128] [--samples 32] [PRESET ...]

Each preset is loaded into an empty scene and compared as ``tools/compare_preset.py`` does (the same
``compare_design`` steps: build, Lamp Camera from the preset, both renders into their slots), at a
small size so that the whole set runs in minutes. At one sample per pixel both renderers follow the ray
through each pixel's centre, and where a cut lens images the bulb sharply that point sample aliases
(paper-bulb-position at 128x128: the tracer's lens mean 1.741 at one sample, 1.659 at 256x256, 5 %
apart): so the tracer takes ``--tracer-samples`` per pixel (16) spread by Cycles' own pixel filter,
which Compare then gives Cycles too (``compare.settings``), and both integrate each pixel's area.
The lens pixels are found by geometry (the eye ray
through the pixel centre meets a lens's outer face; ``core_tracer.raytrace.engine.lens_pixels``);
luminance is Y of linear Rec.709. Cycles' noise on the lens mean is measured, not assumed: Cycles
renders the design a second time with another seed, and the noise of one render's lens mean is
sqrt(mean((Y1 - Y2)^2) / 2 / N) over the N lens pixels (pixels taken as independent), in % of the
mean. The tracer at the preset's samples has no random numbers. Prints a Markdown table
(benchmarks/RESULTS.md, "Compare on every paper preset"). Needs the bpy module (the project's .venv).
"""

from __future__ import annotations

import argparse
import importlib
import math
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from core_tracer import load_scene  # noqa: E402

TOLERANCE_PERCENT = 3.0


def paper_presets() -> list[Path]:
    """Every preset of the paper's light model (the photometric ones are compared elsewhere)."""
    return sorted(p for p in (ROOT / "presets").glob("*.json")
                  if load_scene(str(p)).get("light_model") != "photometric")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("presets", nargs="*", help="preset files (default: every paper preset)")
    parser.add_argument("--size", default="128x128")
    parser.add_argument("--samples", type=int, default=64, help="Cycles samples per pixel")
    parser.add_argument("--tracer-samples", type=int, default=16,
                        help="the tracer's samples per pixel (the preset's image.samples replaced; 0 keeps it)")
    args = parser.parse_args()
    size = tuple(int(v) for v in args.size.lower().split("x"))
    presets = [Path(p) for p in args.presets] or paper_presets()
    own_resources = tempfile.mkdtemp(prefix="lamp-blender-user-")
    os.environ.setdefault("BLENDER_USER_RESOURCES", own_resources)
    try:
        import bpy

        from tools import dev_extension

        bpy.ops.wm.read_homefile(use_empty=True)
        with dev_extension.enabled_from_source(bpy, "lamp_styling_dev") as package:
            rows = [_row(bpy, package, preset, size, args.samples, args.tracer_samples) for preset in presets]
    finally:
        shutil.rmtree(own_resources, ignore_errors=True)
    command = (f"`.venv/bin/python benchmarks/bench_compare_presets.py --size {args.size} --samples {args.samples} "
               f"--tracer-samples {args.tracer_samples}`")
    print(f"\n{len(rows)} presets at {size[0]}x{size[1]}, Cycles {args.samples} spp, tracer {args.tracer_samples} "
          f"samples per pixel; {command}\n")
    print("| preset | lens px | tracer lens Y | Cycles lens Y | tracer − Cycles | Cycles noise (1σ) | R, G, B |")
    print("|---|---|---|---|---|---|---|")
    for row in rows:
        print(row)
    return 0


def _row(bpy, package: str, preset: Path, size: tuple[int, int], samples: int, tracer_samples: int) -> str:
    comparison = importlib.import_module(f"{package}.lamp_addon.compare.comparison")
    design = importlib.import_module(f"{package}.lamp_addon.design.properties")
    lamp_camera = importlib.import_module(f"{package}.lamp_addon.design.lamp_camera")
    sheet = importlib.import_module(f"{package}.lamp_addon.convert.sheet")
    bpy.ops.wm.read_homefile(use_empty=True)
    bl_scene = bpy.context.scene
    name = preset.stem
    try:
        document = load_scene(str(preset))
        if tracer_samples:
            document["image"]["samples"] = tracer_samples
        design.scene_to_design(bl_scene, document)
        bl_scene.camera, _ = lamp_camera.ensure_lamp_camera(bl_scene, frame=False)
        start = time.perf_counter()
        with comparison.CompareRun(bl_scene, samples=samples, resolution=size) as run:
            run.prepare()
            for stage in comparison.STAGES:
                run.start(stage)
                run.collect()
            result = run.compose()
            first = run.images["cycles"]
            bl_scene.cycles.seed = 1  # the comparison's own seed is 0: a second, independent render
            run.start(comparison.CYCLES)
            run.collect()
            second = run.images["cycles"]
    except Exception as e:  # noqa: BLE001 - a preset Compare cannot run is a row of the table, not the end
        return f"| {name} | fails: {type(e).__name__}: {e} | | | | | |"
    lens = result["lens_differences"]
    mask = comparison.lens_pixels(result["scene"], first.shape[:2])
    lamp = importlib.import_module(f"{package}.core_tracer.raytrace.engine").lens_pixels(result["scene"], *size)
    y_t, y_c = sheet.luminance(result["tracer"]), sheet.luminance(first)
    lamp[~mask] = -1  # the same lens pixels as the whole row's
    per_lamp = " ".join(f"{i}: {sheet.percent_text(sheet.percent(y_t[lamp == i].mean(), y_c[lamp == i].mean()))}"
                        for i in range(lamp.max() + 1) if (lamp == i).any())
    y1, y2 = sheet.luminance(first)[mask], sheet.luminance(second)[mask]
    noise = 100.0 * math.sqrt(np.mean((y1 - y2) ** 2) / 2.0 / max(1, mask.sum())) / max(y1.mean(), 1e-300)
    channels = ", ".join(sheet.percent_text(v) for v in lens["percent"])
    within = lens["luminance_percent"] is not None and abs(lens["luminance_percent"]) <= TOLERANCE_PERCENT
    print(f"{name}: lens Y tracer {lens['tracer_luminance']:.4g}, Cycles {lens['cycles_luminance']:.4g}, "
          f"{sheet.percent_text(lens['luminance_percent'])} (noise {noise:.2f} %), {lens['pixels']} px, "
          f"{time.perf_counter() - start:.1f} s; per lamp {per_lamp}", flush=True)
    mark = "" if within else " **over 3 %**"
    return (f"| {name} | {lens['pixels']} | {lens['tracer_luminance']:.4g} | {lens['cycles_luminance']:.4g} | "
            f"{sheet.percent_text(lens['luminance_percent'])}{mark} | {noise:.2f} % | {channels} |")


if __name__ == "__main__":
    raise SystemExit(main())

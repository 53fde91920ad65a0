"""The headless main job: a preset rendered by the tracer and by Cycles, written side by side
(the command-line comparison). ``tools/compare_preset.py`` starts Blender (or the bpy module), enables the
extension and calls ``run``; this module is the part that needs the extension.
"""

from __future__ import annotations

import os
import sys

import bpy

from ...core_tracer.images import display, imageio
from ...core_tracer.scene.reading import SceneError
from ...core_tracer.scene.validate import load_scene
from ..convert.sheet import CLIP_PERCENT, percent_text
from ..design import lamp_camera
from ..design import properties as design_properties
from .comparison import DEFAULT_SAMPLES, compare_design, write_comparison
from .scope import left_out_text

CHANNELS = ("R", "G", "B")


def run(preset: str, output: str, *, samples: int = DEFAULT_SAMPLES,
        size: tuple[int, int] | None = None, view: str = display.DEFAULT_VIEW, exposure: float | str = "auto",
        prog: str = "compare_preset") -> int:
    """Load ``preset`` into the current (empty) scene's design, build it, render it both ways
    and write the side-by-side image to ``output`` (.png through ``view`` at ``exposure``, both
    halves alike, or .exr). Returns the exit status: 0 done, 2 bad input (one line on stderr)."""
    try:
        imageio.image_format(output)
        scene = load_scene(preset)
        transform = display.view_transform(view)
    except SceneError as e:
        print(f"{prog}: {e}", file=sys.stderr)
        return 2
    except ValueError as e:  # not a view of Blender's configuration
        print(f"{prog}: --view: {e}", file=sys.stderr)
        return 2
    if transform.note and output.lower().endswith(".png"):
        print(f"{prog}: note: {transform.note}", file=sys.stderr)
    bl_scene = bpy.context.scene
    design_properties.scene_to_design(bl_scene, scene)
    # The preset fixes the view: the Lamp Camera takes it and becomes the scene camera.
    bl_scene.camera, _ = lamp_camera.ensure_lamp_camera(bl_scene, frame=False)
    if size is None:
        size = (scene["image"]["width"], scene["image"]["height"])
    comparison = compare_design(bl_scene, samples=samples, resolution=size)
    folder = os.path.dirname(os.path.abspath(output))
    os.makedirs(folder, exist_ok=True)
    ev = write_comparison(output, comparison, view=transform, exposure=exposure)
    print(report(comparison, preset, output))
    if output.lower().endswith(".png"):
        print(f"shown: {transform.view} at {ev:+.1f} EV, both halves")
    return 0


def report(comparison: dict, preset: str, output: str) -> str:
    """The text the job prints: the two render times and the per-channel differences."""
    width, height = comparison["size"]
    seconds = comparison["seconds"]
    diff = comparison["differences"]
    rows = (
        ("mean, Lamp Tracer", diff["tracer_mean"]),
        ("mean, Cycles", diff["cycles_mean"]),
        ("mean difference", diff["mean_difference"]),
        ("mean |difference|", diff["mean_abs_difference"]),
        ("RMS difference", diff["rms_difference"]),
    )
    lines = [
        f"preset:       {preset}",
        f"Lamp Tracer:  {width}x{height} in {seconds['tracer']:.2f} s",
        f"Cycles:       {width}x{height}, {comparison['samples']} samples per pixel, in {seconds['cycles']:.2f} s",
        "tracer - Cycles, linear RGB  " + "".join(f"{c:>10}" for c in CHANNELS),
    ]
    lines += [f"  {name:<27}" + "".join(f"{v:10.4f}" for v in values) for name, values in rows]
    lens = comparison.get("lens_differences")
    if lens is not None:
        lines.append(f"over the {lens['pixels']} lens pixels (found by geometry; the third panel maps "
                     f"(tracer - Cycles) / Cycles of the luminance, clipped at ±{CLIP_PERCENT:g} %)")
        lines += [f"  {name:<27}" + "".join(f"{v:10.4f}" for v in lens[key]) for name, key in (
            ("lens mean, Lamp Tracer", "tracer_mean"), ("lens mean, Cycles", "cycles_mean"),
            ("lens mean difference", "mean_difference"), ("lens RMS difference", "rms_difference"))]
        lines.append(f"  {'lens mean difference, %':<27}" + "".join(f"{percent_text(v):>10}" for v in lens["percent"]))
        if lens["pixels"] and not (lens["tracer_luminance"] or lens["cycles_luminance"]):
            lines.append("lens mean luminance: 0 in both (nothing lights the lens)")
        else:
            lines.append(f"lens mean luminance: tracer {lens['tracer_luminance']:.4g}, Cycles "
                         f"{lens['cycles_luminance']:.4g}, tracer - Cycles {percent_text(lens['luminance_percent'])} "
                         f"of Cycles'")
    if comparison.get("by_design"):
        lines.append(comparison["by_design"])
    if comparison.get("left_out"):
        lines.append(left_out_text(comparison["left_out"]))
    lines.append(f"wrote {output}")
    return "\n".join(lines)

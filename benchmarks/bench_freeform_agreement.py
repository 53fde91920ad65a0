"""Does the free-form tracer, on the add-on's meshes, render every preset as the parametric tracer does?

For every preset in ``presets/`` (and the paper's lamp with flutes instead of fish-eye cuts), the
add-on (from this source tree, through the bpy module) converts the design to meshes with Convert to
Free-form; the parametric tracer renders the design and the free-form tracer the converted meshes,
at the same camera and size. Per preset it prints:

- ``light``: the total light of the lens pixels, free-form over parametric (the sum of R + G + B over
  the pixels where an eye ray enters a lens in both images: every pass but the body's and the
  background's is lit; ``rim``: how many pixels one image has on a lens and the other not, at the
  lenses' polygonal rims);
- ``all`` and ``away``: the share of the lens pixels within 2 % (``agreement``: of the pixel's largest
  channel), over all of them and away from creases and silhouettes (pixels within 10 % of their
  neighbours in the parametric image, as ``tests/addon/test_addon_freeform_convert.py`` excepts them),
  and how many of the lens pixels are away from creases;
- triangles of the converted lens parts (lens glass, prism plates) and of all parts, the build (Build
  Lamp + Convert) and the two renders' seconds.

    .venv/bin/python benchmarks/bench_freeform_agreement.py [--size 256] [--samples N] [--tolerance MM]
        [--cut-tolerance MM] [PRESET ...]

The presets under a sky (``environment``) differ by more than the meshes: their phantom light crosses
the lens as a flat plate of the mesh's mean thickness, where the parametric lamp takes t + h/2
(docs/model.md §8.14). At 128x128 and below the creases' few pixels move a preset's total by
up to 0.75 %.

``--tolerance`` and ``--cut-tolerance`` convert with other tolerances than Convert to Free-form's
``FREEFORM_CHORD_TOLERANCE_MM`` and ``FREEFORM_CUT_TOLERANCE_MM`` / ``FLUTE_TOLERANCE_MM`` (the module
constants, for this process only; Build's 0.05 / 0.0075 mm: ``--tolerance 0.05 --cut-tolerance 0.0075``).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))  # the crease mask the agreement test uses

from helpers import creases  # noqa: E402

PRESETS = ROOT / "presets"
TAU = 0.02  # a pixel agrees within 2 % of its largest channel
EDGE_CONTRAST = 0.10  # a crease or silhouette: 10 % from a neighbour (the test's exception)
FLUTES = "paper-baseline+flutes"  # the paper's lamp with flutes (no preset has them)


def lens_pixels(passes: dict[str, np.ndarray]) -> np.ndarray:
    """Pixels whose eye ray enters a lens: lit by a pass other than the body's and the background's."""
    lit = sum(image for name, image in passes.items() if name not in ("body", "background"))
    return lit.max(axis=2) > 0.0




def agreement(parametric, freeform, lens) -> dict:
    """The figures of one preset (see the module's docstring)."""
    value = np.maximum(parametric.max(axis=2), 1e-3 * parametric.max())
    within = np.abs(freeform - parametric).max(axis=2) / value <= TAU
    away = lens & ~creases(parametric, EDGE_CONTRAST)
    return {"light": float(freeform[lens].sum() / parametric[lens].sum()), "lens_pixels": int(lens.sum()),
            "all": float(within[lens].mean()), "away": float(within[away].mean()),
            "away_share": float(away.sum() / lens.sum())}


def designs(names: list[str]) -> list[tuple[str, dict]]:
    from core_tracer.scene.validate import load_scene, parse_scene

    chosen = []
    for path in sorted(PRESETS.glob("*.json")):
        if not names or path.stem in names:
            chosen.append((path.stem, load_scene(path)))
    if not names or FLUTES in names:
        doc = json.loads((PRESETS / "paper-baseline.json").read_text())
        doc["lamps"][0]["cuts"].update(type="flutes", height=1.5)
        chosen.append((FLUTES, parse_scene(doc)))
    return chosen


def set_tolerances(package: str, chord: float | None, cut: float | None) -> None:
    """Convert to Free-form with other tolerances in this process: the chord tolerance
    (``FREEFORM_CHORD_TOLERANCE_MM``) and the cut surfaces' (``FREEFORM_CUT_TOLERANCE_MM``, the flutes'
    ``FLUTE_TOLERANCE_MM`` too); Build's are not changed."""
    meshes = sys.modules[f"{package}.lamp_addon.convert.meshes.builder"]
    if cut:
        meshes.FREEFORM_CUT_TOLERANCE_MM = cut
        sys.modules[f"{package}.lamp_addon.convert.meshes.flutes"].FLUTE_TOLERANCE_MM = cut
    if chord:
        meshes.FREEFORM_CHORD_TOLERANCE_MM = chord
    parts = sys.modules[f"{package}.lamp_addon.design.parts"]
    parts.shapes.items.clear()
    parts.subdivisions.items.clear()


def measure(bpy, lamp_addon, core, name: str, scene: dict, size: int, samples: int) -> dict:
    bpy.ops.wm.read_homefile(use_empty=True)
    bl_scene = bpy.context.scene
    scene = json.loads(json.dumps(scene))
    scene["image"] = {"width": size, "height": size, "samples": samples}
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    design = lamp_addon.design.properties.design_to_scene(bl_scene)
    start = time.perf_counter()
    lamp_addon.design.builder.build_lamp(bl_scene, design)
    lamp_addon.freeform.conversion.convert_to_freeform(bl_scene)
    prepared = lamp_addon.freeform.render.prepare(bl_scene, bpy.context.evaluated_depsgraph_get(), design)
    build = time.perf_counter() - start
    start = time.perf_counter()
    parametric = core.render_passes(design, size, size)
    parametric_seconds = time.perf_counter() - start
    start = time.perf_counter()
    freeform = lamp_addon.freeform.render.render_passes(prepared, size, size)
    freeform_seconds = time.perf_counter() - start
    lens = lens_pixels(parametric.passes) & lens_pixels(freeform.passes)
    figures = agreement(parametric.image, freeform.image, lens)
    figures["rim_pixels"] = int((lens_pixels(parametric.passes) != lens_pixels(freeform.passes)).sum())
    meshes = prepared.geometry.meshes
    lens_names = {p["object"] for p in prepared.scene["freeform"]["parts"] if p["role"] == "lens"}
    figures.update(name=name, lens_triangles=sum(len(m.triangles) for n, m in meshes.items() if n in lens_names),
                   triangles=sum(len(m.triangles) for m in meshes.values()), build=build,
                   parametric_seconds=parametric_seconds, freeform_seconds=freeform_seconds)
    return figures


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("presets", nargs="*", help=f"preset names (default: all, and {FLUTES})")
    parser.add_argument("--size", type=int, default=256)
    parser.add_argument("--samples", type=int, default=1, help="samples per pixel")
    parser.add_argument("--tolerance", type=float, help="chord tolerance, mm (default: the add-on's)")
    parser.add_argument("--cut-tolerance", type=float,
                        help="the cut surfaces' tolerance (caps and flutes), mm (default: the add-on's)")
    parser.add_argument("--json", metavar="FILE", help="also write the figures as JSON")
    args = parser.parse_args()

    os.environ["BLENDER_USER_RESOURCES"] = resources = tempfile.mkdtemp(prefix="lamp-blender-user-")
    import bpy

    from tools import dev_extension

    rows = []
    try:
        with dev_extension.enabled_from_source(bpy, "lamp_bench", reuse_enabled=False) as package:
            lamp_addon, core = sys.modules[f"{package}.lamp_addon"], sys.modules[f"{package}.core_tracer"]
            set_tolerances(package, args.tolerance, args.cut_tolerance)
            meshes = sys.modules[f"{package}.lamp_addon.convert.meshes.builder"]
            tol, cut = meshes.FREEFORM_CHORD_TOLERANCE_MM, meshes.FREEFORM_CUT_TOLERANCE_MM
            print(f"chord tolerance {tol} mm, cut surfaces {cut} mm, {args.size}x{args.size}, "
                  f"{args.samples} samples per pixel")
            print(f"{'preset':32} {'light':>7} {'all':>7} {'away':>7} {'(share)':>7} {'rim':>4} {'lens tris':>9} "
                  f"{'tris':>8} {'build s':>7} {'param s':>7} {'free s':>7}")
            for name, scene in designs(args.presets):
                f = measure(bpy, lamp_addon, core, name, scene, args.size, args.samples)
                f.update(tolerance=tol, cut_tolerance=cut, size=args.size, samples=args.samples)
                rows.append(f)
                print(f"{name:32} {f['light']:7.4f} {f['all']:7.2%} {f['away']:7.2%} {f['away_share']:7.0%} "
                      f"{f['rim_pixels']:4d} {f['lens_triangles']:9d} {f['triangles']:8d} {f['build']:7.2f} "
                      f"{f['parametric_seconds']:7.2f} {f['freeform_seconds']:7.2f}", flush=True)
    finally:
        shutil.rmtree(resources, ignore_errors=True)
    worst = max(rows, key=lambda f: abs(f["light"] - 1.0))
    print(f"worst total lens light: {worst['name']} {worst['light']:.4f}")
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())

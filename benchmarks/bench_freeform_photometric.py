"""The photometric stop lamp against its free-form twin (issue 32): what the meshes change, measured.

The design (``presets/photometric-stop-lamp.json``) is built and converted by the add-on (this source
tree, through the bpy module) with the given tolerances; the same engine then measures the parametric
lamp and the meshes:

- the lit lens's mean luminance in the measures' 0.5 mm front view (``homogeneity``, as
  ``tests/addon/test_addon_freeform_convert.py`` takes it), the share of its pixels that agree within
  2 % (the same surfaces met) and their mean difference, and what the other pixels add (of the lens's
  light);
- I(H, V) at the given points, rendered views at ``--pixel`` mm: per replicate the same randomly shifted
  pixel grid for both, so that the difference is paired; printed: each estimate's standard error
  (replicates' spread / √n) and the paired difference's mean and standard error.

    .venv/bin/python benchmarks/bench_freeform_photometric.py [--tolerance MM] [--cut-tolerance MM]
        [--socket-tolerance MM] [--bulb-tolerance MM] [--points "H,V;H,V"] [--replicates N] [--pixel MM]

``--tolerance`` / ``--cut-tolerance`` as ``bench_freeform_agreement.py``'s; ``--socket-tolerance`` and
``--bulb-tolerance`` tessellate only the socket or only the bulb finer.
"""

from __future__ import annotations

import argparse
import importlib
import os
import shutil
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from bench_freeform_agreement import set_tolerances  # noqa: E402

FRONT_PIXEL_MM = 0.5
AGREE = 0.02


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--tolerance", type=float, help="chord tolerance, mm (default: Convert to Free-form's)")
    p.add_argument("--cut-tolerance", type=float, help="the cut surfaces' tolerance, mm")
    p.add_argument("--socket-tolerance", type=float, help="the socket's chord tolerance only, mm")
    p.add_argument("--bulb-tolerance", type=float, help="the bulb's chord tolerance only, mm")
    p.add_argument("--points", default="20,10;20,-10;-20,10;-20,-10;20,0;0,0", help='"H,V;H,V" in degrees')
    p.add_argument("--replicates", type=int, default=3)
    p.add_argument("--pixel", type=float, default=0.5, help="the grid views' pixel, mm")
    a = p.parse_args()
    os.environ["BLENDER_USER_RESOURCES"] = resources = tempfile.mkdtemp(prefix="lamp-blender-user-")
    import bpy

    from tools import dev_extension

    try:
        with dev_extension.enabled_from_source(bpy, "lamp_bench", reuse_enabled=False) as package:
            addon = sys.modules[f"{package}.lamp_addon"]
            set_tolerances(package, a.tolerance, a.cut_tolerance)
            part_meshes = sys.modules[f"{package}.lamp_addon.convert.meshes.parts"]
            if a.socket_tolerance:
                part_meshes.socket_mesh.__defaults__ = (a.socket_tolerance,)
            if a.bulb_tolerance:
                part_meshes.sphere_mesh.__defaults__ = (a.bulb_tolerance,)

            def core(name: str):
                return importlib.import_module(f"{package}.core_tracer.{name}")

            bpy.ops.wm.read_homefile(use_empty=True)
            bl_scene = bpy.context.scene
            scene = core("scene").load_scene(ROOT / "presets" / "photometric-stop-lamp.json")
            scene["image"] = {"width": 96, "height": 96, "samples": 1}
            addon.design.properties.scene_to_design(bl_scene, scene)
            design = addon.design.properties.design_to_scene(bl_scene)
            addon.design.builder.build_lamp(bl_scene, design)
            addon.freeform.conversion.convert_to_freeform(bl_scene)
            prepared = addon.freeform.render.prepare(bl_scene, bpy.context.evaluated_depsgraph_get(), design)
            freeform = prepared.scene
            meshes = core("freeform.design").DesignMeshes(prepared.geometry.meshes)
            print("triangles:", {n: len(m.triangles) for n, m in prepared.geometry.meshes.items()}, flush=True)
            intensity, direction = core("measures.intensity"), core("measures.directions").direction
            homogeneity = core("measures.homogeneity").homogeneity
            view = intensity.view_along(design, direction(0.0, 0.0), FRONT_PIXEL_MM)
            parametric = intensity.render_view(intensity.measurement_scene(design), view)[..., 1]
            meshed = intensity.render_view(intensity.measurement_scene(freeform), view, meshes=meshes)[..., 1]
            lens = (intensity.lamp_of_pixels(design, view) == 0) & (parametric > 0)
            l_p = homogeneity(parametric, lens, FRONT_PIXEL_MM).l_mean
            l_m = homogeneity(meshed, lens, FRONT_PIXEL_MM).l_mean
            ratio = meshed[lens] / parametric[lens]
            agree = np.abs(ratio - 1.0) < AGREE
            other = (meshed[lens][~agree].sum() - parametric[lens][~agree].sum()) / parametric[lens].sum()
            print(f"lit lens: {l_p:.1f} cd/m² parametric, {l_m:.1f} free-form ({l_m / l_p - 1:+.3%}); "
                  f"{agree.mean():.1%} of its pixels within 2 %: {ratio[agree].mean() - 1:+.3%}; "
                  f"the others add {other:+.3%}", flush=True)
            for k, point in enumerate(filter(None, a.points.split(";"))):
                h, v = map(float, point.split(","))
                cd = np.zeros((2, a.replicates))
                for r in range(a.replicates):
                    seed = 1000 * k + r  # one pixel grid per replicate, the same for both
                    cd[0, r] = intensity.rendered_intensities(design, h, v, pixel_mm=a.pixel, replicates=1,
                                                              seed=seed)[0].cd
                    cd[1, r] = intensity.rendered_intensities(freeform, h, v, pixel_mm=a.pixel, replicates=1,
                                                              seed=seed, meshes=meshes)[0].cd
                se = cd.std(axis=1, ddof=1) / np.sqrt(a.replicates)
                paired = cd[1] / cd[0] - 1.0
                print(f"H {h:+5.1f} V {v:+5.1f}: {cd[0].mean():.2f} ± {se[0]:.2f} cd parametric, "
                      f"{cd[1].mean():.2f} ± {se[1]:.2f} free-form; paired {paired.mean():+.3%} "
                      f"± {paired.std(ddof=1) / np.sqrt(a.replicates):.3%}", flush=True)
    finally:
        shutil.rmtree(resources, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())

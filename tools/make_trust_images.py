"""Make the pictures that show issue 31's colour path from Blender, as a designer gets them.

    xvfb-run -a .venv/bin/python tools/make_trust_images.py [--out docs/images]

From Blender's factory startup file (Cube, Camera, Light) with the add-on enabled from this tree:

- ``blender-study-sheet-photometric.png``: the photometric stop lamp applied, Run Study over the lens's
  refractive index (1.45, 1.6), Save Sheet: the sheet as Blender writes it (before issue 31 the lamp
  showed gold on it, its XYZ taken for R, G, B).
- ``blender-reads-photometric-exr.png``: the command line's EXR of the same lamp (X, Y, Z in cd/m² with
  their chromaticities) opened by ``bpy.data.images.load`` and saved through the scene's view
  transform, as the Image Editor shows it: left, the file as written (Blender picks "Linear CIE-XYZ E");
  right, the same pixels with the chromaticities left out, read as Rec.709 R, G, B (the old fault).
Each prints the colour space Blender chose and the lit lens's median G/R, B/R.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
STOP_LAMP = os.path.join(ROOT, "presets", "photometric-stop-lamp.json")
SIZE = 160


def lit_ratios(rgb: np.ndarray) -> tuple[float, float]:
    """Median G/R and B/R over the pixels whose red is above half the brightest red (not grey)."""
    red = rgb[..., 0]
    grey = (np.abs(red - rgb[..., 1]) < 0.02) & (np.abs(red - rgb[..., 2]) < 0.02)
    lit = (red > 0.5 * red[~grey].max()) & ~grey
    return float(np.median(rgb[..., 1][lit] / red[lit])), float(np.median(rgb[..., 2][lit] / red[lit]))


def study_sheet(bpy, core, addon, path: str) -> None:
    bpy.ops.wm.read_homefile(use_factory_startup=True)
    bl_scene = bpy.context.scene
    scene = core.load_scene(STOP_LAMP)
    addon.design.properties.scene_to_design(bl_scene, scene)
    assert bpy.ops.lamp.build() == {"FINISHED"}
    study = bl_scene.lamp_study
    study.width, study.height, study.workers = SIZE, SIZE, 1
    study.axis_1.parameter, study.axis_1.mode, study.axis_1.values = "lens.ior", "LIST", "1.45, 1.6"
    study.use_axis_2 = False
    assert bpy.ops.lamp.study_run() == {"FINISHED"}
    assert bpy.ops.lamp.study_save_sheet(filepath=path) == {"FINISHED"}
    import OpenImageIO as oiio

    shown = np.asarray(oiio.ImageBuf(path).get_pixels(oiio.FLOAT))[..., :3]
    g, b = lit_ratios(shown)
    print(f"Save Sheet -> {path}: lit lens G/R {g:.2f}, B/R {b:.2f}")


def exr_in_blender(bpy, core, path: str) -> None:
    import OpenImageIO as oiio

    folder = tempfile.mkdtemp(prefix="lamp-exr-")
    exr = os.path.join(folder, "stop.exr")
    subprocess.run([sys.executable, "-m", "core_tracer", "render", STOP_LAMP, "-o", exr, "--width", str(SIZE),
                    "--height", str(SIZE)], cwd=ROOT, check=True, capture_output=True)
    bare = os.path.join(folder, "stop-without-chromaticities.exr")
    buf = oiio.ImageBuf(exr)
    spec = buf.spec()
    spec.erase_attribute("chromaticities")
    spec.erase_attribute("whiteLuminance")
    out = oiio.ImageOutput.create(bare)
    out.open(bare, spec)
    out.write_image(buf.get_pixels(oiio.FLOAT))
    out.close()
    bpy.ops.wm.read_homefile(use_factory_startup=True)
    bl_scene = bpy.context.scene
    bl_scene.view_settings.view_transform = "Filmic"  # the lamp view (display.LAMP_VIEW)
    ev100 = float(core.load_scene(STOP_LAMP)["camera"]["ev100"])
    # the file's cd/m² at the design's EV100, as the tracer shows it: scaled by 1 / (1.2 2^EV100)
    # (``photometry.output.exposure_scale``), i.e. Blender's exposure -(EV100 + log2 1.2) stops
    bl_scene.view_settings.exposure = -(ev100 + float(np.log2(1.2)))
    halves = []
    settings = bl_scene.render.image_settings
    settings.file_format, settings.color_mode, settings.color_depth = "PNG", "RGB", "8"
    for name in (exr, bare):
        image = bpy.data.images.load(name)
        shown = os.path.join(folder, os.path.basename(name) + ".png")
        image.save_render(shown, scene=bl_scene)
        rgb = np.asarray(oiio.ImageBuf(shown).get_pixels(oiio.FLOAT))[..., :3]
        g, b = lit_ratios(rgb)
        print(f"{os.path.basename(name)}: Blender reads it as {image.colorspace_settings.name!r}; shown lit lens "
              f"G/R {g:.2f}, B/R {b:.2f}")
        halves.append(rgb)
    gap = np.full((SIZE, 6, 3), 0.2, np.float32)
    both = np.concatenate([halves[0], gap, halves[1]], axis=1)
    out = oiio.ImageBuf(oiio.ImageSpec(both.shape[1], both.shape[0], 3, oiio.UINT8))
    out.set_pixels(oiio.ROI(), np.ascontiguousarray(both, np.float32))
    out.write(path)
    print(f"-> {path}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=os.path.join(ROOT, "docs", "images"), help="folder to write into")
    args = parser.parse_args(argv)
    os.makedirs(args.out, exist_ok=True)
    sys.path.insert(0, ROOT)
    from tools import dev_extension

    with dev_extension.blender_with_addon("lamp_trust") as (bpy, addon, core):
        study_sheet(bpy, core, addon, os.path.join(args.out, "blender-study-sheet-photometric.png"))
        exr_in_blender(bpy, core, os.path.join(args.out, "blender-reads-photometric-exr.png"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

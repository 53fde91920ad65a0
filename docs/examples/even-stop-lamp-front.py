"""The front view of the photometric example's start and best designs (docs/optimise-photometric-front.png):
the luminance seen from H-V, as the homogeneity measures see it. From the repository root:

    .venv/bin/python docs/examples/even-stop-lamp-front.py [--out docs/optimise-photometric-front.png]
"""

import argparse
import copy
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, ROOT)

from core_tracer.measures import intensity as I  # noqa: E402
from core_tracer.measures.directions import direction  # noqa: E402
from core_tracer.measures.homogeneity import homogeneity  # noqa: E402
from core_tracer.scene.reading import read_json  # noqa: E402
from core_tracer.scene.validate import parse_scene  # noqa: E402

DESIGNS = [("start (trial 0)", 0.0, 9.0, 1.5), ("best (trial 21)", 3.62219, 12.1502, 0.885761)]
PIXEL_MM = 1.0

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--out", default=os.path.join(ROOT, "docs", "optimise-photometric-front.png"))
args = parser.parse_args()
base = read_json(os.path.join(ROOT, "presets", "photometric-stop-lamp.json"))
fig, axes = plt.subplots(1, 2, figsize=(10, 4.4))
for ax, (what, offset, pitch, height) in zip(axes, DESIGNS, strict=True):
    doc = copy.deepcopy(base)
    lamp = doc["lamps"][0]
    lamp["bulb"]["offset"][1], lamp["cuts"]["pitch"], lamp["cuts"]["height"] = offset, pitch, height
    scene = parse_scene(doc)
    view = I.view_along(scene, direction(0.0, 0.0), PIXEL_MM)
    luminance = I.render_view(I.measurement_scene(scene), view)[..., 1]
    mask = (I.lamp_of_pixels(scene, view) == 0) & (luminance > 0)
    figures = homogeneity(luminance, mask, PIXEL_MM)
    ys, xs = np.nonzero(mask)
    crop = (slice(ys.min() - 3, ys.max() + 4), slice(xs.min() - 3, xs.max() + 4))
    shown = ax.imshow(luminance[crop], cmap="inferno", vmin=0, vmax=32000)
    ax.axis("off")
    if figures.dark.any():
        ax.contour(figures.dark[crop], levels=[0.5], colors="cyan", linewidths=0.8)
    ax.set_title(f"{what}\noffset {offset:.2f} mm, pitch {pitch:.1f} mm, height {height:.2f} mm\n"
                 f"CV {figures.cv:.3f}, Lmin/Lmean {figures.uniformity_min_mean:.2f}, "
                 f"dark {100 * figures.dark_fraction:.0f} %", fontsize=8)
bar = fig.colorbar(shown, ax=axes, fraction=0.03)
bar.set_label("luminance from H-V, cd/m²")
fig.suptitle("photometric stop lamp seen from H-V (1 mm pixels, eye at 10 m; cyan: below half the mean)", fontsize=9)
fig.subplots_adjust(top=0.8, left=0.02, right=0.88, wspace=0.1)
fig.savefig(args.out, dpi=100)

"""What carrying Fresnel at a few wavelength nodes costs in accuracy (``spectral.Throughput``,
docs/photometric.md "Speed"): every photometric preset rendered with Fresnel per band (a node at
each band's centre) and with J nodes, compared on the lit lens (the pixels whose luminance is at
least 1/10 of the 99th percentile of the per-band render), and the time of each.

    .venv/bin/python benchmarks/bench_fresnel_nodes.py [--nodes 4 6 8 12] [--scale 0.5] [--bands K]

Per preset and J: the largest |ΔL|/L of a lit-lens pixel (and its 99.9th percentile), the largest
|Δx| or |Δy| of a pixel, and the lit lens's mean luminance and chromaticity (of the summed XYZ)
against the per-band render's. Renders on threads of this process (the node count is this
process's ``spectral.FRESNEL_NODES``), at ``--scale`` of each preset's size and its own samples.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # before numpy is imported (bench_photometric.py)
ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from core_tracer import load_scene, render_passes  # noqa: E402
from core_tracer.raytrace import spectral  # noqa: E402


def chromaticity(XYZ: np.ndarray) -> np.ndarray:
    total = XYZ.sum(axis=-1)
    return XYZ[..., :2] / np.where(total > 0, total, 1.0)[..., None]


def rendered(scene: dict, size: tuple[int, int], bands: int, nodes: int) -> tuple[np.ndarray, float]:
    spectral.FRESNEL_NODES = nodes
    start = time.perf_counter()
    image = render_passes(scene, *size, keep_passes=False, bands=bands).image.astype(np.float64)
    return image, time.perf_counter() - start


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nodes", type=int, nargs="+", default=[4, 6, 8, 12])
    parser.add_argument("--scale", type=float, default=0.5)
    parser.add_argument("--bands", type=int, default=spectral.DEFAULT_BANDS)
    args = parser.parse_args()
    print(f"K = {args.bands}, each preset at {args.scale:g} of its size, load average {os.getloadavg()[0]:.2f}")
    worst: dict[int, list[float]] = {j: [0.0, 0.0, 0.0, 0.0] for j in args.nodes}
    for path in sorted((ROOT / "presets").glob("*.json")):
        scene = load_scene(path)
        if scene.get("light_model") != "photometric":
            continue
        image_size = scene["image"]
        size = (max(8, round(image_size["width"] * args.scale)), max(8, round(image_size["height"] * args.scale)))
        exact, seconds = rendered(scene, size, args.bands, args.bands)
        Y = exact[..., 1]
        lit = Y >= 0.1 * np.percentile(Y, 99)
        xy = chromaticity(exact)[lit]
        lens_xy = chromaticity(exact[lit].sum(axis=0))
        print(f"{path.stem} {size[0]}x{size[1]}: per band {seconds:.2f} s, lit lens {int(lit.sum())} px")
        for nodes in args.nodes:
            image, seconds = rendered(scene, size, args.bands, nodes)
            dL = np.abs(image[..., 1] - Y)[lit] / Y[lit]
            dxy = np.abs(chromaticity(image)[lit] - xy).max()
            mean_L = abs(image[..., 1][lit].mean() / Y[lit].mean() - 1.0)
            mean_xy = np.abs(chromaticity(image[lit].sum(axis=0)) - lens_xy).max()
            for i, value in enumerate((dL.max(), dxy, mean_L, mean_xy)):
                worst[nodes][i] = max(worst[nodes][i], float(value))
            print(f"  J = {nodes:2d}: {seconds:.2f} s; max |dL|/L {dL.max():.2e} (99.9th pct "
                  f"{np.percentile(dL, 99.9):.1e}), max |dxy| {dxy:.1e}; lit lens mean L {mean_L:.1e}, "
                  f"xy {mean_xy:.1e}", flush=True)
    for nodes, (dL, dxy, mean_L, mean_xy) in worst.items():
        print(f"worst over the presets, J = {nodes:2d}: max |dL|/L {dL:.2e}, max |dxy| {dxy:.1e}, "
              f"lit lens mean L {mean_L:.1e}, xy {mean_xy:.1e}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

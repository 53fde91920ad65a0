"""Dispersion: what holding the rays' directions at n_d costs (the engine refracts every band along
the n_d direction and applies n(λ) in Fresnel only, ``raytrace.spectral``).

The reference traces each band k along its own directions: the lens is given the index n(λ_k) of
its plastic at the band's centre (a custom material of that n_d and Abbe number 100, the least
dispersion the scene allows, so its Fresnel n stays within 0.2 % of n(λ_k) across the band), and
only band k of that render is kept (its row of the XYZ matrix); the K renders are summed. Over the
lit lens of the photometric stop lamp (fish-eye cuts), for PMMA and polycarbonate, it prints the
difference of the lens's mean luminance (%) and intensity-weighted xy, and per pixel the median and
95th percentile of |ΔL|/L and of max(|Δx|, |Δy|).

    .venv/bin/python benchmarks/bench_dispersion.py [--size 128] [--bands K]
        [--preset presets/photometric-stop-lamp.json]

Only this script changes the engine's XYZ matrix (``spectral.setup`` wrapped while it runs), to
pick one band out of a render; the tracer itself is unchanged.
"""

from __future__ import annotations

import contextlib
import copy
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from benchmarks.common import arguments  # noqa: E402
from core_tracer import load_scene, render_passes  # noqa: E402
from core_tracer.photometry import materials  # noqa: E402
from core_tracer.raytrace import spectral  # noqa: E402

LIT_FRACTION = 0.1


@contextlib.contextmanager
def only_band(k: int):
    """While inside, a photometric render's XYZ holds band ``k``'s share only."""
    original = spectral.setup

    def setup(scene, bands, sun_direction):
        light = original(scene, bands, sun_direction)
        mask = np.zeros_like(light.to_xyz)
        mask[k] = light.to_xyz[k]
        return replace(light, to_xyz=mask)

    spectral.setup = setup
    try:
        yield
    finally:
        spectral.setup = original


def per_band_directions(scene: dict, material: materials.Material, k_bands: int) -> np.ndarray:
    bands = spectral.bands_of(k_bands)
    total = None
    for k, n_k in enumerate(material.index(bands.centres_nm)):
        band_scene = copy.deepcopy(scene)
        for lamp in band_scene["lamps"]:
            lamp["lens"].update(material="custom", ior=float(n_k), abbe=100.0)
        with only_band(k):
            image = render_passes(band_scene, bands=k_bands, threads=1).image.astype(np.float64)
        total = image if total is None else total + image
    return total


def compare(held: np.ndarray, own: np.ndarray) -> dict[str, float]:
    region = held[..., 1] >= LIT_FRACTION * np.percentile(held[..., 1], 99.0)
    a, b = held[region], own[region]
    mean_l = abs(b[:, 1].mean() / a[:, 1].mean() - 1.0) * 100.0
    xy_a, xy_b = a.sum(0)[:2] / a.sum(0).sum(), b.sum(0)[:2] / b.sum(0).sum()
    rel = np.abs(b[:, 1] - a[:, 1]) / np.maximum(a[:, 1], 1e-30)
    pxy = np.abs(b[:, :2] / b.sum(1, keepdims=True) - a[:, :2] / a.sum(1, keepdims=True)).max(axis=1)
    return {"pixels": int(region.sum()), "mean L %": mean_l, "mean xy": float(np.abs(xy_b - xy_a).max()),
            "pixel dL/L median %": float(np.median(rel)) * 100, "pixel dL/L p95 %": float(np.percentile(rel, 95)) * 100,
            "pixel dxy median": float(np.median(pxy)), "pixel dxy p95": float(np.percentile(pxy, 95))}


def main() -> int:
    args = arguments(__doc__, "photometric-stop-lamp.json", size=128, bands=spectral.DEFAULT_BANDS).parse_args()
    base = load_scene(args.preset)
    base["image"].update(width=args.size, height=args.size, samples=1)
    print(f"{Path(args.preset).name}, {args.size}x{args.size} px, 1 sample, K = {args.bands}: directions held at n_d "
          f"against each band along its own")
    for key in ("pmma", "polycarbonate"):
        start = time.perf_counter()
        material = materials.MATERIALS[key]
        scene = copy.deepcopy(base)
        for lamp in scene["lamps"]:
            lamp["lens"]["material"] = key
        held = render_passes(scene, bands=args.bands, threads=1).image.astype(np.float64)
        own = per_band_directions(scene, material, args.bands)
        figures = compare(held, own)
        shown = ", ".join(f"{name} {value:.4g}" for name, value in figures.items())
        print(f"  {key} (n_d {material.n_d}, Abbe {material.abbe}): {shown}  ({time.perf_counter() - start:.1f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

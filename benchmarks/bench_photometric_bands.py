"""K by measurement: every photometric preset rendered by the tracer at K bands and at 81 (5 nm),
the issue's reference. Per preset: the intensity-weighted mean chromaticity xy (the sum of XYZ
over the region, then xy) and the mean luminance over the lit lens (pixels within 1/10 of the
81-band render's 99th luminance percentile; the whole image for an unlit preset, where nothing is
that bright apart from the surroundings: the region is then every pixel), and their differences
from 81 bands: max(|Δx|, |Δy|) and ΔL in %. Limits (issue 22 item 2): xy 0.001, luminance 0.5 %.

    .venv/bin/python benchmarks/bench_photometric_bands.py [--ks 16,24,32,40,48] [--size 96] [--samples 1]

The last line names the smallest K of the list from which every larger K meets both limits on
every preset (``spectral.DEFAULT_BANDS`` is set from it; docs/photometric.md).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from core_tracer import load_scene, render_passes  # noqa: E402
from core_tracer.raytrace import spectral  # noqa: E402

REFERENCE_K = 81
XY_LIMIT = 0.001
LUMINANCE_LIMIT = 0.5  # %
LIT_FRACTION = 0.1  # of the 99th luminance percentile: the lit lens


def photometric_presets() -> list[Path]:
    return sorted(p for p in (ROOT / "presets").glob("*.json") if '"photometric"' in p.read_text())


def render_xyz(scene: dict, k: int, size: int, samples: int) -> np.ndarray:
    scene = {**scene, "image": {**scene["image"], "width": size, "height": size, "samples": samples}}
    return render_passes(scene, bands=k).image.astype(np.float64)


def lit_region(reference: np.ndarray, lit: bool) -> np.ndarray:
    """The lit lens of the 81-band render (a lit preset), else every pixel."""
    luminance = reference[..., 1]
    if not lit:
        return np.ones(luminance.shape, dtype=bool)
    return luminance >= LIT_FRACTION * np.percentile(luminance, 99.0)


def summary(XYZ: np.ndarray, region: np.ndarray) -> tuple[np.ndarray, float]:
    """(xy of the summed XYZ over ``region``, its mean luminance in cd/m²)."""
    total = XYZ[region].sum(axis=0)
    return total[:2] / total.sum(), float(XYZ[region][:, 1].mean())


def errors(scene: dict, ks: list[int], size: int, samples: int) -> tuple[dict[int, tuple[float, float]], float,
                                                                         np.ndarray, int]:
    """{K: (max |Δxy|, |ΔL| %)} against 81 bands, the reference's mean luminance and xy, region pixels."""
    reference = render_xyz(scene, REFERENCE_K, size, samples)
    lit = any(lamp["bulb"]["on"] for lamp in scene["lamps"])
    region = lit_region(reference, lit)
    xy_ref, lum_ref = summary(reference, region)
    out = {}
    for k in ks:
        xy, lum = summary(render_xyz(scene, k, size, samples), region)
        out[k] = (float(np.abs(xy - xy_ref).max()), abs(lum / lum_ref - 1.0) * 100.0)
    return out, lum_ref, xy_ref, int(region.sum())


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ks", default="16,24,32,40,48", help="the K to compare with 81, comma-separated")
    parser.add_argument("--size", type=int, default=96, help="image side in pixels")
    parser.add_argument("--samples", type=int, default=1, help="samples per pixel (the same at every K)")
    args = parser.parse_args()
    ks = sorted(int(k) for k in args.ks.split(","))
    start = time.perf_counter()
    print(f"against K = {REFERENCE_K}, {args.size}x{args.size} px, {args.samples} sample(s); "
          f"each cell: max |dx|,|dy| and luminance error in %; default K = {spectral.DEFAULT_BANDS}")
    print(f"{'preset':36s}" + "".join(f"{'K=' + str(k):>16s}" for k in ks) + "   L(81) cd/m2   xy(81)")
    worst = {k: (0.0, 0.0) for k in ks}
    for path in photometric_presets():
        scene = load_scene(path)
        table, lum, xy, pixels = errors(scene, ks, args.size, args.samples)
        cells = "".join(f"{e_xy:>9.5f} {e_l:5.2f}%" for e_xy, e_l in table.values())
        print(f"{path.stem:36s}{cells}   {lum:11.4g}   ({xy[0]:.4f}, {xy[1]:.4f})  [{pixels} px]")
        for k, (e_xy, e_l) in table.items():
            worst[k] = (max(worst[k][0], e_xy), max(worst[k][1], e_l))
    print(f"{'worst':36s}" + "".join(f"{e_xy:>9.5f} {e_l:5.2f}%" for e_xy, e_l in worst.values()))
    good = [k for k in ks if all(worst[j][0] <= XY_LIMIT and worst[j][1] <= LUMINANCE_LIMIT for j in ks if j >= k)]
    chosen = f"K = {good[0]}" if good else f"none of {ks}"
    print(f"smallest K meeting xy {XY_LIMIT} and luminance {LUMINANCE_LIMIT} % on every preset: {chosen} "
          f"({time.perf_counter() - start:.1f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

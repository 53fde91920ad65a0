"""Bands by measurement: every photometric preset rendered by the tracer on K uniform bands and on the
bands it chooses for the scene (``raytrace.spectral_bands``, column "scene"), against 161 uniform bands
(2.5 nm), the reference. Per preset: the intensity-weighted mean chromaticity xy (the sum of XYZ over
the region, then xy) and the mean luminance over the lit lens (pixels within 1/10 of the reference
render's 99th luminance percentile; the whole image for an unlit preset, where nothing is that bright
apart from the surroundings: the region is then every pixel), and their differences from the
reference: max(|Δx|, |Δy|) and ΔL in %. Limits (issue 32): xy 0.002, luminance 1 %. With ``--time``
each cell also gives the render's CPU time over the 40-band render's, in the same run (the same size).

    .venv/bin/python benchmarks/bench_photometric_bands.py [--ks 40,48,64,81] [--size 96] [--samples 1]
        [--time [--repeats N]] [--only NAME]

The last line says whether the scenes' own bands meet both limits on every preset, and the smallest K of
the list from which every larger uniform K does.
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from core_tracer import load_scene, render_passes  # noqa: E402
from core_tracer.raytrace import spectral  # noqa: E402

REFERENCE_K = 161
XY_LIMIT = 0.002
LUMINANCE_LIMIT = 1.0  # %
LIT_FRACTION = 0.1  # of the 99th luminance percentile: the lit lens
SCENE = None  # in a list of K: the bands the scene chooses


def photometric_presets() -> list[Path]:
    return sorted(p for p in (ROOT / "presets").glob("*.json") if '"photometric"' in p.read_text())


def render_xyz(scene: dict, k: int | None, size: int, samples: int) -> tuple[np.ndarray, float, int]:
    """(XYZ image, CPU seconds, bands traced) of ``scene`` on ``k`` uniform bands (None: the scene's). The
    render's threads are this process's: its CPU time counts them all, steadier than the wall on a
    shared machine."""
    scene = {**scene, "image": {**scene["image"], "width": size, "height": size, "samples": samples}}
    start = time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a coarse K on purpose
        result = render_passes(scene, bands=k)
    return result.image.astype(np.float64), time.process_time() - start, int(result.stats["bands"])


def lit_region(reference: np.ndarray, lit: bool) -> np.ndarray:
    """The lit lens of the reference render (a lit preset), else every pixel."""
    luminance = reference[..., 1]
    if not lit:
        return np.ones(luminance.shape, dtype=bool)
    return luminance >= LIT_FRACTION * np.percentile(luminance, 99.0)


def summary(XYZ: np.ndarray, region: np.ndarray) -> tuple[np.ndarray, float]:
    """(xy of the summed XYZ over ``region``, its mean luminance in cd/m²)."""
    total = XYZ[region].sum(axis=0)
    return total[:2] / total.sum(), float(XYZ[region][:, 1].mean())


def errors(scene: dict, ks: list[int | None], size: int, samples: int, timed: bool = False, repeats: int = 1
           ) -> tuple[dict, float, np.ndarray, int]:
    """{K: (max |Δxy|, |ΔL| %)} against the reference (with ``timed``: {K: (max |Δxy|, |ΔL| %, seconds,
    bands traced)}, the seconds the least of ``repeats`` renders, taken in turn over the K), the
    reference's mean luminance and xy, region pixels."""
    reference = render_xyz(scene, REFERENCE_K, size, samples)[0]
    lit = any(lamp["bulb"]["on"] for lamp in scene["lamps"])
    region = lit_region(reference, lit)
    xy_ref, lum_ref = summary(reference, region)
    out, seconds = {}, {k: float("inf") for k in ks}
    for _ in range(repeats):  # in turn, so that a change of the machine's load falls on every K alike
        for k in ks:
            image, took, traced = render_xyz(scene, k, size, samples)
            seconds[k] = min(seconds[k], took)
            out[k] = (image, traced)
    for k in ks:
        image, traced = out[k]
        xy, lum = summary(image, region)
        errors_k = (float(np.abs(xy - xy_ref).max()), abs(lum / lum_ref - 1.0) * 100.0)
        out[k] = errors_k + (seconds[k], traced) if timed else errors_k
    return out, lum_ref, xy_ref, int(region.sum())


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ks", default="40,48,64,81", help="uniform K to compare with the reference, comma-separated")
    parser.add_argument("--size", type=int, default=96, help="image side in pixels")
    parser.add_argument("--samples", type=int, default=1, help="samples per pixel (the same at every K)")
    parser.add_argument("--time", action="store_true", help="each render's time over the 40-band one's")
    parser.add_argument("--repeats", type=int, default=1, help="renders per K; the time is the least")
    parser.add_argument("--only", default="", help="the presets whose name holds this (default every one)")
    args = parser.parse_args()
    ks = sorted({int(k) for k in args.ks.split(",")} | ({spectral.DEFAULT_BANDS} if args.time else set()))
    columns = [SCENE] + ks
    start = time.perf_counter()
    print(f"against K = {REFERENCE_K}, {args.size}x{args.size} px, {args.samples} sample(s); each cell: max "
          f"|dx|,|dy| and luminance error in %" + (", time / time at K = 40" if args.time else ""))
    width = 26 if args.time else 16
    print(f"{'preset':40s}" + "".join(f"{'K=' + str(k) if k else 'scene':>{width}s}" for k in columns)
          + f"   L({REFERENCE_K}) cd/m2   xy({REFERENCE_K})")
    worst = {k: (0.0, 0.0) for k in columns}
    for path in (p for p in photometric_presets() if args.only in p.stem):
        table, lum, xy, pixels = errors(load_scene(path), columns, args.size, args.samples, timed=True,
                                         repeats=args.repeats)
        base = table[spectral.DEFAULT_BANDS][2] if args.time else None
        cells = ""
        for k, (e_xy, e_l, seconds, traced) in table.items():
            cell = f"{e_xy:.5f} {e_l:5.2f}%"
            if args.time:
                cell += f" {seconds / base:4.2f}x"
            if k is SCENE:
                cell = f"({traced}) " + cell
            cells += f"{cell:>{width}s}"
        print(f"{path.stem:40s}{cells}   {lum:11.4g}   ({xy[0]:.4f}, {xy[1]:.4f})  [{pixels} px]", flush=True)
        for k, (e_xy, e_l, *_) in table.items():
            worst[k] = (max(worst[k][0], e_xy), max(worst[k][1], e_l))
    print(f"{'worst':40s}" + "".join(f"{f'{e_xy:.5f} {e_l:5.2f}%':>{width}s}" for e_xy, e_l in worst.values()))
    meets = {k: worst[k][0] <= XY_LIMIT and worst[k][1] <= LUMINANCE_LIMIT for k in columns}
    good = [k for k in ks if all(meets[j] for j in ks if j >= k)]
    print(f"the scenes' own bands {'meet' if meets[SCENE] else 'miss'} xy {XY_LIMIT} and luminance "
          f"{LUMINANCE_LIMIT} % on every preset; smallest uniform K meeting them: "
          f"{f'K = {good[0]}' if good else f'none of {ks}'} ({time.perf_counter() - start:.1f} s)")
    return 0 if meets[SCENE] else 1  # a scene's own bands that miss the limits fail the run


if __name__ == "__main__":
    raise SystemExit(main())

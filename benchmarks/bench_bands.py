"""How the colour and luminance of each source through each filter converge with the number of bands K.

The tracer carries band means and multiplies them band by band: a bulb's band radiance (its flux
luminance, exact at every K) times the band means of each filter, mirror or paint on the path.
This script does exactly that for every source × filter (and via an aluminium reflector, and
body paint under the sun) at K = 3 … 81 and compares with K = 81, the issue's reference:
the largest |Δx|, |Δy| and the luminance difference in %. The last columns give the smallest K
from which every larger K in the list stays within xy 0.001 and luminance 0.5 % of 81, and the
81-band figures against a 1 nm integral (how far the reference itself is from the continuum), and
T_v, the luminous transmittance of the path (an amber LED behind a red lens passes little).

    .venv/bin/python benchmarks/bench_bands.py [--ks 3,4,5,6,8,10,12,16,20,24,32,40,48,64,81]

It is the first evidence for the choice of K; the final choice needs full renders of the
photometric presets (the tracer's own convergence test).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from core_tracer.photometry import cie, daylight, materials, sources  # noqa: E402
from core_tracer.photometry.bands import Bands  # noqa: E402
from core_tracer.photometry.spectrum import Spectrum  # noqa: E402

XY_LIMIT, Y_LIMIT_PCT = 0.001, 0.5
DEFAULT_KS = (3, 4, 5, 6, 8, 10, 12, 16, 20, 24, 32, 40, 48, 64, 81)
PAINTS = {"red paint": (0.60, 0.05, 0.03), "blue paint": (0.05, 0.12, 0.45), "grey paint": (0.5, 0.5, 0.5)}


def cases() -> list[tuple[str, Spectrum, list[Spectrum]]]:
    """(label, source, [factors along the path]) for every combination measured."""
    out = []
    mirror = materials.mirror_reflectance("aluminium")
    for source_name in sources.SPECTRA:
        source = sources.named_spectrum(source_name)
        for filter_name, cut_on in materials.FILTERS.items():
            out.append((f"{source_name} / {filter_name}", source, [cut_on.spectrum()]))
            out.append((f"{source_name} / Al / {filter_name}", source, [mirror, cut_on.spectrum()]))
    sun = daylight.daylight_spectrum(daylight.SUN_CCT_K)
    for paint_name, rgb in PAINTS.items():
        out.append((f"sun / {paint_name}", sun, [materials.reflectance_spectrum(rgb)]))
    return out


def banded(source: Spectrum, factors: list[Spectrum], bands: Bands) -> np.ndarray:
    """XYZ of the path as the tracer computes it: band means multiplied band by band."""
    radiance = sources.spectral_shape(source, bands)
    for factor in factors:
        radiance = radiance * factor.band_means(bands)
    return radiance @ cie.xyz_matrix(bands)


def continuum(source: Spectrum, factors: list[Spectrum]) -> np.ndarray:
    """XYZ of the same path integrated at 1 nm (source scaled to luminance 1 as in the bands)."""
    product = source.scaled(1.0 / float(cie.spectrum_xyz(source)[1]))
    for factor in factors:
        product = product.times(factor)
    return cie.spectrum_xyz(product)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ks", default=",".join(map(str, DEFAULT_KS)), help="band counts, comma separated")
    args = parser.parse_args(argv)
    ks = sorted({int(k) for k in args.ks.split(",")} | {81})
    start = time.perf_counter()
    shown = [k for k in ks if k in (3, 5, 8, 12, 16, 24, 32, 48)]
    print(f"xy error (max |dx|,|dy|) and luminance error (%) against K = 81; limits xy {XY_LIMIT}, "
          f"luminance {Y_LIMIT_PCT} %")
    header = f"{'source / [mirror] / filter':34s} " + " ".join(f"{'K=' + str(k):>13s}" for k in shown)
    print(header + f" {'K needed':>8s} {'81 vs 1 nm: xy, Y %':>22s} {'T_v':>6s}")
    needed_all = []
    for label, source, factors in cases():
        reference = banded(source, factors, Bands.uniform(81))
        ref_xy = cie.xy(reference)
        errors = {}
        for k in ks:
            xyz = banded(source, factors, Bands.uniform(k))
            errors[k] = (float(np.abs(cie.xy(xyz) - ref_xy).max()), float(100.0 * abs(xyz[1] / reference[1] - 1.0)))
        needed = next((k for i, k in enumerate(ks)
                       if all(errors[j][0] <= XY_LIMIT and errors[j][1] <= Y_LIMIT_PCT for j in ks[i:])), 81)
        exact = continuum(source, factors)
        transmitted = float(exact[1])  # the path's luminous transmittance (source at luminance 1)
        needed_all.append((needed, label, transmitted))
        to_continuum = (float(np.abs(ref_xy - cie.xy(exact)).max()), float(100.0 * abs(reference[1] / exact[1] - 1.0)))
        cells = " ".join(f"{errors[k][0]:6.4f} {errors[k][1]:5.2f}%" if errors[k][1] < 100
                         else f"{errors[k][0]:6.4f}  >99%" for k in shown)
        print(f"{label:34s} {cells} {needed:8d} {to_continuum[0]:10.5f} {to_continuum[1]:9.3f}% {transmitted:6.3f}")
    worst = max(needed_all)
    print(f"\nK needed for every case above: {worst[0]} (set by {worst[1]}); "
          f"{sum(1 for n, _, _ in needed_all if n <= 16)} of {len(needed_all)} cases need 16 or fewer")
    counts = {}
    for n, _, _ in needed_all:
        counts[n] = counts.get(n, 0) + 1
    print("cases by K needed: " + ", ".join(f"K {n}: {c}" for n, c in sorted(counts.items())))
    print(f"({time.perf_counter() - start:.2f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""The Lamp Tracer against Cycles at equal noise (issue 22): one photometric preset rendered by both
on one geometry (the Compare path: ``lamp_addon.compare`` builds the Cycles scene from the design,
as ``tools/compare_preset.py`` does), each renderer's noise measured against itself, and the time
each takes to reach the same noise.

    .venv/bin/python benchmarks/bench_cycles_noise.py [--preset presets/four-lamp-night-lit-photometric.json]
        [--size 256x160] [--tracer-samples 1 4 8 16] [--reference-samples 64] [--cycles-samples 16 64 256]

The metric: the RMS over the lit lens (the pixels whose luminance is at least 1/10 of the 99th
percentile of the tracer's reference) of a render's luminance minus its converged value, relative
to the lit lens's mean luminance.

- the tracer places its samples by the pixel filter on a fixed pattern (no random numbers): its
  error at N samples is measured against its own render at ``--reference-samples`` with every
  sample of every pixel traced;
- Cycles' noise is random: two renders at the same samples with different seeds differ by
  √2 × the noise of one, which needs no converged image (Cycles converges slowly).

Cycles' noise falls as samples^-b (b fitted over ``--cycles-samples``, about 0.5); the samples at
which it equals the tracer's noise at the preset's samples follow, Cycles is rendered there and
both times are compared: wall clock, both on every core (Cycles' CPU device, the tracer's band pool
of worker processes as the command line renders). numpy's BLAS runs single-threaded
(``processes.worker_environment``). Needs the bpy module (the project's .venv).
"""

from __future__ import annotations

import argparse
import math
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # before numpy is imported (docstring)
ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from benchmarks.common import design_in_blender  # noqa: E402
from core_tracer import load_scene, render_passes  # noqa: E402
from core_tracer.raytrace import band_pool  # noqa: E402

REC709_Y = np.array([0.2126, 0.7152, 0.0722])  # luminance of linear Rec.709 (ITU-R BT.709-6, item 3.3)


def lit_lens(reference_y: np.ndarray) -> np.ndarray:
    """The pixels of the lit lens: luminance at least 1/10 of the 99th percentile."""
    return reference_y >= 0.1 * np.percentile(reference_y, 99)


def relative_rms(values: np.ndarray, converged: np.ndarray, mask: np.ndarray) -> float:
    return float(np.sqrt(np.mean((values[mask] - converged[mask]) ** 2)) / converged[mask].mean())


def tracer_y(scene: dict, size: tuple[int, int], samples: int, pool, every_sample: bool = False
             ) -> tuple[np.ndarray, float]:
    start = time.perf_counter()
    result = render_passes(scene, *size, samples=samples, keep_passes=False, pool=pool,
                           adaptive_threshold=0.0 if every_sample else None)
    return result.image[..., 1].astype(np.float64), time.perf_counter() - start  # Y of XYZ, cd/m²


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--preset", default=str(ROOT / "presets" / "four-lamp-night-lit-photometric.json"))
    parser.add_argument("--size", default="256x160")
    parser.add_argument("--tracer-samples", type=int, nargs="+", default=[1, 4, 8, 16])
    parser.add_argument("--reference-samples", type=int, default=64)
    parser.add_argument("--cycles-samples", type=int, nargs="+", default=[16, 64, 256])
    args = parser.parse_args()
    size = tuple(int(v) for v in args.size.lower().split("x"))
    document = load_scene(args.preset)
    if document.get("light_model") != "photometric":
        raise SystemExit(f"{args.preset}: not a photometric preset")
    own_resources = tempfile.mkdtemp(prefix="lamp-blender-user-")
    os.environ.setdefault("BLENDER_USER_RESOURCES", own_resources)
    try:
        import bpy

        from tools import dev_extension

        bpy.ops.wm.read_homefile(use_empty=True)
        with dev_extension.enabled_from_source(bpy, "lamp_styling_dev") as package:
            return _run(bpy, package, args, document, size)
    finally:
        shutil.rmtree(own_resources, ignore_errors=True)


def _run(bpy, package: str, args, document: dict, size: tuple[int, int]) -> int:
    bl_scene, comparison = design_in_blender(bpy, package, document)
    preset_samples = int(document["image"]["samples"])
    pool = band_pool.shared()
    if not pool.ready(60):
        raise SystemExit(f"the band pool did not start: {pool.broken}")
    with comparison.CompareRun(bl_scene, samples=args.cycles_samples[0], resolution=size) as run:
        run.prepare()
        scene = run.scene  # what the tracer traces, as Compare does
        render_passes(scene, 64, 40, keep_passes=False, pool=pool)  # warm up (world image, workers)
        print(f"{Path(args.preset).name} at {size[0]}x{size[1]}, {os.cpu_count()} cores, "
              f"load average {os.getloadavg()[0]:.2f}", flush=True)
        reference, seconds = tracer_y(scene, size, args.reference_samples, pool, every_sample=True)
        mask = lit_lens(reference)
        print(f"tracer reference: {args.reference_samples} samples, every sample, {seconds:.1f} s; lit lens "
              f"{int(mask.sum())} px, mean {reference[mask].mean():.0f} cd/m²", flush=True)
        tracer = {}
        for samples in sorted(set(args.tracer_samples) | {preset_samples}):
            times, image = [], None
            for _ in range(3):
                image, seconds = tracer_y(scene, size, samples, pool)
                times.append(seconds)
            tracer[samples] = (relative_rms(image, reference, mask), min(times))
            print(f"  tracer {samples:4d} samples: noise {tracer[samples][0]:.4f}, {min(times):.2f} s (min of 3)",
                  flush=True)

        def cycles(samples: int, seed: int) -> tuple[np.ndarray, float]:
            bl_scene.cycles.samples = samples
            bl_scene.cycles.seed = seed
            run.start(comparison.CYCLES)
            run.collect()
            return run.images["cycles"][..., :3].astype(np.float64) @ REC709_Y, run.seconds["cycles"]

        def cycles_noise(samples: int) -> tuple[float, float]:
            first, seconds = cycles(samples, 1)
            second, _ = cycles(samples, 2)
            mean = 0.5 * (first + second)
            noise = float(np.sqrt(np.mean((first[mask] - second[mask]) ** 2) / 2.0) / mean[mask].mean())
            print(f"  Cycles {samples:5d} samples: noise {noise:.4f}, {seconds:.2f} s (lit lens mean "
                  f"{mean[mask].mean():.4g} in Cycles' units)", flush=True)
            return noise, seconds

        cycles(1, 0)  # warm up: Cycles' first render compiles its kernels and builds the scene
        measured = {samples: cycles_noise(samples) for samples in args.cycles_samples}
        counts = np.array(sorted(measured), dtype=np.float64)
        noise = np.array([measured[int(c)][0] for c in counts])
        slope, intercept = np.polyfit(np.log(counts), np.log(noise), 1)
        target = tracer[preset_samples][0]
        equal = max(1, int(math.ceil(math.exp((math.log(target) - intercept) / slope))))
        print(f"  Cycles' noise ~ samples^{slope:.2f}; the tracer's at {preset_samples} samples "
              f"({target:.4f}) needs {equal} Cycles samples", flush=True)
        at_equal, cycles_seconds = cycles_noise(equal)
    tracer_seconds = tracer[preset_samples][1]
    print(f"equal noise: tracer {preset_samples} samples {tracer_seconds:.2f} s (noise {target:.4f}), Cycles "
          f"{equal} samples {cycles_seconds:.2f} s (noise {at_equal:.4f}): Cycles takes "
          f"{cycles_seconds / tracer_seconds:.1f}x as long; load average {os.getloadavg()[0]:.2f}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

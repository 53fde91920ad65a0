"""Render every preset with one tree's tracer, or compare two such sets of renders.

    cd <tree> && .venv/bin/python <this file> render OUT      # writes OUT/<preset>-<case>.npy
    cd <tree> && .venv/bin/python <this file> freeform OUT    # the same, presets as meshes (free-form tracer)
    python <this file> compare OLD NEW                       # max |new - old| / peak per preset

The cases: 128x96 at 1 sample and 96x64 at 8 samples (one thread, so bands are traced alike)."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np

CASES = {"128x96-1spp": (128, 96, 1), "96x64-8spp": (96, 64, 8)}


def render(out: Path) -> None:
    sys.path.insert(0, os.getcwd())
    import core_tracer

    out.mkdir(parents=True, exist_ok=True)
    for preset in sorted(Path("presets").glob("*.json")):
        scene = core_tracer.load_scene(str(preset))
        for case, (width, height, samples) in CASES.items():
            image = core_tracer.render_passes(scene, width, height, samples=samples, threads=1,
                                              keep_passes=False).image
            np.save(out / f"{preset.stem}-{case}.npy", image)
        print(preset.stem, flush=True)


FREEFORM_PRESETS = ("paper-baseline", "four-lamp-rear-combination", "four-lamp-day-lit")


def freeform(out: Path) -> None:
    """The round-lens presets as meshes (``benchmarks/bench_freeform.py``'s conversion) through the
    free-form tracer."""
    sys.path.insert(0, os.getcwd())
    sys.path.insert(0, os.path.join(os.getcwd(), "benchmarks"))
    from bench_freeform import four_lamp_design

    from core_tracer.freeform import GeometryCache, render_passes

    out.mkdir(parents=True, exist_ok=True)
    for name in FREEFORM_PRESETS:
        scene, meshes = four_lamp_design(Path("presets") / f"{name}.json")
        cache = GeometryCache()
        for case, (width, height, samples) in CASES.items():
            result = render_passes(scene, meshes, width, height, samples=samples, threads=1, geometry_cache=cache)
            np.save(out / f"freeform-{name}-{case}.npy", result.image)
        print(name, flush=True)


def compare(old: Path, new: Path) -> None:
    worst = 0.0
    for path in sorted(old.glob("*.npy")):
        a = np.load(path).astype(np.float64)
        b = np.load(new / path.name).astype(np.float64)
        peak = max(float(a.max()), 1e-300)
        diff = float(np.abs(b - a).max()) / peak
        worst = max(worst, diff)
        print(f"{path.stem:48s} max|diff|/peak {diff:.3e}{'  identical' if diff == 0 else ''}")
    print(f"worst {worst:.3e}")


if __name__ == "__main__":
    if sys.argv[1] == "render":
        render(Path(sys.argv[2]))
    elif sys.argv[1] == "freeform":
        freeform(Path(sys.argv[2]))
    else:
        compare(Path(sys.argv[2]), Path(sys.argv[3]))

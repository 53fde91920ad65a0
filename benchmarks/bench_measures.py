"""How long do the measures take against one render? For a photometric preset (default: the four-lamp
night preset, tail, stop, turn and reversing lit): one 512x512 render of it at its own samples, then
each part of ``python -m core_tracer measure``: the intensity at every direction the regulation grids
read (UN R148 and FMVSS 108, every function), the grids and ratios, the colours, the homogeneity view,
the (C, gamma) sweep for the IES and EULUMDAT files, the rendered lamp and the page. Target: the whole
measure within 30x the render (issue 23). Also the two intensity estimators' agreement at a few
directions (light tracing against the rendered cone means), with the time of each.

    .venv/bin/python benchmarks/bench_measures.py [--preset P] [--pixel-mm 2] [--replicates 2] [--agreement]
"""

from __future__ import annotations

import math
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from benchmarks.common import arguments  # noqa: E402
from core_tracer.measures import export, intensity, light_tracing, report  # noqa: E402
from core_tracer.raytrace.engine import render_passes  # noqa: E402
from core_tracer.scene import load_scene  # noqa: E402


def main() -> int:
    parser = arguments(__doc__, "four-lamp-night-lit-photometric.json", pixel_mm=2.0, replicates=2)
    parser.add_argument("--agreement", action="store_true", help="also compare the two estimators")
    args = parser.parse_args()
    scene = load_scene(args.preset)

    start = time.perf_counter()
    render_passes(scene, 512, 512, keep_passes=False)
    render = time.perf_counter() - start
    print(f"one 512x512 render at {scene['image']['samples']} samples: {render:.2f} s")

    times = {}
    start = time.perf_counter()
    result = report.measure(scene, pixel_mm=args.pixel_mm, replicates=args.replicates)
    times.update(result.seconds)
    start = time.perf_counter()
    export.measure_distributions(scene, result.functions, pixel_mm=args.pixel_mm, replicates=1)
    times["beam files (C, gamma sweep)"] = time.perf_counter() - start
    start = time.perf_counter()
    picture = report.lamp_picture(scene)
    with tempfile.TemporaryDirectory() as folder:
        report.write_json(result, Path(folder) / "measures.json")
        report.write_page(result, Path(folder) / "measures.png", picture)
    times["rendered lamp and page"] = time.perf_counter() - start
    total = sum(times.values())
    for what, seconds in times.items():
        print(f"  {what:32s} {seconds:7.2f} s  {seconds / render:6.1f} x the render")
    print(f"  {'whole measure':32s} {total:7.2f} s  {total / render:6.1f} x the render (target <= 30 x)")
    print("verdicts:", {k: ("pass" if ok else "FAIL") for k, ok in result.verdicts().items()})

    if args.agreement:
        directions = [(0.0, 0.0), (10.0, 5.0), (-20.0, 0.0), (5.0, -10.0)]
        groups = [[i] for i in range(len(scene["lamps"]))]
        start = time.perf_counter()
        traced = light_tracing.traced_intensities(scene, directions, groups, photons=300_000, cone_deg=3.0, seed=11)
        print(f"light tracing, 300k photons per source and lamp: {time.perf_counter() - start:.1f} s")
        for j, (h, v) in enumerate(directions):
            start = time.perf_counter()
            rendered = intensity.rendered_cone_means(scene, h, v, 3.0, groups, pixel_mm=1.0, replicates=2)
            cells = []
            for g, r in enumerate(rendered):
                t = traced[g][j]
                z = (t.cd - r.cd) / math.hypot(t.stderr, r.stderr)
                cells.append(f"lamp {g}: {r.cd:.2f}±{r.stderr:.2f} / {t.cd:.2f}±{t.stderr:.2f} (z {z:+.1f})")
            print(f"  ({h:g}, {v:g}) rendered / traced cd: " + "; ".join(cells)
                  + f"  [{time.perf_counter() - start:.1f} s]")
    return 0


if __name__ == "__main__":
    sys.exit(main())

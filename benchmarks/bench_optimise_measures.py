"""What one optimisation trial costs when its measures are the photometric report's: the work its
task does on a worker (``core_tracer/optimise/photometric.py``) for each kind of measure, on a
photometric preset (default: the stop lamp), the median of ``--runs`` runs, with the standard errors
the estimators give and the task's memory estimate (what the workers' limits are checked against).

    .venv/bin/python benchmarks/bench_optimise_measures.py [--preset P] [--runs 3] [--photons 20000]
"""

from __future__ import annotations

import os
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from benchmarks.common import arguments  # noqa: E402
from core_tracer.optimise import photometric as P  # noqa: E402
from core_tracer.optimise import search, spec  # noqa: E402


def main() -> int:
    args = arguments(__doc__, "photometric-stop-lamp.json", runs=3, photons=P.DEFAULT_PHOTONS).parse_args()
    cases = {
        "homogeneity, 1 mm front view": [{"measure": "luminance_cv", "pixel_mm": 1.0}],
        "homogeneity, 2 mm front view": [{"measure": "luminance_cv", "pixel_mm": 2.0}],
        f"grid margin + total flux, {args.photons} photons": [{"measure": "grid_min_margin", "photons": args.photons},
                                                              {"measure": "total_flux", "photons": args.photons}],
        "intensity and colour at H-V": [{"measure": "intensity_hv"}, {"measure": "colour_distance"}],
    }
    print(f"{Path(args.preset).name}, load average {os.getloadavg()[0]:.1f}, median of {args.runs} runs")
    for what, objectives in cases.items():
        opt = spec.from_doc({"schema": spec.SCHEMA, "base": args.preset, "objectives": objectives,
                             "parameters": [{"parameter": "cuts.height", "range": [0.5, 2.0]}],
                             "storage": "sqlite:///:memory:"}, str(ROOT))
        scene = opt.base
        seconds, figures = [], None
        for _ in range(args.runs):
            start = time.perf_counter()
            figures = P.figures(scene, opt.request)
            seconds.append(time.perf_counter() - start)
        values, named, _ = search.measure(opt, scene, None, None, figures)
        detail = ", ".join(f"{k} {v:.4g}" for k, v in named.items())
        if figures.grid:
            cd, var = figures.grid[0][(0.0, 0.0)]
            detail += f"; I(H-V) light-traced {cd:.1f} ± {var ** 0.5:.1f} cd"
        if figures.flux:
            lm, var = figures.flux[0]
            detail += f"; flux ± {var ** 0.5:.2f} lm"
        if figures.axis:
            cd, err, _ = figures.axis[0]
            detail += f"; I(H-V) rendered {cd:.1f} ± {err:.1f} cd"
        print(f"{what}: {statistics.median(seconds):.2f} s, task estimate {search.trial_bytes(opt) / 2**20:.0f} MB; "
              f"{detail}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

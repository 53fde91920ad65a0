"""The time of a 6x6 design study: target <= 30 s at 256x256 on a 2-core machine.

    .venv/bin/python benchmarks/bench_study.py [--preset FILE] [--size 256x256] [--workers N]

Varies the refractive index against the cut height (the pair the paper's Figs. 14 and 15 compare)
on the four-lamp rear combination preset, renders the 36 variants with N worker processes (default
one per core) and then with one worker process, and prints both wall times, the parallel speed-up
and the machine's load average (other work on the machine slows both runs). Composing and writing
the contact sheet is timed separately.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from core_tracer.scene.reading import read_json  # noqa: E402
from core_tracer.study import definition as st  # noqa: E402
from core_tracer.study import run as study_run  # noqa: E402
from core_tracer.study import sheet as study_sheet  # noqa: E402

PRESETS = ROOT / "presets"
DEFAULT_PRESET = PRESETS / "four-lamp-rear-combination.json"
FALLBACK_PRESET = PRESETS / "paper-baseline.json"
AXES = ("lens.ior=1.45:1.60:6", "cuts.height=0.5:2.0:6")
TARGET_SECONDS = 30.0


def _load_average() -> str:
    try:
        return ", ".join(f"{x:.2f}" for x in os.getloadavg())
    except OSError:
        return "unknown"


def _timed(study: st.Study, workers: int, threads: int | None = None) -> tuple[float, list]:
    start = time.perf_counter()
    images = study_run.run_study(study, workers, threads=threads)
    return time.perf_counter() - start, images


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--preset", type=Path, help=f"base design (default {DEFAULT_PRESET.name})")
    parser.add_argument("--size", default="256x256", help="variant image size WxH (default 256x256)")
    parser.add_argument("--workers", type=int, default=study_run.default_workers(),
                        help="worker processes of the parallel run (default: one per core)")
    parser.add_argument("--skip-serial", action="store_true", help="only time the parallel run")
    parser.add_argument("--sheet", type=Path, help="also keep the contact sheet here (.png or .exr)")
    args = parser.parse_args()

    preset = args.preset or (DEFAULT_PRESET if DEFAULT_PRESET.exists() else FALLBACK_PRESET)
    w, h = (int(x) for x in args.size.lower().split("x"))
    study = st.Study.build(read_json(preset), [st.parse_vary(a) for a in AXES], (w, h))
    cores = os.cpu_count()
    print(f"study: 6 x 6 = {len(study)} variants of {w}x{h} px, {' x '.join(AXES)}")
    print(f"base: {preset.relative_to(ROOT) if preset.is_relative_to(ROOT) else preset} "
          f"({len(study.base['lamps'])} lamps); {cores} cores; load average before: {_load_average()}")

    parallel, images = _timed(study, args.workers)
    verdict = "meets" if parallel <= TARGET_SECONDS else "misses"
    print(f"{args.workers} workers: {parallel:7.2f} s  ({parallel / len(study) * 1000:.0f} ms per variant; "
          f"{verdict} the {TARGET_SECONDS:.0f} s target)")

    with tempfile.TemporaryDirectory() as folder:
        compose_start = time.perf_counter()
        study_sheet.write_sheet(os.path.join(folder, "sheet.png"), study, images)
        study_sheet.write_sheet(os.path.join(folder, "sheet.exr"), study, images)
        sheet_seconds = time.perf_counter() - compose_start
    if args.sheet is not None:
        study_sheet.write_sheet(args.sheet, study, images)
    layout = study_sheet.layout(study)
    print(f"contact sheet {layout.width}x{layout.height} px composed and written (PNG through AgX + EXR): "
          f"{sheet_seconds:.2f} s")

    if not args.skip_serial:
        serial, _ = _timed(study, 1, threads=1)
        print(f"1 worker:   {serial:7.2f} s  (one process, one thread)")
        print(f"parallel speed-up: {serial / parallel:.2f}x with {args.workers} workers")
    print(f"load average after: {_load_average()}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

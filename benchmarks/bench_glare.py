"""How much does glare cost? For the four-lamp preset with glare on: the median time of the glare
alone (``core_tracer.images.glare.apply``) on its 512x512 render, the energy error per channel
(relative change of each channel's total), and the peak memory the glare allocates (tracemalloc)
against the budget's estimate (``budget.GLARE_BYTES_PER_PIXEL``).

    .venv/bin/python benchmarks/bench_glare.py [--runs 5] [--size 512]
"""

from __future__ import annotations

import statistics
import sys
import time
import tracemalloc
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

import core_tracer  # noqa: E402
from benchmarks.common import arguments  # noqa: E402
from core_tracer import budget  # noqa: E402
from core_tracer.images import glare  # noqa: E402


def main() -> int:
    args = arguments(__doc__, "four-lamp-rear-combination.json", runs=5, size=512).parse_args()

    scene = core_tracer.load_scene(args.preset)
    scene["glare"]["on"] = True
    n = args.size
    start = time.perf_counter()
    image = core_tracer.render(scene, n, n)
    render_seconds = time.perf_counter() - start
    times = []
    for _ in range(args.runs):
        start = time.perf_counter()
        out = glare.apply(image, scene)
        times.append(time.perf_counter() - start)
    before = image.sum(axis=(0, 1), dtype=np.float64)
    after = out.sum(axis=(0, 1), dtype=np.float64)
    tracemalloc.start()
    glare.apply(image, scene)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    median = statistics.median(times)
    print(f"{n}x{n}: render {render_seconds:.3f} s; glare median {median:.3f} s over {args.runs} runs")
    print("energy error per channel (relative): " + ", ".join(f"{e:+.1e}" for e in after / before - 1.0))
    print(f"glare peak {peak / n / n:.0f} bytes/pixel (budget's estimate {budget.GLARE_BYTES_PER_PIXEL})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

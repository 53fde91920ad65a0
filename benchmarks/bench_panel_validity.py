"""What the panel's validity line costs at a redraw (the add-on checks a design again only when it
changed, ``lamp_addon.design.validity``).

    .venv/bin/python benchmarks/bench_panel_validity.py [--runs 50]

Prints the median time of checking the four-lamp preset (valid), of each invalid edit the panel
explains (a shrunk body, a moved or too big bulb, a cut height too deep), of the dependent limits
shown beside the sliders, and of the cache key (the design document as canonical JSON) that every
redraw pays. The bpy side (reading the properties into a document) is not included.
"""

from __future__ import annotations

import argparse
import copy
import json
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from core_tracer.scene.limits import lamp_limits  # noqa: E402
from core_tracer.scene.reading import SceneError, read_json  # noqa: E402
from core_tracer.scene.validate import parse_scene  # noqa: E402

PRESET = ROOT / "presets" / "four-lamp-rear-combination.json"

EDITS = {
    "valid": lambda d: None,
    "shrunk body": lambda d: d["body"].update(size=[80, 30]),
    "bulb moved back": lambda d: d["lamps"][3]["bulb"].update(offset=[0, 30, 0]),
    "bulb moved sideways": lambda d: d["lamps"][3]["bulb"].update(offset=[40, 0, 0]),
    "bulb too big": lambda d: d["lamps"][3]["bulb"].update(radius=30),
    "cut height 100": lambda d: d["lamps"][3]["cuts"].update(height=100),
}


def _median(fn, runs: int) -> float:
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=50)
    args = parser.parse_args()
    base = read_json(PRESET)
    for name, edit in EDITS.items():
        doc = copy.deepcopy(base)
        edit(doc)

        def check(doc=doc):
            try:
                parse_scene(copy.deepcopy(doc))
            except SceneError:
                pass

        print(f"check, {name:20s} {_median(check, args.runs) * 1e3:7.2f} ms")
    scene = parse_scene(base)
    limits = _median(lambda: [lamp_limits(scene, i) for i in range(4)], args.runs)
    print(f"dependent limits, 4 lamps  {limits * 1e3:7.3f} ms")
    print(f"cache key (JSON), 4 lamps  {_median(lambda: json.dumps(scene, sort_keys=True), args.runs) * 1e3:7.3f} ms")


if __name__ == "__main__":
    main()

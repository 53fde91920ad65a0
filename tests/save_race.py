"""A worker process of the concurrent-save test: several designers save the same new preset name at once."""

from __future__ import annotations

import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def designer(folder: str, who: int, rounds: int, barrier, results) -> None:
    sys.path.insert(0, str(ROOT))
    from core_tracer.library import presets as P

    library = P.Library("Team", folder, writable=True)
    base = json.loads((ROOT / "presets" / "paper-baseline.json").read_text())
    for r in range(rounds):
        design = dict(base, author=f"designer {who}")  # each designer's own design
        barrier.wait()  # everyone saves the same new name at the same moment
        try:
            P.save_preset(library, f"Round {r}", design)
            results.put((r, who, "saved"))
        except P.PresetExistsError as e:
            results.put((r, who, f"taken: {e}"))

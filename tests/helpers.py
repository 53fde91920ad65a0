"""What the tests share: the project's folders, the command line in a subprocess, and small scenes
built for the tracer's tests (each isolates one part of the model)."""

from __future__ import annotations

import copy
import json
import subprocess
import sys
from pathlib import Path

from core_tracer.scene.validate import parse_scene

ROOT = Path(__file__).resolve().parent.parent
PRESETS = ROOT / "presets"
BASELINE = PRESETS / "paper-baseline.json"
FOUR_LAMPS = PRESETS / "four-lamp-rear-combination.json"


def run_cli(*args: str | Path, timeout: float = 120) -> subprocess.CompletedProcess:
    """``python -m core_tracer ARGS`` from the repository root, output captured as text."""
    return subprocess.run([sys.executable, "-m", "core_tracer", *map(str, args)], cwd=ROOT,
                          capture_output=True, text=True, timeout=timeout)


def assert_bad_input(proc: subprocess.CompletedProcess, *needles: str) -> str:
    """Exit 2, exactly one line on stderr containing every needle, no traceback."""
    assert proc.returncode == 2, (proc.returncode, proc.stderr)
    assert "Traceback" not in proc.stderr
    lines = proc.stderr.splitlines()
    assert len(lines) == 1, proc.stderr
    for needle in needles:
        assert needle in lines[0], (needle, lines[0])
    return lines[0]


def baseline_doc() -> dict:
    return json.loads(BASELINE.read_text())


def scene_with(**edits) -> dict:
    """The paper baseline with dotted-path edits, e.g. ``scene_with(**{"lamps[0].cuts.height": 0})``."""
    doc = copy.deepcopy(baseline_doc())
    for path, value in edits.items():
        node = doc
        parts = path.replace("]", "").replace("[", ".").split(".")
        for part in parts[:-1]:
            node = node[int(part)] if part.isdigit() else node.setdefault(part, {})
        last = parts[-1]
        if value is None:
            node.pop(last, None)
        else:
            node[last] = value
    return parse_scene(doc)


def flat_lens_on_axis(ior: float = 1.49, absorption=(0.0, 0.0, 0.0), intensity=(8.0, 7.0, 6.0),
                      thickness: float = 3.0) -> dict:
    """A flat lens (no cuts) seen straight on by an orthographic camera: the centre pixel sees the
    bulb at normal incidence, with no lens-surface shading and no reflector in the way."""
    return scene_with(**{
        "camera": {"type": "orthographic", "position": [0, -500, 0], "target": [0, 0, 0], "up": [0, 0, 1],
                   "width": 20.0},
        "image": {"width": 9, "height": 9},
        "lamps[0].cuts.height": 0.0,
        "lamps[0].lens.ior": ior,
        "lamps[0].lens.thickness": thickness,
        "lamps[0].lens.absorption": list(absorption),
        "lamps[0].lens.specular": 0.0,
        "lamps[0].lens.diffuse_color": [0.0, 0.0, 0.0],
        "lamps[0].bulb.intensity": list(intensity),
    })

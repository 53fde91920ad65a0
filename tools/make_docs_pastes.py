"""Make the docs pictures that are several CLI images pasted side by side.

    .venv/bin/python tools/make_docs_pastes.py new-lamp-types [--out docs/new-lamp-types.png]
    .venv/bin/python tools/make_docs_pastes.py light-states [--out docs/images/light-states-tail-only-vs-design.png]

new-lamp-types: the README's row of the lamp types after the paper (square tail lamp, saw-tooth stop
lamp, wrap-around combination, prism-plate stop lamp), each ``python -m core_tracer render PRESET
--width 240 --height 240`` (AgX, automatic exposure), 4 px white gaps.

light-states: docs/measures.md's relight example, one ``states`` run of the four-lamp night
photometric preset at 256², then ``relight --off stop,turn,reversing`` (the tail lamp and the street
light only) and ``relight`` of the design's own states, both at EV100 12, 8 px black gap.

Each command is printed as it runs; the pictures are pasted unchanged (no rescaling).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile

import numpy as np
from PIL import Image

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CLI = (sys.executable, "-m", "core_tracer")

NEW_LAMP_TYPES = ("square-tail-lamp", "sawtooth-stop-lamp", "wrap-around-combination", "prism-plate-stop-lamp")
NEW_LAMP_SIDE = 240
STATES_SIDE = 256
STATES_EV100 = "12"


def _run(*arguments: str) -> None:
    print(" ".join(arguments[1:] if arguments[0] == sys.executable else arguments), flush=True)
    subprocess.run(arguments, cwd=ROOT, check=True)


def paste(paths: list[str], gap: int, gap_value: int, out: str) -> None:
    """The images side by side, ``gap`` pixels of grey ``gap_value`` between them (same heights)."""
    images = [np.asarray(Image.open(p).convert("RGB")) for p in paths]
    height = images[0].shape[0]
    if any(im.shape[0] != height for im in images):
        raise SystemExit(f"make_docs_pastes: images of different heights {[im.shape[0] for im in images]}")
    spacer = np.full((height, gap, 3), gap_value, np.uint8)
    row = [images[0]]
    for im in images[1:]:
        row += [spacer, im]
    Image.fromarray(np.concatenate(row, axis=1)).save(out)
    print(f"wrote {out}")


def new_lamp_types(scratch: str, out: str) -> None:
    made = []
    for name in NEW_LAMP_TYPES:
        path = os.path.join(scratch, f"{name}.png")
        _run(*CLI, "render", f"presets/{name}.json", "-o", path,
             "--width", str(NEW_LAMP_SIDE), "--height", str(NEW_LAMP_SIDE))
        made.append(path)
    paste(made, 4, 255, out)


def light_states(scratch: str, out: str) -> None:
    states = os.path.join(scratch, "night.npz")
    _run(*CLI, "states", "presets/four-lamp-night-lit-photometric.json", "-o", states,
         "--width", str(STATES_SIDE), "--height", str(STATES_SIDE))
    tail_only, design = os.path.join(scratch, "tail-only.png"), os.path.join(scratch, "design.png")
    _run(*CLI, "relight", states, "-o", tail_only, "--off", "stop,turn,reversing", "--ev100", STATES_EV100)
    _run(*CLI, "relight", states, "-o", design, "--ev100", STATES_EV100)
    paste([tail_only, design], 8, 0, out)


PICTURES = {"new-lamp-types": (new_lamp_types, "docs/new-lamp-types.png"),
            "light-states": (light_states, "docs/images/light-states-tail-only-vs-design.png")}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("picture", choices=sorted(PICTURES))
    parser.add_argument("--out", help="the pasted picture (default: its place under docs/)")
    args = parser.parse_args(argv)
    make, default = PICTURES[args.picture]
    out = os.path.abspath(args.out or os.path.join(ROOT, default))
    with tempfile.TemporaryDirectory(prefix="docs-paste-") as scratch:
        make(scratch, out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

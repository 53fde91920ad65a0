"""Regenerate the committed example outputs, on purpose, with one command.

    .venv/bin/python tools/regenerate_outputs.py            # every step
    .venv/bin/python tools/regenerate_outputs.py --list     # the steps and what each writes
    .venv/bin/python tools/regenerate_outputs.py measures-stop measures-tail

Each step is the command a reader of the docs runs (the README's and docs/measures.md's ``measure``,
the picture scripts of tools/), its outputs written where the docs show them. The measure reports are
checked against fresh runs by ``tests/measures/test_committed_reports.py``, which fails when a report
no longer matches within its standard errors: run the step it names, look at the new page, commit.

Pictures no recorded command makes yet are listed in ``NOT_REGENERATED`` with why; a test keeps
every picture under docs/ in one list or the other, so none goes stale unnoticed.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
from dataclasses import dataclass

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PYTHON = sys.executable


@dataclass(frozen=True)
class Step:
    name: str
    command: tuple[str, ...]  # run from the repository root; "{python}" is this interpreter
    outputs: tuple[str, ...]  # files under the repository it writes (a folder: every file in it)
    display: bool = False  # needs a display (xvfb-run) for Blender's GPU drawing
    copies: tuple[tuple[str, str], ...] = ()  # (file in the step's scratch folder "{scratch}", committed path)


def _measure(preset: str, *options: str) -> Step:
    """The measure report of ``preset`` (``options``: the settings docs/measures.md gives it)."""
    folder = f"docs/measures/{preset}"
    return Step(f"measures-{preset.removeprefix('photometric-').removesuffix('-photometric')}",
                ("{python}", "-m", "core_tracer", "measure", f"presets/{preset}.json", "-o", folder, "--exit-zero",
                 *options),
                (folder,))


# The LED presets' lit appearance by night and by day (tools/make_led_appearance_images.py).
LED_APPEARANCE = tuple(f"docs/images/{preset}-{when}.png"
                       for preset in ("led-stop-lamp", "led-light-guide-tail-lamp",
                                      "led-stop-lamp-freeform-lens-photometric", "led-rear-combination-photometric")
                       for when in ("night", "day"))


STEPS: tuple[Step, ...] = (
    _measure("four-lamp-night-lit-photometric"),
    _measure("photometric-stop-lamp"),
    _measure("photometric-tail-lamp"),
    _measure("led-stop-lamp"),
    # The three LED presets' reports without beam files: their (C, γ) grid of 1009 directions had not passed
    # its first direction after 7 minutes on the loaded machine they were made on (the grids, 45-55 directions,
    # take 4-8 minutes).
    _measure("led-light-guide-tail-lamp", "--function", "0=tail", "--pixel-mm", "1", "--no-beam-files"),
    _measure("led-stop-lamp-freeform-lens-photometric", "--function", "0=stop", "--pixel-mm", "1", "--no-beam-files"),
    _measure("led-rear-combination-photometric", "--pixel-mm", "1", "--no-beam-files"),
    Step("led-appearance", ("{python}", "tools/make_led_appearance_images.py"), LED_APPEARANCE),
    Step("measures-panel", ("{python}", "tools/make_measures_panel_image.py"), ("docs/measures-panel.png",)),
    Step("stop-vs-tail", ("{python}", "tools/make_stop_vs_tail.py"), ("docs/images/stop-vs-tail-photometric.png",)),
    Step("lamp-view", ("{python}", "tools/make_lamp_view_image.py"), ("docs/lamp-view-agx-filmic.png",)),
    Step("trust", ("{python}", "tools/make_trust_images.py"),
         ("docs/images/blender-study-sheet-photometric.png", "docs/images/blender-reads-photometric-exr.png"),
         display=True),
    Step("docs-images", ("{python}", "tools/make_docs_images.py"),
         ("docs/viewport-preview-agx.png", "docs/compare-startup-four-lamps.png", "docs/study-ior-cut-height.png"),
         display=True),
    Step("quickstart", ("{python}", "tools/make_quickstart_images.py"),
         tuple(f"docs/quickstart-{n}.png" for n in ("1-first-lamp", "2-preset", "3-compare", "4-study", "5-freeform")),
         display=True),
    Step("optimise-liked-look",
         ("{python}", "-m", "core_tracer", "optimise", "docs/examples/liked-look.optimise.json", "-o", "{scratch}"),
         ("docs/optimise-sheet.png", "docs/optimise-history.png"),
         copies=(("sheet.png", "docs/optimise-sheet.png"), ("history.png", "docs/optimise-history.png"))),
    Step("optimise-even-stop-lamp",
         ("{python}", "-m", "core_tracer", "optimise", "docs/examples/even-stop-lamp.optimise.json", "-o", "{scratch}"),
         ("docs/optimise-photometric-sheet.png", "docs/optimise-photometric-history.png"),
         copies=(("sheet.png", "docs/optimise-photometric-sheet.png"),
                 ("history.png", "docs/optimise-photometric-history.png"))),
)

# Committed pictures without a recorded command (made by hand in a session, or of a past tree).
NOT_REGENERATED: dict[str, str] = {
    "docs/issue24": "before/after of issue 24: needs the tree the issue was filed against "
                    "(tools/make_issue24_images.py BEFORE_TREE)",
    "docs/issue24-exposure-before-after.png": "of issue 24, from a past tree (as docs/issue24)",
    "docs/optimise-photometric-front.png": "no recorded command",
    "docs/blender-photometric-stop-tail.png": "no recorded command",
    "docs/compare-baseline-difference.png": "no recorded command",
    "docs/compare-evening-unlit.png": "no recorded command",
    "docs/compare-photometric-stop-lamp.png": "no recorded command",
    "docs/compare-sawtooth-stop-lamp.png": "no recorded command",
    "docs/cut-types-four-lamps.png": "no recorded command",
    "docs/new-lamp-types.png": "no recorded command",
    "docs/study-lamp-types.png": "no recorded command",
    "docs/study-four-lamp-ior-cut-height.png": "no recorded command",
    "docs/study-sorted-by-measure.png": "no recorded command",
    "docs/images/light-states-tail-only-vs-design.png": "no recorded command",
    "docs/images/led-light-guide-close-up.png": "no recorded command",
    "docs/led-stop-lamp-night.png": "no recorded command",
    **{f"docs/surroundings-{when}-{lit}.png": "no recorded command"
       for when in ("day", "evening", "night") for lit in ("lit", "unlit")},
}


def step(name: str) -> Step:
    for s in STEPS:
        if s.name == name:
            return s
    raise SystemExit(f"regenerate_outputs: {name!r} is not a step; allowed {', '.join(s.name for s in STEPS)}")


def run(s: Step) -> None:
    with tempfile.TemporaryDirectory(prefix="regenerate-") as scratch:
        command = [part.format(python=PYTHON, scratch=os.path.join(scratch, "out")) for part in s.command]
        if s.display and not os.environ.get("DISPLAY"):
            command = ["xvfb-run", "-a", *command]
        print(f"{s.name}: {' '.join(command)}", flush=True)
        subprocess.run(command, cwd=ROOT, check=True)
        for made, committed in s.copies:
            shutil.copyfile(os.path.join(scratch, "out", made), os.path.join(ROOT, committed))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("steps", nargs="*", help="the steps to run (default: every one)")
    parser.add_argument("--list", action="store_true", help="list the steps and what each writes")
    args = parser.parse_args(argv)
    if args.list:
        for s in STEPS:
            print(f"{s.name}: {', '.join(s.outputs)}")
        for path, why in NOT_REGENERATED.items():
            print(f"(not regenerated) {path}: {why}")
        return 0
    for s in [step(n) for n in args.steps] or STEPS:
        run(s)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

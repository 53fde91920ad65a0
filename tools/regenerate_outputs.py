"""Regenerate the committed example outputs, on purpose, with one command.

    .venv/bin/python tools/regenerate_outputs.py            # every step
    .venv/bin/python tools/regenerate_outputs.py --list     # the steps and what each writes
    .venv/bin/python tools/regenerate_outputs.py measures-stop measures-tail
    .venv/bin/python tools/regenerate_outputs.py --into /tmp/try led-stop-lamp-night   # beside, not over

Each step is the command a reader of the docs runs (the README's and docs/measures.md's ``measure``,
the picture scripts of tools/), its outputs written where the docs show them. The measure reports are
checked against fresh runs by ``tests/measures/test_committed_reports.py``, which fails when a report
no longer matches within its standard errors: run the step it names, look at the new page, commit.

Pictures no recorded command makes are listed in ``NOT_REGENERATED`` with why (only issue 24's
before/after, of a past tree); a test keeps every picture under docs/ in one list or the other, so
none goes stale unnoticed. Study sheets are re-run from the study in their own header; the two
renders of a changed preset (the cut types, the light guide close up) from its scene, saved from the
committed picture's header into docs/examples/. ``--into DIR`` writes a step's outputs under DIR
(same relative paths) to try it; a script that writes in place is refused there.
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
    # take 4-8 minutes). Measured again on 2026-12-08 (the free-form lens stop lamp, --pixel-mm 1,
    # --beam-grid 90,10,30, one run, load ~37 on 2 cores): a beam-file direction costs 6.4 s against 8.9 s
    # for one of the 45 intensity directions, so the default grid is ~16 times the intensity grid, ~1.8 h there.
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

def _render(scene: str, out: str, *options: str) -> tuple[str, ...]:
    return ("{python}", "-m", "core_tracer", "render", scene, "-o", out, *options)


def _compare(preset: str, out: str, size: str, samples: int, exposure: str) -> Step:
    return Step(out.removeprefix("docs/").removesuffix(".png"),
                ("{python}", "tools/compare_preset.py", f"presets/{preset}.json", "-o", out, "--size", size,
                 "--samples", str(samples), "--view", "AgX", "--exposure", exposure), (out,))


def _study(sheet: str, *options: str) -> Step:
    """A study sheet re-run from the study in its own header (``study --study SHEET.png``)."""
    return Step(sheet.removeprefix("docs/").removesuffix(".png"),
                ("{python}", "-m", "core_tracer", "study", "--study", sheet, "-o", sheet, *options), (sheet,))


# The road presets by day, evening and night, lit and unlit (README): 320x200, 8 samples, AgX at the
# lit picture's exposure so lit and unlit compare (commit 3a52d7d).
SURROUNDINGS_EXPOSURE = {"day": "-4", "evening": "-3.6", "night": "-4.3"}

STEPS += tuple(
    Step(f"surroundings-{when}-{lit}",
         _render(f"presets/four-lamp-{when}-{lit}.json", f"docs/surroundings-{when}-{lit}.png", "--width", "320",
                 "--height", "200", "--samples", "8", "--exposure", SURROUNDINGS_EXPOSURE[when]),
         (f"docs/surroundings-{when}-{lit}.png",))
    for when in ("day", "evening", "night") for lit in ("lit", "unlit")) + (
    # docs/photometric.md: 320², 4 samples, EV100 15, the preset's glare
    Step("led-stop-lamp-night",
         _render("presets/led-stop-lamp.json", "docs/led-stop-lamp-night.png", "--width", "320", "--height", "320",
                 "--samples", "4", "--ev100", "15"),
         ("docs/led-stop-lamp-night.png",)),
    # docs/photometric.md's command (about a minute under load)
    Step("led-light-guide-night",
         _render("presets/led-light-guide-tail-lamp.json", "docs/images/led-light-guide-tail-lamp-night.png",
                 "--width", "512", "--height", "512", "--samples", "16"),
         ("docs/images/led-light-guide-tail-lamp-night.png",)),
    # the preset seen 70 mm from the LED's end face at EV100 12, 384x256, 8 samples: the scene is the
    # committed picture's header, saved as an example (about 3 minutes under load)
    Step("led-light-guide-close-up",
         _render("docs/examples/led-light-guide-close-up.json", "docs/images/led-light-guide-close-up.png"),
         ("docs/images/led-light-guide-close-up.png",)),
    # docs/photometric.md's commands: a guide lit at both ends, a guide along an arc
    Step("led-light-guide-both-ends",
         _render("docs/examples/led-light-guide-both-ends.json", "docs/images/led-light-guide-both-ends.png",
                 "--width", "512", "--height", "192", "--samples", "16"),
         ("docs/images/led-light-guide-both-ends.png",)),
    Step("led-light-guide-arc",
         _render("docs/examples/led-light-guide-arc.json", "docs/images/led-light-guide-arc.png",
                 "--width", "384", "--height", "256", "--samples", "8"),
         ("docs/images/led-light-guide-arc.png",)),
    # docs/model.md §8.6: fish-eye tail, saw-tooth stop, flutes on the turn lamp; the scene is the
    # committed picture's header, saved as an example
    Step("cut-types-four-lamps",
         _render("docs/examples/cut-types-four-lamps.json", "docs/cut-types-four-lamps.png", "--exposure", "-5.3"),
         ("docs/cut-types-four-lamps.png",)),
    Step("new-lamp-types",
         ("{python}", "tools/make_docs_pastes.py", "new-lamp-types", "--out", "docs/new-lamp-types.png"),
         ("docs/new-lamp-types.png",)),
    Step("light-states",
         ("{python}", "tools/make_docs_pastes.py", "light-states",
          "--out", "docs/images/light-states-tail-only-vs-design.png"),
         ("docs/images/light-states-tail-only-vs-design.png",)),
    Step("optimise-photometric-front",
         ("{python}", "docs/examples/even-stop-lamp-front.py", "--out", "docs/optimise-photometric-front.png"),
         ("docs/optimise-photometric-front.png",)),
    # Compare (Cycles beside the tracer) at the sizes of commit 1eb71d6 and the Cycles samples the
    # committed pictures name; up to a minute of Cycles each
    _compare("paper-baseline", "docs/compare-baseline-difference.png", "240x240", 64, "-4"),
    _compare("four-lamp-evening-unlit", "docs/compare-evening-unlit.png", "256x160", 64, "-2.2"),
    _compare("photometric-stop-lamp", "docs/compare-photometric-stop-lamp.png", "240x240", 64, "-2.6"),
    _compare("sawtooth-stop-lamp", "docs/compare-sawtooth-stop-lamp.png", "320x320", 32, "-5.3"),
    Step("blender-stop-tail", ("{python}", "tools/make_blender_stop_tail.py",
                               "--out", "docs/blender-photometric-stop-tail.png"),
         ("docs/blender-photometric-stop-tail.png",), display=True),
    _study("docs/study-lamp-types.png"),
    _study("docs/study-four-lamp-ior-cut-height.png"),
    _study("docs/study-sorted-by-measure.png"),
    # a free-form design's study: from its preset (its .glb lies beside the preset, not beside the sheet)
    Step("study-freeform-filter-bulb",
         ("{python}", "-m", "core_tracer", "study", "presets/freeform-sculpted-wrap-lamp-photometric.json", "--vary",
          "freeform.parts[].lens.filter=red,amber", "--vary", "freeform.parts[].bulb.state=tail,stop",
          "-o", "docs/study-freeform-filter-bulb.png"), ("docs/study-freeform-filter-bulb.png",)),
)

# Committed pictures without a recorded command.
NOT_REGENERATED: dict[str, str] = {
    "docs/issue24": "before/after of issue 24: needs the tree the issue was filed against "
                    "(tools/make_issue24_images.py BEFORE_TREE)",
    "docs/issue24-exposure-before-after.png": "of issue 24, from a past tree (as docs/issue24)",
    **{f"docs/images/lit-lens-8spp-{when}{kind}.png": "before/after of issue 34's edge samples: the tree "
       "before them beside this one (benchmarks/RESULTS.md, \"Bulb edges\")"
       for when in ("before", "after") for kind in ("", "-luminance")},
}

OUTPUT_FLAGS = ("-o", "--output", "--out")


def step(name: str) -> Step:
    for s in STEPS:
        if s.name == name:
            return s
    raise SystemExit(f"regenerate_outputs: {name!r} is not a step; allowed {', '.join(s.name for s in STEPS)}")


def redirected(s: Step, into: str) -> tuple[list[str], str]:
    """The step's command writing its outputs under ``into`` instead of the repository, and the folder
    its copies go to; a step whose command writes in place (no output argument) is refused."""
    command, placed = [], set()
    for before, part in zip(("",) + s.command, s.command, strict=False):
        if before in OUTPUT_FLAGS and part in s.outputs:
            part = os.path.join(into, part)
            os.makedirs(os.path.dirname(part) or ".", exist_ok=True)
            placed.add(os.path.relpath(part, into))
        command.append(part)
    placed |= {committed for _, committed in s.copies}
    if set(s.outputs) - placed:
        raise SystemExit(f"regenerate_outputs: step {s.name!r} writes {', '.join(sorted(set(s.outputs) - placed))} "
                         f"in place; --into cannot redirect it")
    return command, into


def run(s: Step, into: str | None = None) -> None:
    with tempfile.TemporaryDirectory(prefix="regenerate-") as scratch:
        command, root = redirected(s, os.path.abspath(into)) if into else (list(s.command), ROOT)
        command = [part.format(python=PYTHON, scratch=os.path.join(scratch, "out")) for part in command]
        if s.display and not os.environ.get("DISPLAY"):
            command = ["xvfb-run", "-a", *command]
        print(f"{s.name}: {' '.join(command)}", flush=True)
        subprocess.run(command, cwd=ROOT, check=True)
        for made, committed in s.copies:
            target = os.path.join(root, committed)
            os.makedirs(os.path.dirname(target), exist_ok=True)
            shutil.copyfile(os.path.join(scratch, "out", made), target)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("steps", nargs="*", help="the steps to run (default: every one)")
    parser.add_argument("--list", action="store_true", help="list the steps and what each writes")
    parser.add_argument("--into", metavar="DIR", help="write the outputs under DIR (same relative paths) instead "
                                                      "of over the committed files: to try a step")
    args = parser.parse_args(argv)
    if args.list:
        for s in STEPS:
            print(f"{s.name}: {', '.join(s.outputs)}")
        for path, why in NOT_REGENERATED.items():
            print(f"(not regenerated) {path}: {why}")
        return 0
    for s in [step(n) for n in args.steps] or STEPS:
        run(s, args.into)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

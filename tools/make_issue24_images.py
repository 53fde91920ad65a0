"""The before/after images of issue 24 (docs/issue24/): its walk done from the built extension zip in
Blender's startup file, once as the add-on was when the issue was filed and once for this tree.

    python tools/make_issue24_images.py BEFORE_TREE [--out docs/issue24]

BEFORE_TREE is a checkout of the commit the issue was filed against (``git worktree add /tmp/before24
6bc8af6``, with this tree's ``.venv`` linked into it). Each tree's zip is built by its own
``tools/build-extension`` and walked by ``tools/issue24_walk.py`` in a fresh process under ``xvfb-run``
(the Workbench pictures need a display); the pictures and the recorded reports are then set side by
side, before on the left, after on the right, each with a caption. Text (reports, messages, object
names, panel words) is drawn with OpenImageIO's own font.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path

import numpy as np
import OpenImageIO as oiio

ROOT = Path(__file__).resolve().parent.parent
BACKGROUND = (0.13, 0.13, 0.14)
INK = (0.92, 0.92, 0.92)
FONT = 16
LINE = 20
MARGIN = 12


def build_and_walk(tree: Path, out: Path, work: Path) -> dict:
    env = dict(os.environ, PYTHON=sys.executable)
    env.pop("BLENDER", None)
    built = subprocess.run([str(tree / "tools" / "build-extension"), str(work / "dist")], capture_output=True,
                           text=True, env=env, check=True)
    zip_path = built.stdout.strip().splitlines()[-1]
    walk_env = dict(os.environ, BLENDER_USER_RESOURCES=str(work / "user"))
    subprocess.run(["xvfb-run", "-a", sys.executable, str(ROOT / "tools" / "issue24_walk.py"), zip_path, str(out)],
                   check=True, env=walk_env, cwd=work, stdout=subprocess.DEVNULL)
    return json.loads((out / "walk.json").read_text(encoding="utf-8"))


def read_png(path: Path) -> np.ndarray:
    buf = oiio.ImageBuf(str(path))
    return np.asarray(buf.get_pixels(oiio.FLOAT))[..., :3]


def text_panel(lines: list[str], width: int, height: int | None = None) -> np.ndarray:
    """``lines`` drawn on a dark panel ``width`` px wide (wrapped to it)."""
    chars = max(20, (width - 2 * MARGIN) // 9)
    wrapped = [piece for line in lines for piece in (textwrap.wrap(line, chars) or [""])]
    height = height or 2 * MARGIN + LINE * len(wrapped)
    buf = oiio.ImageBuf(oiio.ImageSpec(width, height, 3, oiio.FLOAT))
    oiio.ImageBufAlgo.fill(buf, BACKGROUND)
    for i, line in enumerate(wrapped):
        oiio.ImageBufAlgo.render_text(buf, MARGIN, MARGIN + FONT + i * LINE, line, FONT, "", INK)
    return np.asarray(buf.get_pixels(oiio.FLOAT))[..., :3]


def stack(*parts: np.ndarray) -> np.ndarray:
    width = max(p.shape[1] for p in parts)
    padded = [np.pad(p, ((0, 0), (0, width - p.shape[1]), (0, 0)), constant_values=BACKGROUND[0]) for p in parts]
    return np.concatenate(padded, axis=0)


def side_by_side(before: np.ndarray, after: np.ndarray, caption_before: list[str],
                 caption_after: list[str]) -> np.ndarray:
    width = max(before.shape[1], after.shape[1], 420)
    cb, ca = text_panel(caption_before, width), text_panel(caption_after, width)
    height = max(cb.shape[0], ca.shape[0])
    cb, ca = text_panel(caption_before, width, height), text_panel(caption_after, width, height)
    left, right = stack(cb, before), stack(ca, after)
    rows = max(left.shape[0], right.shape[0])
    left = np.pad(left, ((0, rows - left.shape[0]), (0, width - left.shape[1]), (0, 0)), constant_values=BACKGROUND[0])
    right = np.pad(right, ((0, rows - right.shape[0]), (0, width - right.shape[1]), (0, 0)),
                   constant_values=BACKGROUND[0])
    gap = np.full((rows, 8, 3), 0.5, np.float32)
    return np.concatenate([left, gap, right], axis=1)


def write_png(path: Path, rgb: np.ndarray) -> None:
    height, width = rgb.shape[:2]
    buf = oiio.ImageBuf(oiio.ImageSpec(width, height, 3, oiio.UINT8))
    buf.set_pixels(oiio.ROI(), np.clip(rgb, 0.0, 1.0).astype(np.float32))
    if not buf.write(str(path)):
        raise OSError(buf.geterror())


def reports_lines(lines: list[str]) -> list[str]:
    return [f"[{len(line) - len('Info: ')} chars] {line}" if line.startswith("Info: ") else line for line in lines]


def compose(before_dir: Path, after_dir: Path, out: Path) -> list[str]:
    b = json.loads((before_dir / "walk.json").read_text(encoding="utf-8"))
    a = json.loads((after_dir / "walk.json").read_text(encoding="utf-8"))
    made = []

    def save(name: str, image: np.ndarray) -> None:
        write_png(out / name, image)
        made.append(name)

    def pictures(name: str, captions: tuple[list[str], list[str]], files: list[str]) -> None:
        before = np.concatenate([read_png(before_dir / f) for f in files], axis=1)
        after = np.concatenate([read_png(after_dir / f) for f in files], axis=1)
        save(name, side_by_side(before, after, *captions))

    def texts(name: str, before: list[str], after: list[str], width: int = 760) -> None:
        save(name, side_by_side(text_panel(before, width), text_panel(after, width), ["BEFORE (6bc8af6)"],
                                ["AFTER (this branch)"]))

    r = (b["renders"], a["renders"])
    off = "1-exposure-tail-after-lamp-off"
    pictures("1-exposure-lamp-off-then-tail.png",
             ([f"BEFORE: lamp off, then tail lamp, F12 at {r[0][off]['exposure']:+.1f} EV"],
              [f"AFTER: same steps, F12 at {r[1][off]['exposure']:+.1f} EV"]),
             ["1-exposure-tail-after-lamp-off.png"])
    pictures("1-exposure-tail-then-stop.png",
             ([f"BEFORE: tail lamp built ({r[0]['1-exposure-tail']['exposure']:+.1f} EV), stop lamp built "
               f"({r[0]['1-exposure-stop']['exposure']:+.1f} EV): Build re-exposed"],
              [f"AFTER: tail lamp ({r[1]['1-exposure-tail']['exposure']:+.1f} EV), stop lamp "
               f"({r[1]['1-exposure-stop']['exposure']:+.1f} EV): one exposure, the stop lamp is brighter"]),
             ["1-exposure-tail.png", "1-exposure-stop.png"])
    texts("1-exposure-from-design-all-off.png", ["Exposure from Design, every bulb off:",
                                                  *b["exposure_from_design_all_off"]],
          ["Exposure from Design, every bulb off:", *a["exposure_from_design_all_off"]])
    vb, va = b["views"]["2-first-look"], a["views"]["2-first-look"]
    after_files = ["2-first-look-solid.png", "2-first-look-rendered.png"]
    if (after_dir / "2-first-look-others-hidden-solid.png").is_file():
        after_files.insert(1, "2-first-look-others-hidden-solid.png")
    before = np.concatenate([read_png(before_dir / f) for f in ("2-first-look-solid.png",
                                                                 "2-first-look-rendered.png")], axis=1)
    after = np.concatenate([read_png(after_dir / f) for f in after_files], axis=1)
    save("2-first-look.png", side_by_side(
        before, after,
        ["BEFORE: first preset applied in the startup file; the 3D View as it is (view distance "
         f"{vb['distance']:.1f} m): Solid | Rendered"],
        [f"AFTER: the same; the 3D View framed on the lamp (view distance {va['distance']:.2f} m): Solid (inside "
         "the startup Cube, which the report names) | Solid after Hide Other Objects | Rendered"]))
    texts("3-one-vocabulary.png",
          ["Cut height 8 mm, F12:", *b["vocabulary"]["f12"], "", "Build:", *b["vocabulary"]["build"], "",
           "Lens radius 80, Build:", *b["vocabulary"]["lens_radius_80_build"]],
          ["Cut height 8 mm, F12:", *a["vocabulary"]["f12"], "", "Build:", *a["vocabulary"]["build"], "",
           "Lens radius 80, Build:", *a["vocabulary"]["lens_radius_80_build"]])
    rb, ra = b["renames"], a["renames"]
    texts("4-renames.png",
          ["Function Stop, Build:", ", ".join(rb["built"]), "",
           "Socket renamed \"My Socket\", Function Turn, Build:", ", ".join(rb["after_turn"]), "",
           "Add Lamp, Build:", ", ".join(rb["after_add"])],
          ["Function Stop, Build:", ", ".join(ra["built"]), "",
           "Socket renamed \"My Socket\", Function Turn, Build:", ", ".join(ra["after_turn"]), "",
           "Add Lamp, Build:", ", ".join(ra["after_add"])])
    texts("5-report-lengths.png",
          ["First Apply Preset in the startup file: one report, which the status bar cuts:",
           *reports_lines(b["first_apply_reports"])],
          ["First Apply Preset: report lines of at most 120 characters, in the Info editor; the last one is "
           "what the status bar shows:", *reports_lines(a["first_apply_reports"])])
    if (before_dir / "6-compare.png").is_file() and (after_dir / "6-compare.png").is_file():
        pictures("6-compare.png", (["BEFORE: Compare with Cycles:", *b["compare_reports"]],
                                   ["AFTER: Compare with Cycles:", *a["compare_reports"]]), ["6-compare.png"])
    fb, fa = r[0]["7-framing-new-design"], r[1]["7-framing-new-design"]
    pictures("7-framing-new-design.png",
             ([f"BEFORE: a new design (Add Lamp, Build), F12 {fb['size'][0]}x{fb['size'][1]}"],
              [f"AFTER: the same, F12 {fa['size'][0]}x{fa['size'][1]} (the body's aspect)"]),
             ["7-framing-new-design.png"])
    fb, fa = r[0]["7-framing-four-lamps"], r[1]["7-framing-four-lamps"]
    pictures("7-framing-four-lamp-preset.png",
             ([f"BEFORE: four-lamp preset, F12 {fb['size'][0]}x{fb['size'][1]}"],
              [f"AFTER: four-lamp preset, F12 {fa['size'][0]}x{fa['size'][1]} (the preset's own image size)"]),
             ["7-framing-four-lamps.png"])
    if "freeform" in a:
        ff = a["freeform"]
        shipped = read_png(after_dir / "10-freeform-f12.png")
        before = (read_png(before_dir / "10-freeform-f12.png") if "freeform" in b
                  else text_panel(["The preset browser lists no free-form example."], shipped.shape[1]))
        save("10-freeform-example.png", side_by_side(
            before, shipped, ["BEFORE: no free-form example ships"],
            [f"AFTER: the free-form example's F12 from the zip; against the zip's command line "
             f"{ff['equal']:.1%} of the pixels equal (largest difference {ff['largest']:g})"]))
    keys = [k for k in a["words"] if k.startswith(("light.", "lamp.", "lens.ior", "lens.absorption", "bulb."))]
    keys += [k for k in b["words"] if k.startswith("lamp.") and k not in keys]

    def word_lines(words: dict) -> list[str]:
        return [f"{k}: \"{words[k][0]}\" - {words[k][1]}" if k in words else f"{k}: (none)" for k in keys]

    texts("8-words.png", ["Field: \"label\" - tooltip", *word_lines(b["words"])],
          ["Field: \"label\" - tooltip", *word_lines(a["words"])], width=900)
    return made


def readme_section(tree: Path) -> list[str]:
    text = (tree / "README.md").read_text(encoding="utf-8").splitlines()
    start = next((i for i, line in enumerate(text) if line.startswith("## A first look")), 0)
    return text[start:start + 44]


def panel_excerpt(path: Path) -> list[str]:
    """The Light, Camera & Image and first lamp's lines of a ``docs/panel.txt``."""
    text = path.read_text(encoding="utf-8").splitlines()
    start = next(i for i, line in enumerate(text) if line.strip().startswith("\u25b8 Light"))
    stop = next(i for i, line in enumerate(text) if line.strip().startswith("\u25b8 Lens"))
    return [line.replace("\u25b8", ">") for line in text[start:stop] if not line.strip().startswith(("Lamp ", "On:"))]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("before_tree", type=Path)
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "issue24")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="issue24-") as tmp:
        work = Path(tmp)
        dirs = {}
        for label, tree in (("before", args.before_tree.resolve()), ("after", ROOT)):
            (work / label).mkdir()
            dirs[label] = work / label / "walk"
            build_and_walk(tree, dirs[label], work / label)
        made = compose(dirs["before"], dirs["after"], args.out)
        before, after = readme_section(args.before_tree), readme_section(ROOT)
        write_png(args.out / "9-readme.png", side_by_side(text_panel(before, 760), text_panel(after, 760),
                                                          ["BEFORE: README, Blender part"],
                                                          ["AFTER: README, Blender part"]))
        made.append("9-readme.png")
        panel = [tree / "docs" / "panel.txt" for tree in (args.before_tree, ROOT)]
        write_png(args.out / "8-panel.png", side_by_side(
            text_panel(panel_excerpt(panel[0]), 560), text_panel(panel_excerpt(panel[1]), 560),
            ["BEFORE: docs/panel.txt (the panel as drawn), Light to Lamps"],
            ["AFTER: the same part"]))
        made.append("8-panel.png")
        shutil.copy(dirs["after"] / "walk.json", args.out / "walk-after.json")
        shutil.copy(dirs["before"] / "walk.json", args.out / "walk-before.json")
    print("\n".join(str(args.out / name) for name in made))


if __name__ == "__main__":
    main()

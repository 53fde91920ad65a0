"""The LED presets lit, by night and by day: ``docs/images/<preset>-night.png`` and ``-day.png``.

    .venv/bin/python tools/make_led_appearance_images.py [PRESET ...]

By night each preset renders as it is (the night world at its lux, EV100 of the preset). By day its
lamps stay lit and the world is the four-lamp day preset's (``presets/four-lamp-day-lit-photometric.json``:
the city world at 20 000 lx, the sun at 100 000 lx, no glare, EV100 14), so a lamp is seen as it is
against daylight. The day twin is written into a temporary folder with the preset's mesh file
beside it (a scene reads only files beside it), and rendered by ``python -m core_tracer render``.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PRESETS = ("led-stop-lamp", "led-light-guide-tail-lamp", "led-stop-lamp-freeform-lens-photometric",
           "led-rear-combination-photometric")
DAY = "four-lamp-day-lit-photometric"
# Render options for a night picture other than the preset's own size (docs/photometric.md's command for it).
NIGHT_OPTIONS = {"led-light-guide-tail-lamp": ("--width", "512", "--height", "512", "--samples", "16")}


def _read(path: str) -> dict:
    with open(path, encoding="utf-8") as f:
        return json.load(f)


def day_twin(scene: dict) -> dict:
    """The scene with the day preset's light, environment, glare and exposure."""
    day = _read(os.path.join(ROOT, "presets", DAY + ".json"))
    twin = dict(scene, light=day["light"], environment=day["environment"])
    twin["glare"] = day.get("glare", {"on": False})
    twin["camera"] = dict(scene["camera"], exposure=day["camera"]["exposure"], ev100=day["camera"]["ev100"])
    return twin


def render(path: str, out: str, *options: str) -> None:
    cmd = [sys.executable, "-m", "core_tracer", "render", path, "-o", out, *options]
    proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    if proc.returncode != 0:
        raise SystemExit(proc.stderr.strip().splitlines()[-1])
    print(proc.stdout.strip() or out)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("presets", nargs="*", default=list(PRESETS), help="preset names (default: the LED presets)")
    args = parser.parse_args(argv)
    images = os.path.join(ROOT, "docs", "images")
    for stem in args.presets:
        path = os.path.join(ROOT, "presets", stem + ".json")
        scene = _read(path)
        render(path, os.path.join(images, f"{stem}-night.png"), *NIGHT_OPTIONS.get(stem, ()))
        with tempfile.TemporaryDirectory(prefix="lamp-day-") as folder:
            mesh_file = scene.get("freeform", {}).get("mesh_file")
            if mesh_file:
                shutil.copy(os.path.join(ROOT, "presets", mesh_file), folder)
            twin = os.path.join(folder, stem + ".json")
            with open(twin, "w", encoding="utf-8") as f:
                json.dump(day_twin(scene), f)
            render(twin, os.path.join(images, f"{stem}-day.png"))
    return 0


if __name__ == "__main__":
    sys.exit(main())

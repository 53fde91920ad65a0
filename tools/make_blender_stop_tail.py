"""Make ``docs/blender-photometric-stop-tail.png``: the photometric stop and tail presets by F12 in Blender.

    xvfb-run -a .venv/bin/python tools/make_blender_stop_tail.py [--out docs/blender-photometric-stop-tail.png]

As a user gets them: the add-on enabled from this source tree in Blender's factory startup file,
*Apply Preset* of each photometric preset, F12 with the Lamp Tracer at the preset's camera (320², EV100
15) under AgX (the user guide's caption; the first lamp of a new file sets the Lamp View, Filmic),
written as Blender writes a still; the two pasted side by side, stop left, tail right.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PRESETS = ("photometric-stop-lamp.json", "photometric-tail-lamp.json")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=os.path.join(ROOT, "docs", "blender-photometric-stop-tail.png"))
    args = parser.parse_args(argv)
    out = os.path.abspath(args.out)
    os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="lamp-stop-tail-"))
    sys.path.insert(0, ROOT)
    import bpy

    from tools import dev_extension
    from tools.make_docs_pastes import paste
    from tools.make_quickstart_images import apply_preset, f12

    with tempfile.TemporaryDirectory(prefix="stop-tail-") as scratch, \
            dev_extension.enabled_from_source(bpy, "lamp_stop_tail"):
        bpy.ops.wm.read_homefile(use_factory_startup=True)
        bl_scene = bpy.context.scene
        bpy.ops.lamp.preset_refresh()
        made = []
        for name in PRESETS:
            apply_preset(bpy, name)
            assert bpy.ops.lamp.build() == {"FINISHED"}
            # the user guide's caption says AgX: a new file's first lamp sets the Lamp View (Filmic)
            bl_scene.view_settings.view_transform = "AgX"
            path = os.path.join(scratch, name.replace(".json", ".png"))
            f12(bpy, bl_scene, path)
            made.append(path)
        paste(made, 0, 0, out)
    return 0


if __name__ == "__main__":
    sys.exit(main())

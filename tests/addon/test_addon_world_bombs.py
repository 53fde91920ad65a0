"""Environment-image bombs in a preset library, in Blender: Refresh (the thumbnail thread), Apply
Preset and Build never load an image past the memory budget (issue 21).

A teammate's preset names an image beside it that declares far more than it holds (a 93-byte .hdr
declaring 30000x15000 px, one of 100000x100000, a negative size, an OpenEXR of 1 x 1 px whose tiles
are declared 33 million px wide), or a real 8192 x 4096 OpenEXR of 214 KB, which is read once,
within what its header was counted for. Each action's peak resident memory is measured (the
process's high-water mark, reset through /proc/self/clear_refs before it) and printed
(``pytest -s``); a bomb that reached OpenImageIO's or Blender's reader would take gigabytes.
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

import numpy as np
import pytest
from helpers import BASELINE, status_bytes, whole_report, write_tile_bomb

pytestmark = [pytest.mark.blender, pytest.mark.slow,
              pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")]

MIB = 2**20
HDR_HEAD = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n"
BOMBS = {  # file: (bytes, what the refusal says)
    "wide.hdr": (HDR_HEAD + b"-Y 15000 +X 30000\n" + bytes(38), "declares 30000x15000 px"),
    "huge.hdr": (HDR_HEAD + b"-Y 100000 +X 100000\n", "declares 100000x100000 px"),
    "negative.hdr": (HDR_HEAD + b"-Y -5 +X 100\n", "its header declares 100x-5 px"),
}
BIG = (8192, 4096)  # a real image at the size read without averaging: counted, read once
# What a bomb may grow the process by: the tracer's thumbnail or preview renders and Blender's own
# bookkeeping; a bomb read even in part takes gigabytes (30000 x 15000 float RGB: 5.4 GB).
BOMB_GROWTH = 300 * MIB


class Peak:
    """The growth of the process's peak resident memory over what it held at the start of a block."""

    def __enter__(self):
        self.start = status_bytes("VmRSS")
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
        return self

    def __exit__(self, *exc):
        self.grown = status_bytes("VmHWM") - self.start


def _big_exr(oiio, path: Path) -> None:
    """An 8192 x 4096 OpenEXR of a sky with one bright sun (zip: a few hundred kB)."""
    w, h = BIG
    spec = oiio.ImageSpec(w, h, 3, oiio.HALF)
    spec.attribute("compression", "zip")
    out = oiio.ImageOutput.create(str(path))
    assert out.open(str(path), spec)
    rows = np.linspace(1.0, 0.2, h, dtype=np.float32)[:, None, None] * np.ones((1, w, 3), np.float32)
    rows[h // 4:h // 4 + 8, w // 3:w // 3 + 8] = 5000.0
    assert out.write_image(rows)
    out.close()


@pytest.fixture
def bomb_library(tmp_path, addon):
    """A read-only library folder: a preset beside each bomb image and the big image."""
    import bpy
    import OpenImageIO as oiio

    folder = tmp_path / "team"
    folder.mkdir()
    doc = json.loads(BASELINE.read_text())
    images = {name: said for name, (data, said) in BOMBS.items()}
    for name, (data, _) in BOMBS.items():
        (folder / name).write_bytes(data)
    write_tile_bomb(folder / "tiles.exr")
    images["tiles.exr"] = "would take"
    _big_exr(oiio, folder / "big.exr")
    images["big.exr"] = None
    for name in images:
        preset = {**doc, "name": f"Sky {name}", "environment": {"world": "file", "file": name, "strength": 1.0}}
        (folder / f"sky-{Path(name).stem}.json").write_text(json.dumps(preset))
    prefs = bpy.context.preferences.addons[addon].preferences
    item = prefs.library_folders.add()
    item.name, item.directory, item.read_only = "Bombs", str(folder), False
    yield folder, images
    index = next(i for i, it in enumerate(prefs.library_folders) if it.name == "Bombs")
    prefs.library_folders.remove(index)


def _select(wm, file_name: str) -> None:
    for i, item in enumerate(wm.lamp_presets):
        if os.path.basename(item.file) == file_name:
            wm.lamp_presets_index = i
            return
    raise AssertionError(f"{file_name} is not listed")


def _blender_images_of(folder: Path) -> list[str]:
    import bpy

    return [im.filepath for im in bpy.data.images if Path(bpy.path.abspath(im.filepath)).parent == folder]


def test_refresh_apply_and_build_never_load_a_bomb(lamp_addon, addon_core, bl_scene, bomb_library, capsys):
    import bpy

    folder, images = bomb_library
    world_image = addon_core.raytrace.world_image
    budget = addon_core.budget
    lib = lamp_addon.presets.library
    figures = []

    # Refresh: the thumbnail thread renders every preset of the library with the tracer.
    with Peak() as refreshed:
        assert bpy.ops.lamp.preset_refresh() == {"FINISHED"}
        lib.thumbnails().wait(timeout=600)
    figures.append(("Refresh (6 thumbnails)", refreshed.grown))
    thumbs = lib.thumbnails()
    for name, said in images.items():
        entry = lib.listing().entry(str(folder / f"sky-{Path(name).stem}.json"))
        path = thumbs.path(entry)
        if said is None:
            assert path not in thumbs.errors and os.path.isfile(path), thumbs.errors.get(path)
        else:
            assert said in thumbs.errors[path] and "\n" not in thumbs.errors[path], thumbs.errors.get(path)
    big = world_image.peak_bytes(*world_image.header(str(folder / "big.exr")))
    assert refreshed.grown <= budget.BASE_BYTES + big, refreshed.grown / MIB  # the big image once, as counted

    wm = bpy.context.window_manager
    bl_scene.lamp_design.auto_build = True
    for name, said in images.items():
        _select(wm, f"sky-{Path(name).stem}.json")
        with Peak() as applied:
            if said is None:
                assert bpy.ops.lamp.preset_apply() == {"FINISHED"}
            else:
                capsys.readouterr()
                with pytest.raises(RuntimeError) as err:
                    bpy.ops.lamp.preset_apply()
                # one line in the status bar; the whole refusal in the Info editor
                assert said in whole_report(str(err.value), capsys.readouterr().out), name
        figures.append((f"Apply {name}", applied.grown))
        with Peak() as built:
            if said is None:
                assert bpy.ops.lamp.build() == {"FINISHED"}
        figures.append((f"Build after {name}", built.grown))
        limit = budget.BASE_BYTES + big if said is None else BOMB_GROWTH
        assert applied.grown <= limit and built.grown <= limit, (name, applied.grown / MIB, built.grown / MIB)
    # A bomb picked in the Surroundings panel (a user's own image, any folder), then Build.
    env = bl_scene.lamp_design.environment
    for name, said in images.items():
        if said is None:
            continue
        env.world, env.file = "file", str(folder / name)
        with Peak() as built:
            result = bpy.ops.lamp.build()
        figures.append((f"Build with {name} picked", built.grown))
        assert result == {"FINISHED"} and built.grown <= BOMB_GROWTH, (name, result, built.grown / MIB)
    # Blender's own reader never had a bomb: only the big image is an image data-block.
    assert [Path(p).name for p in _blender_images_of(folder)] in ([], ["big.exr"])
    with capsys.disabled():
        print("\nworld-image bombs in Blender, peak resident memory growth:")
        for what, grown in figures:
            print(f"  {what:<30} {grown / MIB:8.0f} MB")

"""A Blender build that cannot import OpenImageIO: each feature that needs it says so once, in
words, and the rest works (no traceback, no thumbnail "being made" for ever).

The missing module is simulated the way Python sees it: ``sys.modules["OpenImageIO"] = None``
makes every ``import OpenImageIO`` raise ``ImportError`` (and ``expose_bundled_modules`` cannot
bring it back).
"""

from __future__ import annotations

import sys
from types import SimpleNamespace

import numpy as np
import pytest
from helpers import BASELINE, scene_with
from study_axes import one_axis

pytestmark = pytest.mark.blender


@pytest.fixture
def no_openimageio(monkeypatch):
    monkeypatch.setitem(sys.modules, "OpenImageIO", None)


def _design(lamp_addon, bl_scene) -> None:
    scene = scene_with(image={"width": 24, "height": 16})
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    lamp_addon.design.lamp_camera.ensure_lamp_camera(bl_scene, frame=False)


def test_openimageio_is_missing_as_blender_sees_it(lamp_addon, no_openimageio):
    assert not lamp_addon.image_view.openimageio_available()
    with pytest.raises(ImportError):
        import OpenImageIO  # noqa: F401


def test_compare_runs_and_says_once_that_it_cannot_save(lamp_addon, bl_scene, tmp_path, no_openimageio, capfd):
    import bpy

    _design(lamp_addon, bl_scene)
    out = tmp_path / "compare.png"
    capfd.readouterr()
    assert bpy.ops.lamp.compare_cycles(samples=1, filepath=str(out)) == {"FINISHED"}
    printed = capfd.readouterr()
    text = printed.out + printed.err
    assert "Traceback" not in text
    said = [line for line in text.splitlines() if line.startswith("Warning: ")]  # the one-line reports
    assert sum("no OpenImageIO" in line for line in said) == 1 and "compare.png not written" in text
    assert not out.exists() and list(tmp_path.iterdir()) == []
    # The comparison itself is there, labelled with the bitmap font.
    shown = lamp_addon.image_view.image_to_array(bpy.data.images["Lamp Compare"])
    strip = lamp_addon.convert.sheet.label_height(16)
    assert shown.shape == (16 + strip, 3 * 24 + 2 * 2, 3) and shown[:strip].max() > 0.5  # tracer, Cycles, difference


@pytest.mark.slow
def test_study_runs_and_save_sheet_says_why_not(lamp_addon, bl_scene, tmp_path, no_openimageio):
    import bpy

    _design(lamp_addon, bl_scene)
    one_axis(bl_scene.lamp_study, width=24, height=24, workers=0)
    assert bpy.ops.lamp.study_run() == {"FINISHED"}  # composed in numpy, labels in the bitmap font
    image = bpy.data.images["Lamp Study"]
    assert lamp_addon.image_view.image_to_array(image).max() > 0
    path = tmp_path / "sheet.png"
    with pytest.raises(RuntimeError) as error:  # the operator's ERROR report, as a script sees it
        bpy.ops.lamp.study_save_sheet(filepath=str(path))
    message = str(error.value)
    assert "Sheet not saved" in message and "no OpenImageIO" in message and "Traceback" not in message
    assert not path.exists()


def test_thumbnails_say_why_they_are_missing_instead_of_being_made(lamp_addon, tmp_path, no_openimageio):
    library = lamp_addon.presets.library
    P = lamp_addon.presets.library.P
    folder = tmp_path / "lib"
    folder.mkdir()
    (folder / "red.json").write_text(BASELINE.read_text())
    entries, warnings = P.list_presets([P.Library("lib", str(folder), writable=True)])
    assert warnings == [] and len(entries) == 1
    thumbs = library.Thumbnails()
    try:
        thumbs.request(entries)
        assert not thumbs.busy()  # nothing queued that could never finish
        reason = thumbs.missing_reason(entries[0].file)
        assert reason.startswith("No thumbnail") and "no OpenImageIO" in reason
        thumbs.request(entries)  # listed again: still one reason, not a second attempt
        assert len(thumbs.errors) == 1
        # The panel shows the reason, not "Thumbnail being made...".
        labels = _draw_selected(lamp_addon, thumbs, entries[0])
        assert any("no OpenImageIO" in text and icon == "ERROR" for text, icon in labels)
        assert not any("being made" in text for text, _ in labels)
    finally:
        thumbs.close()
    assert not (folder / ".thumbnails").exists() or not any((folder / ".thumbnails").iterdir())


class _Labels:
    """Records the labels a draw function makes (every other layout call is accepted and ignored)."""

    def __init__(self, log):
        self.log = log

    def label(self, *, text="", icon="NONE", **_kw):
        self.log.append((text, icon))

    def __getattr__(self, name):
        return lambda *args, **kw: _Labels(self.log) if name in ("box", "column", "row") else SimpleNamespace()


def _draw_selected(lamp_addon, thumbs, entry) -> list[tuple[str, str]]:
    import bpy

    wm = bpy.context.window_manager
    wm.lamp_presets.clear()
    item = wm.lamp_presets.add()
    item.name, item.file = entry.name, entry.file
    wm.lamp_presets_index = 0
    panel = lamp_addon.presets.panel
    original = panel.library.thumbnails
    panel.library.thumbnails = lambda: thumbs
    try:
        log: list[tuple[str, str]] = []
        panel.LAMP_PT_presets._draw_selected(SimpleNamespace(window_manager=wm), _Labels(log))
        return log
    finally:
        panel.library.thumbnails = original
        wm.lamp_presets.clear()


def test_display_without_openimageio_is_standard_and_says_so(addon_core, no_openimageio):
    view = addon_core.images.display.view_transform("AgX")
    assert view.view == "Standard" and "OpenImageIO is not installed" in view.note
    shown = view.to_display(np.full((1, 1, 3), 0.18, np.float32))
    assert np.allclose(shown, addon_core.images.display.srgb_encode(0.18), atol=1e-6)

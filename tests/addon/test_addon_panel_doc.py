"""``docs/panel.txt`` is what ``tools/make_docs_images.py --panel-only`` writes today, so it cannot go
stale: a change to a panel fails here until the file is written again."""

from __future__ import annotations

import os
import sys

import pytest

pytestmark = pytest.mark.blender


@pytest.mark.slow
def test_docs_panel_txt_is_up_to_date(lamp_addon, addon, repo_root):
    from tools import make_docs_images

    user, _why = lamp_addon.presets.library.user_library()  # presets other tests saved are not the doc's
    if user is not None:
        for name in os.listdir(user.folder):
            if name.endswith(".json"):
                os.remove(os.path.join(user.folder, name))
    core = sys.modules[f"{addon}.core_tracer"]
    bl_scene = make_docs_images.startup_with_preset(__import__("bpy"), core, lamp_addon)
    text = make_docs_images.panel_outline(__import__("bpy"), lamp_addon, bl_scene)
    shipped = (repo_root / "docs" / "panel.txt").read_text(encoding="utf-8")
    assert text == shipped, ("docs/panel.txt is stale: run "
                             "`xvfb-run -a .venv/bin/python tools/make_docs_images.py --panel-only`")
    for words in ("Light Gathering: reflector", "▸ Glare  (closed at first)   [header: Glare: False]",
                  "[Hide Other Objects]", "Follow Environment Color", "▸ Free-form Parts",
                  "▸ Bulb\n      Radius (mm): 8.0\n      At most 10.12 mm where the bulb sits  (INFO)\n"
                  "      Position (mm)"):
        assert words in text, words

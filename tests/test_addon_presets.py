"""The preset browser in Blender: sharing through a folder, safe saving, hostile folders, all-or-nothing apply."""

from __future__ import annotations

import json
import os
import shutil
import time
from pathlib import Path

import pytest
from hostile_presets import make_hostile_folder

pytestmark = pytest.mark.blender

BUILTIN = Path(__file__).resolve().parent.parent / "presets"


@pytest.fixture
def browser(lamp_addon):
    """The add-on's preset modules, with the user's own library emptied before the test."""
    lib = lamp_addon.preset_library
    user, why = lib.user_library()
    assert user is not None, why
    for name in os.listdir(user.folder):
        path = os.path.join(user.folder, name)
        shutil.rmtree(path) if os.path.isdir(path) else os.unlink(path)
    return lamp_addon


@pytest.fixture
def add_library(addon):
    """Add folders to the add-on preferences (as a designer does) and take them away afterwards."""
    import bpy

    prefs = bpy.context.preferences.addons[addon].preferences
    added = []

    def add(folder: Path, name: str, read_only: bool = False) -> str:
        item = prefs.library_folders.add()
        item.name, item.directory, item.read_only = name, str(folder), read_only
        added.append(item.name)
        return str(folder)

    yield add
    for name in added:
        index = next(i for i, item in enumerate(prefs.library_folders) if item.name == name)
        prefs.library_folders.remove(index)


def refresh():
    import bpy

    assert bpy.ops.lamp.preset_refresh() == {"FINISHED"}
    return bpy.context.window_manager


def select(wm, file_name: str, library: str | None = None) -> None:
    for i, item in enumerate(wm.lamp_presets):
        if os.path.basename(item.file) == file_name and (library is None or item.library == library):
            wm.lamp_presets_index = i
            return
    raise AssertionError(f"{file_name} is not listed: {[i.file for i in wm.lamp_presets]}")


def leaves(node, prefix: str = "") -> dict:
    if isinstance(node, dict):
        out = {}
        for k, v in node.items():
            out.update(leaves(v, f"{prefix}.{k}" if prefix else k))
        return out
    if isinstance(node, list) and node and isinstance(node[0], dict):
        out = {}
        for i, v in enumerate(node):
            out.update(leaves(v, f"{prefix}[{i}]"))
        return out
    return {prefix: node}


def test_preferences_belong_to_the_extension(addon, browser):
    import bpy

    prefs = bpy.context.preferences.addons[addon].preferences
    assert type(prefs).bl_idname == addon
    assert hasattr(prefs, "library_folders")


def test_libraries_are_builtin_user_and_preferences(browser, add_library, tmp_path):
    team = add_library(tmp_path, "Team")
    wm = refresh()
    listing = browser.preset_library.listing()
    assert [lib.name for lib in listing.libraries] == ["Built-in", "My Presets", "Team"]
    assert [lib.writable for lib in listing.libraries] == [False, True, True]
    assert listing.libraries[2].folder == team
    assert listing.notes == [] and listing.warnings == []
    assert len(wm.lamp_presets) == len(list(BUILTIN.glob("*.json")))
    assert all(item.library == "Built-in" and not item.writable for item in wm.lamp_presets)


def test_two_designers_share_a_folder(browser, add_library, bl_scene, tmp_path, addon_core):
    import bpy

    (tmp_path / "share").mkdir()
    team = add_library(tmp_path / "share", "Team share")
    props = browser.properties

    # Alice starts from the amber study, changes it and saves it to the team's folder.
    wm = refresh()
    select(wm, "paper-lens-color.json")
    assert bpy.ops.lamp.preset_apply() == {"FINISHED"}
    design = bl_scene.lamp_design
    design.lamps[0].lens.ior = 1.55
    design.lamps[0].cuts.pitch = 7.5
    design.body.color = (0.2, 0.3, 0.4)
    design.lamps[0].bulb.offset = (0.5, 2.25, -0.125)
    alice = props.design_to_scene(bl_scene)
    assert bpy.ops.lamp.preset_save(name="Amber turn (Alice)", author="Alice", tags="amber, turn",
                                    description="Try it with your cuts", library=team) == {"FINISHED"}
    saved = Path(team) / "amber-turn-alice.json"
    assert saved.is_file()
    thumbs = browser.preset_library.thumbnails()
    thumbs.wait()
    entry = browser.preset_library.listing().entry(str(saved))
    thumb = Path(team) / ".thumbnails" / f"amber-turn-alice-{entry.digest}.png"
    assert thumb.is_file() and thumbs.errors == {}

    # Bob, in a new file, lists the folder: he sees the preset with its thumbnail and applies it.
    bpy.ops.wm.read_homefile(use_empty=True)
    scene = bpy.context.scene
    assert scene.lamp_design.name != "Amber turn (Alice)"
    wm = refresh()
    assert not thumbs.busy()  # the thumbnail beside the preset is used, not made again
    select(wm, "amber-turn-alice.json", "Team share")
    item = wm.lamp_presets[wm.lamp_presets_index]
    assert (item.name, item.author, item.tags) == ("Amber turn (Alice)", "Alice", "amber, turn")
    assert thumbs.previews[str(thumb)].image_size[:] == (96, 96)
    assert bpy.ops.lamp.preset_apply() == {"FINISHED"}
    bob = props.design_to_scene(scene)
    expected = dict(alice, name="Amber turn (Alice)", author="Alice", tags=["amber", "turn"],
                    description="Try it with your cuts")
    assert leaves(bob) == leaves(expected)
    assert leaves(addon_core.presets.load_preset(saved)) == leaves(expected)


def test_overwrite_is_refused_without_confirmation(browser, add_library, bl_scene, tmp_path):
    import bpy

    team = add_library(tmp_path, "Team")
    select(refresh(), "paper-baseline.json")
    bpy.ops.lamp.preset_apply()
    assert bpy.ops.lamp.preset_save(name="Red tail", library=team) == {"FINISHED"}
    path = tmp_path / "red-tail.json"
    before = path.read_bytes()
    bl_scene.lamp_design.lamps[0].lens.ior = 1.6
    with pytest.raises(RuntimeError, match="exists already"):
        bpy.ops.lamp.preset_save(name="Red tail", library=team)
    assert path.read_bytes() == before
    assert bpy.ops.lamp.preset_save(name="Red tail", library=team, overwrite=True) == {"FINISHED"}
    assert json.loads(path.read_text())["lamps"][0]["lens"]["ior"] == pytest.approx(1.6)
    assert sorted(p.name for p in tmp_path.iterdir() if not p.name.startswith(".")) == ["red-tail.json"]


def test_an_invalid_design_is_not_saved(browser, add_library, tmp_path):
    import bpy

    team = add_library(tmp_path, "Team")
    refresh()  # the empty file's design has no lamp
    with pytest.raises(RuntimeError, match="Preset not saved: lamps: has 0 items; allowed 1 to 4"):
        bpy.ops.lamp.preset_save(name="Nothing", library=team)
    assert list(tmp_path.iterdir()) == []


def test_hostile_folder_is_listed_with_warnings(browser, add_library, tmp_path):
    good, bad = make_hostile_folder(tmp_path / "hostile")
    add_library(tmp_path / "hostile", "Hostile", read_only=True)
    start = time.perf_counter()
    wm = refresh()
    assert time.perf_counter() - start < 0.1 * (len(good) + len(bad) + 12)
    listing = browser.preset_library.listing()
    assert {os.path.basename(i.file) for i in wm.lamp_presets if i.library == "Hostile"} == good
    assert len(listing.warnings) == len(bad)
    texts = [str(w) for w in listing.warnings]
    printable = browser.preset_library.P.printable
    for name, needles in bad.items():
        (text,) = [t for t in texts if f"/hostile/{printable(name)}:" in t]
        for needle in needles:
            assert needle in text, (name, needle, text)


def _design(props, bl_scene) -> dict:
    return leaves(props.design_to_scene(bl_scene))


def test_apply_is_all_or_nothing(browser, add_library, bl_scene, tmp_path):
    import bpy

    props = browser.properties
    team = Path(add_library(tmp_path, "Team"))
    doc = json.loads((BUILTIN / "paper-baseline.json").read_text())
    # Valid for the tracer, but a tag with a comma cannot be kept in the comma-separated tag field.
    (team / "comma-tag.json").write_text(json.dumps({**doc, "tags": ["red", "tail, stop"]}))
    (team / "changed-after-listing.json").write_text(json.dumps(doc))
    (team / "deleted-after-listing.json").write_text(json.dumps(doc))
    wm = refresh()
    select(wm, "paper-lens-color.json")
    bpy.ops.lamp.preset_apply()
    before = _design(props, bl_scene)

    select(wm, "comma-tag.json")
    with pytest.raises(RuntimeError, match="design is unchanged.*tags"):
        bpy.ops.lamp.preset_apply()
    assert _design(props, bl_scene) == before

    (team / "changed-after-listing.json").write_text(json.dumps(doc).replace('"ior": 1.49', '"ior": 0.5'))
    select(wm, "changed-after-listing.json")
    with pytest.raises(RuntimeError, match=r"lamps\[0\]\.lens\.ior: 0.5 is out of range"):
        bpy.ops.lamp.preset_apply()
    assert _design(props, bl_scene) == before

    select(wm, "deleted-after-listing.json")
    (team / "deleted-after-listing.json").unlink()
    with pytest.raises(RuntimeError, match="cannot read"):
        bpy.ops.lamp.preset_apply()
    assert _design(props, bl_scene) == before

    with pytest.raises(RuntimeError, match="Not a preset of the listed libraries"):
        bpy.ops.lamp.preset_apply(file=str(BUILTIN.parent / "pyproject.toml"))
    assert _design(props, bl_scene) == before
    assert "UNDO" in bpy.types.LAMP_OT_preset_apply.bl_options


def test_read_only_libraries_refuse_changes(browser, add_library, tmp_path):
    import bpy

    (tmp_path / "a.json").write_text((BUILTIN / "paper-baseline.json").read_text())
    add_library(tmp_path, "Reference", read_only=True)
    wm = refresh()
    for library in ("Built-in", "Reference"):
        select(wm, "paper-baseline.json" if library == "Built-in" else "a.json", library)
        assert not bpy.ops.lamp.preset_delete.poll()
        assert not bpy.ops.lamp.preset_rename.poll()
        assert bpy.ops.lamp.preset_apply.poll()
    assert [lib.name for lib in browser.preset_library.writable_libraries()] == ["My Presets"]


def test_rename_and_delete(browser, add_library, bl_scene, tmp_path):
    import bpy

    team = add_library(tmp_path, "Team")
    select(refresh(), "paper-baseline.json")
    bpy.ops.lamp.preset_apply()
    bpy.ops.lamp.preset_save(name="First", library=team)
    wm = bpy.context.window_manager
    assert os.path.basename(wm.lamp_presets[wm.lamp_presets_index].file) == "first.json"
    assert bpy.ops.lamp.preset_rename(new_name="Second") == {"FINISHED"}
    assert os.path.basename(wm.lamp_presets[wm.lamp_presets_index].file) == "second.json"
    assert sorted(p.name for p in tmp_path.glob("*.json")) == ["second.json"]
    assert bpy.ops.lamp.preset_delete() == {"FINISHED"}
    assert list(tmp_path.glob("*.json")) == []
    assert all(item.library != "Team" for item in wm.lamp_presets)


def test_export_then_import(browser, bl_scene, tmp_path, addon_core):
    import bpy

    props = browser.properties
    wm = refresh()
    select(wm, "four-lamp-rear-combination.json")
    bpy.ops.lamp.preset_apply()
    four = _design(props, bl_scene)
    out = tmp_path / "exported.json"
    assert bpy.ops.lamp.preset_export(filepath=str(out)) == {"FINISHED"}
    assert out.read_text() == addon_core.scene_to_json(props.design_to_scene(bl_scene))

    select(wm, "paper-baseline.json")
    bpy.ops.lamp.preset_apply()
    assert _design(props, bl_scene) != four
    assert bpy.ops.lamp.preset_import(filepath=str(out)) == {"FINISHED"}
    assert _design(props, bl_scene) == four
    user = browser.preset_library.user_library()[0]
    assert os.listdir(user.folder) == ["four-lamp-rear-combination.json"]
    assert bpy.ops.lamp.preset_import(filepath=str(out)) == {"FINISHED"}  # the same design again: fine

    other = json.loads(out.read_text())
    other["lamps"][0]["lens"]["ior"] = 1.6
    (tmp_path / "other.json").write_text(json.dumps(other))
    select(wm, "paper-baseline.json")
    bpy.ops.lamp.preset_apply()
    before = _design(props, bl_scene)
    with pytest.raises(RuntimeError, match="exists already with another design"):
        bpy.ops.lamp.preset_import(filepath=str(tmp_path / "other.json"))
    assert _design(props, bl_scene) == before

    (tmp_path / "bad.json").write_text('{"schema": "lamp-scene/2"}')
    with pytest.raises(RuntimeError, match="bad.json: schema"):
        bpy.ops.lamp.preset_import(filepath=str(tmp_path / "bad.json"))
    assert _design(props, bl_scene) == before


def test_json_files_dropped_on_the_viewport_are_imported(browser):
    import bpy

    handler = bpy.types.LAMP_FH_preset
    assert handler.bl_import_operator == "lamp.preset_import"
    assert handler.bl_file_extensions == ".json"
    assert issubclass(handler, bpy.types.FileHandler)

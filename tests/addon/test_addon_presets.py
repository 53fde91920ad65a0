"""The preset browser in Blender: sharing through a folder, safe saving, hostile folders, all-or-nothing apply."""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import pytest
from helpers import PRESETS, whole_report
from hostile_presets import make_hostile_folder

from core_tracer.scene.messages import leaves

pytestmark = pytest.mark.blender

BUILTIN = PRESETS


@pytest.fixture
def browser(lamp_addon):
    """The add-on's preset modules, with the user's own library emptied before the test."""
    lib = lamp_addon.presets.library
    user, why = lib.user_library()
    assert user is not None, why
    if lib.thumbnails() is not None:
        lib.thumbnails().wait()  # a thumbnail an earlier test queued is not written into the emptied folder
    for name in os.listdir(user.folder):
        path = os.path.join(user.folder, name)
        shutil.rmtree(path) if os.path.isdir(path) else os.unlink(path)
    return lamp_addon


def _presets_in(folder: str) -> list[str]:
    """The files of a library folder, without the thumbnail cache a refresh may be writing beside them."""
    return sorted(name for name in os.listdir(folder) if name != ".thumbnails")


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


def test_preferences_belong_to_the_extension(addon, browser):
    import bpy

    prefs = bpy.context.preferences.addons[addon].preferences
    assert type(prefs).bl_idname == addon
    assert hasattr(prefs, "library_folders")


def test_libraries_are_builtin_user_and_preferences(browser, add_library, tmp_path):
    team = add_library(tmp_path, "Team")
    wm = refresh()
    listing = browser.presets.library.listing()
    assert [lib.name for lib in listing.libraries] == ["Built-in", "My Presets", "Team"]
    assert [lib.writable for lib in listing.libraries] == [False, True, True]
    assert listing.libraries[2].folder == team
    assert listing.notes == [] and listing.warnings == []
    assert len(wm.lamp_presets) == len(list(BUILTIN.glob("*.json")))
    assert all(item.library == "Built-in" and not item.writable for item in wm.lamp_presets)


def test_builtin_thumbnails_are_shipped_not_made(browser):
    wm = refresh()
    thumbs = browser.presets.library.thumbnails()
    assert not thumbs.busy()  # nothing to render: opening the browser stays instant
    builtin = [item for item in wm.lamp_presets if item.library == "Built-in"]
    assert len(builtin) == len(list(BUILTIN.glob("*.json")))
    for item in builtin:
        path = Path(thumbs.paths[item.file])
        assert path.parent.name == "thumbnails" and path.parent.parent.samefile(BUILTIN), path
        assert thumbs.previews[str(path)].image_size[:] == (96, 96)  # loaded for the list (icon_id is 0 headless)
    cache = Path(browser.presets.library.thumbnail_cache())
    assert not any(cache.glob("*.png")) if cache.is_dir() else True


@pytest.mark.slow
def test_two_designers_share_a_folder(browser, add_library, bl_scene, tmp_path, addon_core):
    import bpy

    (tmp_path / "share").mkdir()
    team = add_library(tmp_path / "share", "Team share")
    props = browser.design.properties

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
    thumbs = browser.presets.library.thumbnails()
    thumbs.wait()
    entry = browser.presets.library.listing().entry(str(saved))
    thumb = Path(team) / ".thumbnails" / f"amber-turn-alice-{browser.presets.library.P.thumbnail_digest(entry)}.png"
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
    assert leaves(addon_core.library.presets.load_preset(saved)) == leaves(expected)


@pytest.mark.slow
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
    wm = refresh()
    listing = browser.presets.library.listing()
    assert {os.path.basename(i.file) for i in wm.lamp_presets if i.library == "Hostile"} == good
    assert len(listing.warnings) == len(bad)
    texts = [str(w) for w in listing.warnings]
    printable = browser.presets.library.P.printable
    for name, needles in bad.items():
        (text,) = [t for t in texts if f"/hostile/{printable(name)}:" in t]
        for needle in needles:
            assert needle in text, (name, needle, text)


def _design(props, bl_scene) -> dict:
    return leaves(props.design_to_scene(bl_scene))


@pytest.mark.slow
def test_apply_is_all_or_nothing(browser, add_library, bl_scene, tmp_path, capfd):
    import bpy

    props = browser.design.properties
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
    capfd.readouterr()
    with pytest.raises(RuntimeError) as raised:
        bpy.ops.lamp.preset_apply()
    assert "lamps[0].lens.ior: 0.5 is out of range" in whole_report(str(raised.value), capfd.readouterr().out)
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


@pytest.mark.slow
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
    assert [lib.name for lib in browser.presets.library.writable_libraries()] == ["My Presets"]


@pytest.mark.slow
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


@pytest.mark.slow
def test_export_then_import(browser, bl_scene, tmp_path, addon_core):
    import bpy

    props = browser.design.properties
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
    user = browser.presets.library.user_library()[0]
    assert _presets_in(user.folder) == ["four-lamp-rear-combination.json"]
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

    (tmp_path / "bad.json").write_text('{"schema": "lamp-scene/3"}')
    with pytest.raises(RuntimeError, match="bad.json: schema"):
        bpy.ops.lamp.preset_import(filepath=str(tmp_path / "bad.json"))
    assert _design(props, bl_scene) == before


def test_json_files_dropped_on_the_viewport_are_imported(browser):
    import bpy

    handler = bpy.types.LAMP_FH_preset
    assert handler.bl_import_operator == "lamp.preset_import"
    assert handler.bl_file_extensions == ".json"
    assert issubclass(handler, bpy.types.FileHandler)


# ---------------------------------------------------------------------------------------------
# The view a preset records and shows


def _move_camera(ob, location, rotation_deg, lens) -> None:
    import math

    ob.location = location
    ob.rotation_euler = [math.radians(a) for a in rotation_deg]
    ob.data.lens = lens
    ob.data.shift_x = 0.05


def _assert_camera_shows(camera_module, bl_scene, preset: dict) -> None:
    seen = camera_module.scene_camera_to_dict(bl_scene)
    for key, value in preset["camera"].items():
        if isinstance(value, str):
            assert seen[key] == value, key
        else:
            assert seen[key] == pytest.approx(value, rel=1e-5, abs=2e-3), key
    render = bl_scene.render
    assert (render.resolution_x, render.resolution_y, render.resolution_percentage) == (
        preset["image"]["width"], preset["image"]["height"], 100)


@pytest.mark.slow
def test_a_preset_records_the_view_the_designer_sees(browser, add_library, bl_scene, tmp_path, addon_core, capfd):
    import bpy

    camera = browser.design.camera
    team = add_library(tmp_path, "Team share")
    props = browser.design.properties

    # Designer 1 applies a preset (the add-on makes its camera), then moves the Blender camera and
    # changes the render size: the preset records that view, not the design's camera section.
    select(refresh(), "paper-lens-color.json")
    assert bpy.ops.lamp.preset_apply() == {"FINISHED"}
    assert "Made the scene camera \"Lamp Camera\" at its view" in capfd.readouterr().out
    design_camera = props.design_to_scene(bl_scene)["camera"]
    _move_camera(bl_scene.camera, (0.25, -1.4, 0.18), (82.0, 0.0, 9.5), 62.0)
    bl_scene.render.resolution_x, bl_scene.render.resolution_y, bl_scene.render.resolution_percentage = 160, 90, 50
    bpy.context.view_layer.update()
    seen = camera.scene_camera_to_dict(bl_scene)
    assert bpy.ops.lamp.preset_save(name="Amber, low view", author="Alice", library=team) == {"FINISHED"}
    preset = addon_core.library.presets.load_preset(Path(team) / "amber-low-view.json")
    assert preset["image"] == {"width": 80, "height": 45, "samples": 1, "edge_samples": 0}  # what F12 renders
    assert preset["camera"]["position"] != design_camera["position"]
    for key, value in seen.items():
        assert preset["camera"][key] == (value if isinstance(value, str) else pytest.approx(value, abs=1e-4)), key
    # Moving the Lamp Camera moved the design's camera: one view (design.view_link.sync_view).
    for key, value in props.design_to_scene(bl_scene)["camera"].items():
        assert value == (seen[key] if isinstance(value, str) else pytest.approx(seen[key], abs=1e-4)), key

    # Exporting records the same view.
    out = tmp_path / "exported.json"
    assert bpy.ops.lamp.preset_export(filepath=str(out)) == {"FINISHED"}
    exported = addon_core.library.presets.load_preset(out)
    assert (exported["camera"], exported["image"]) == (preset["camera"], preset["image"])

    # Designer 2, in a new file without a camera, applies it: the same design parameter for parameter,
    # camera and image included, and a scene camera that shows the same view.
    bpy.ops.wm.read_homefile(use_empty=True)
    scene = bpy.context.scene
    assert scene.camera is None
    select(refresh(), "amber-low-view.json", "Team share")
    assert bpy.ops.lamp.preset_apply() == {"FINISHED"}
    assert leaves(props.design_to_scene(scene)) == leaves(preset)
    assert scene.camera.name == "Lamp Camera"
    _assert_camera_shows(camera, scene, preset)
    # saving it again records exactly the same numbers (no single-precision drift)
    assert bpy.ops.lamp.preset_save(name="Amber, low view", author="Alice", library=team, overwrite=True) == \
        {"FINISHED"}
    assert leaves(addon_core.library.presets.load_preset(Path(team) / "amber-low-view.json")) == leaves(preset)

    # Applying another preset moves the add-on's camera again.
    capfd.readouterr()
    select(refresh(), "paper-baseline.json", "Built-in")
    assert bpy.ops.lamp.preset_apply() == {"FINISHED"}
    assert "Moved \"Lamp Camera\" to the preset's view" in capfd.readouterr().out
    _assert_camera_shows(camera, scene, props.design_to_scene(scene))


@pytest.mark.slow
def test_applying_never_moves_the_designers_own_camera(browser, bl_scene, addon_core, capfd):
    """A preset applied in a file not yet set up for the lamp sets it up like a first build: the Lamp
    Camera becomes the scene camera at the preset's view and the designer's own camera object is left
    exactly as it was. Once the designer makes their camera the scene camera again, later presets
    keep it so, unmoved."""
    import bpy

    own = bpy.data.objects.new("Studio", bpy.data.cameras.new("Studio"))
    bl_scene.collection.objects.link(own)
    bl_scene.camera = own
    _move_camera(own, (0.1, -2.0, 0.3), (80.0, 0.0, 3.0), 85.0)
    bpy.context.view_layer.update()
    before = ([list(row) for row in own.matrix_world], own.data.lens, own.data.shift_x)
    select(refresh(), "four-lamp-rear-combination.json")
    assert bpy.ops.lamp.preset_apply() == {"FINISHED"}
    assert 'your "Studio" is kept as it was' in capfd.readouterr().out
    assert ([list(row) for row in own.matrix_world], own.data.lens, own.data.shift_x) == before
    assert browser.design.camera.is_lamp_camera(bl_scene.camera)
    preset = addon_core.library.presets.load_preset(BUILTIN / "four-lamp-rear-combination.json")
    assert leaves(browser.design.properties.design_to_scene(bl_scene)) == leaves(preset)  # the design has its view

    bl_scene.camera = own  # the designer's choice, after the set-up
    select(refresh(), "paper-baseline.json")
    assert bpy.ops.lamp.preset_apply() == {"FINISHED"}
    assert bl_scene.camera == own
    assert ([list(row) for row in own.matrix_world], own.data.lens, own.data.shift_x) == before


def test_a_camera_the_tracer_cannot_render_is_not_saved(browser, add_library, bl_scene, tmp_path):
    import bpy

    team = add_library(tmp_path, "Team")
    select(refresh(), "paper-baseline.json")
    bpy.ops.lamp.preset_apply()
    bl_scene.camera.data.type = "PANO"
    with pytest.raises(RuntimeError, match="Preset not saved: camera.type"):
        bpy.ops.lamp.preset_save(name="Pano", library=team)
    assert list(tmp_path.glob("*.json")) == []


@pytest.mark.slow
def test_the_scene_camera_is_saved_even_if_the_designs_own_camera_is_invalid(browser, add_library, bl_scene,
                                                                             tmp_path, addon_core):
    """Through a camera of the designer's, the design's camera fields are not used (they are the Lamp
    Camera's): an invalid one does not stop a save, which records the scene camera's view."""
    import bpy

    team = add_library(tmp_path, "Team")
    select(refresh(), "paper-baseline.json")
    bpy.ops.lamp.preset_apply()
    own = bpy.data.objects.new("Studio", bpy.data.cameras.new("Studio"))
    bl_scene.collection.objects.link(own)
    browser.design.camera.apply_camera(own, browser.design.properties.design_to_scene(bl_scene)["camera"], bl_scene)
    bl_scene.camera = own
    bl_scene.lamp_design.camera.position = (0.0, 500.0, 0.0)  # behind the lamp: not a view of it
    with pytest.raises(addon_core.SceneError, match="camera.position"):
        browser.design.properties.design_to_scene(bl_scene)
    assert bpy.ops.lamp.preset_save(name="Seen", library=team) == {"FINISHED"}
    saved = addon_core.library.presets.load_preset(tmp_path / "seen.json")
    assert saved["camera"]["position"] == pytest.approx([0.0, -800.0, 0.0], abs=1e-4)  # where Studio is


@pytest.mark.slow
def test_importing_a_hostile_file_is_refused_naming_the_field(browser, bl_scene, tmp_path, capfd):
    """Huge numbers, lone surrogates, repeated keys...: each import is refused with the field named (in
    the one-line error, or, when that is cut to one line, whole in the Info editor), and the design
    stays as it was."""
    import bpy

    good, bad = make_hostile_folder(tmp_path / "hostile")
    wm = refresh()
    select(wm, "paper-baseline.json")
    bpy.ops.lamp.preset_apply()
    before = _design(browser.design.properties, bl_scene)
    user = browser.presets.library.user_library()[0]
    printable = browser.presets.library.P.printable
    tried = 0
    for name, needles in bad.items():
        path = tmp_path / "hostile" / name
        if not path.is_file() or path.is_symlink() or name == "huge.json":
            continue
        capfd.readouterr()
        with pytest.raises(RuntimeError) as info:
            bpy.ops.lamp.preset_import(filepath=str(path))
        error = str(info.value)
        assert len(error.strip().removeprefix("Error: ")) <= browser.reports.LINE
        info_lines = [line.removeprefix("Info: ") for line in capfd.readouterr().out.splitlines()
                      if line.startswith("Info: ")]
        text = whole_report(error, "\n".join(f"Info: {line}" for line in info_lines))
        assert "Not imported" in text and "Traceback" not in text, text
        assert printable(name) in text
        for needle in needles:
            if "bytes" not in needle:
                assert needle in text, (name, needle, text)
        tried += 1
    assert tried >= 20
    assert _design(browser.design.properties, bl_scene) == before
    assert _presets_in(user.folder) == []

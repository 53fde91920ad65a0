"""Preset libraries without Blender: sharing, safe saving, hostile folders, thumbnails, the CLI."""

from __future__ import annotations

import copy
import dataclasses
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from helpers import ROOT, assert_bad_input, run_cli
from hostile_presets import make_hostile_folder

from core_tracer import fileio
from core_tracer.images import imageio
from core_tracer.library import presets as P
from core_tracer.library import shipping
from core_tracer.scene import reading
from core_tracer.scene.messages import leaves
from core_tracer.scene.reading import SceneError, read_json, scene_to_json
from core_tracer.scene.validate import parse_scene

BUILTIN = ROOT / "presets"


def builtin_doc(stem: str = "paper-baseline") -> dict:
    return json.loads((BUILTIN / f"{stem}.json").read_text())


def files_in(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


# ---------------------------------------------------------------------------------------------
# Two designers share a folder


def test_two_designers_share_a_folder(tmp_path):
    share = tmp_path / "team-share"
    share.mkdir()
    alice = P.Library("Team share", str(share), writable=True)
    bob = P.Library("Team share (Bob)", str(share), writable=False)

    design = parse_scene(builtin_doc("paper-lens-color"))
    design["author"] = "Alice"
    design["tags"] = ["amber", "turn"]
    design["description"] = "My amber turn lamp; try it with your cuts"
    design["lamps"][0]["lens"]["ior"] = 1.4937
    design["lamps"][0]["cuts"].update(pitch=7.3, height=0.1 + 0.2)  # a float that must survive exactly
    design["lamps"][0]["bulb"]["offset"] = [0.5, 2.25, -0.125]
    saved = P.save_preset(alice, "Amber turn (Alice)", design)
    assert Path(saved.file).name == "amber-turn-alice.json"

    entries, warnings = P.list_presets([P.builtin_library(), bob])
    assert warnings == []
    mine = [e for e in entries if e.library == bob]
    assert [e.name for e in mine] == ["Amber turn (Alice)"]
    entry = mine[0]
    assert (entry.author, entry.tags, entry.description) == ("Alice", ("amber", "turn"),
                                                            "My amber turn lamp; try it with your cuts")
    loaded = P.load_preset(entry.file)
    expected = copy.deepcopy(design)
    expected["name"] = "Amber turn (Alice)"
    assert leaves(loaded) == leaves(expected)
    assert loaded["lamps"][0]["cuts"]["height"] == 0.1 + 0.2
    assert entry.digest == saved.digest


# ---------------------------------------------------------------------------------------------
# Saving safely


def test_overwrite_is_refused_without_confirmation(tmp_path):
    lib = P.Library("mine", str(tmp_path), writable=True)
    first = P.save_preset(lib, "Red tail", parse_scene(builtin_doc()))
    before = Path(first.file).read_bytes()
    changed = parse_scene(builtin_doc())
    changed["lamps"][0]["lens"]["ior"] = 1.6
    for name in ("Red tail", "RED  tail!"):  # the same file name either way
        with pytest.raises(P.PresetExistsError) as err:
            P.save_preset(lib, name, changed)
        assert "red-tail.json" in str(err.value) and "overwrite" in str(err.value)
        assert Path(first.file).read_bytes() == before
    again = P.save_preset(lib, "Red tail", changed, overwrite=True)
    assert again.file == first.file
    assert P.load_preset(again.file)["lamps"][0]["lens"]["ior"] == 1.6
    assert files_in(tmp_path) == ["red-tail.json"]


def test_invalid_design_is_not_saved(tmp_path):
    lib = P.Library("mine", str(tmp_path), writable=True)
    bad = parse_scene(builtin_doc())
    bad["lamps"][0]["lens"]["ior"] = 0.7
    with pytest.raises(SceneError, match=r"lamps\[0\]\.lens\.ior"):
        P.save_preset(lib, "Bad", bad)
    assert files_in(tmp_path) == []


def _boom(*args, **kwargs):
    raise OSError(28, "No space left on device")


@pytest.mark.parametrize("where", ["fsync", "replace"])
def test_interrupted_save_keeps_the_old_file(tmp_path, monkeypatch, where):
    lib = P.Library("mine", str(tmp_path), writable=True)
    first = P.save_preset(lib, "Red tail", parse_scene(builtin_doc()))
    before = Path(first.file).read_bytes()
    changed = parse_scene(builtin_doc("four-lamp-rear-combination"))
    # fsync fails after the new content went into the temporary file (a full disk at flush);
    # replace fails at the very last step
    monkeypatch.setattr(fileio.os, where, _boom)
    with pytest.raises(OSError, match="No space left"):
        P.save_preset(lib, "Red tail", changed, overwrite=True)
    monkeypatch.undo()
    assert Path(first.file).read_bytes() == before
    assert files_in(tmp_path) == ["red-tail.json"]  # no temporary file left behind


def test_ctrl_c_during_save_keeps_the_old_file(tmp_path, monkeypatch):
    lib = P.Library("mine", str(tmp_path), writable=True)
    first = P.save_preset(lib, "Red tail", parse_scene(builtin_doc()))
    before = Path(first.file).read_bytes()

    def interrupt(fd):
        raise KeyboardInterrupt

    monkeypatch.setattr(fileio.os, "fsync", interrupt)
    with pytest.raises(KeyboardInterrupt):
        P.save_preset(lib, "Red tail", parse_scene(builtin_doc("paper-lamp-off")), overwrite=True)
    monkeypatch.undo()
    assert Path(first.file).read_bytes() == before
    assert files_in(tmp_path) == ["red-tail.json"]


def test_read_only_library_refuses_changes(tmp_path):
    (tmp_path / "a.json").write_text(json.dumps(builtin_doc()))
    lib = P.Library("Team (read-only)", str(tmp_path), writable=False)
    (entry,), _ = P.list_presets([lib])
    with pytest.raises(P.PresetError, match="read-only"):
        P.save_preset(lib, "New", entry.scene)
    with pytest.raises(P.PresetError, match="read-only"):
        P.delete_preset(entry)
    with pytest.raises(P.PresetError, match="read-only"):
        P.rename_preset(entry, "Other")
    assert files_in(tmp_path) == ["a.json"]


def test_rename_and_delete(tmp_path):
    lib = P.Library("mine", str(tmp_path), writable=True)
    entry = P.save_preset(lib, "Red tail", parse_scene(builtin_doc()))
    other = P.save_preset(lib, "Other", parse_scene(builtin_doc()))
    with pytest.raises(P.PresetExistsError):
        P.rename_preset(entry, "other")
    renamed = P.rename_preset(entry, "Red tail v2")
    assert files_in(tmp_path) == ["other.json", "red-tail-v2.json"]
    assert P.load_preset(renamed.file)["name"] == "Red tail v2"
    recased = P.rename_preset(renamed, "Red Tail V2")  # same file, new name
    assert recased.file == renamed.file and P.load_preset(recased.file)["name"] == "Red Tail V2"
    P.delete_preset(other)
    assert files_in(tmp_path) == ["red-tail-v2.json"]


def test_names_never_leave_the_library(tmp_path):
    lib = P.Library("mine", str(tmp_path / "lib"), writable=True)
    os.mkdir(lib.folder)
    entry = P.save_preset(lib, "../../etc/passwd", parse_scene(builtin_doc()))
    assert Path(entry.file).parent == Path(lib.folder) and Path(entry.file).name == "etc-passwd.json"
    for bad in ("../x.json", "a/b.json", "a\\b.json", ".hidden.json", "x.txt", "", "/etc/x.json"):
        with pytest.raises(P.PresetError, match="not a preset file name"):
            P.preset_file(lib, bad)
    assert P.slug("Amber Turn (Alice)") == "amber-turn-alice"
    assert P.slug("") == P.slug("///") == "preset"
    assert P.slug("CON") == "con-preset"
    assert P.slug("赤いテールランプ 2") == "赤いテールランプ-2"
    assert len(P.slug("x" * 500)) == P.MAX_SLUG


# ---------------------------------------------------------------------------------------------
# A folder of hostile presets


@pytest.mark.slow
def test_hostile_folder_through_the_api(tmp_path, monkeypatch):
    folder = tmp_path / "hostile"
    good, bad = make_hostile_folder(folder)
    lib = P.Library("hostile", str(folder), writable=False)
    opened = []

    def recording_open(name, *args, **kw):
        opened.append(os.path.basename(name))
        return open(name, *args, **kw)

    monkeypatch.setattr(reading, "open", recording_open, raising=False)
    entries, warnings = P.list_presets([lib, P.builtin_library()])
    assert "huge.json" not in opened and "many-lamps.json" in opened  # refused by its size, unread
    assert {Path(e.file).name for e in entries if e.library == lib} == good
    assert len([e for e in entries if e.library != lib]) == len(list(BUILTIN.glob("*.json")))
    by_file = {Path(w.file).name: w for w in warnings}
    assert len(warnings) == len(bad)
    assert set(by_file) == {P.printable(n) for n in bad}
    for name, needles in bad.items():
        text = str(by_file[P.printable(name)])
        assert text.startswith(str(folder)), text
        assert "\n" not in text and len(text) < 600
        for needle in needles:
            assert needle in text, (name, needle, text)


def test_ten_to_the_six_lamps_stop_validation_at_once():
    doc = builtin_doc()
    # Lamps that are each wrong: the count is refused before any lamp is looked at.
    doc["lamps"] = [{"bogus": 1}] * 1_000_000
    with pytest.raises(SceneError, match="^lamps: has 1000000 items; allowed 1 to 4$"):
        parse_scene(doc)




@pytest.mark.slow
def test_hostile_folder_through_the_cli(tmp_path):
    folder = tmp_path / "hostile"
    good, bad = make_hostile_folder(folder)
    proc = run_cli("presets", "list", folder)
    assert proc.returncode == 0, proc.stderr
    assert "Traceback" not in proc.stderr
    listed = proc.stdout.splitlines()
    assert len(listed) == len(good)
    assert sum("Round red tail lamp" in line for line in listed) == 2
    assert sum("Four-lamp rear combination" in line for line in listed) == 1
    warnings = proc.stderr.splitlines()
    assert len(warnings) == len(bad)
    for name, needles in bad.items():
        (line,) = [w for w in warnings if f"{folder}/{P.printable(name)}:" in w]
        for needle in needles:
            assert needle in line, (name, needle, line)

    proc = run_cli("presets", "validate", folder)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert f"{len(good)} valid, {len(bad)} not valid" in proc.stderr


@pytest.mark.slow
def test_cli_lists_and_shows_the_builtin_presets():
    proc = run_cli("presets", "list", "--json")
    assert proc.returncode == 0, proc.stderr
    rows = json.loads(proc.stdout)
    assert {Path(r["file"]).name for r in rows} == {p.name for p in BUILTIN.glob("*.json")}
    assert all(r["library"] == "Built-in" for r in rows)

    proc = run_cli("presets", "validate")
    assert proc.returncode == 0, proc.stderr

    proc = run_cli("presets", "show", "four-lamp-rear-combination")
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout == scene_to_json(parse_scene(read_json(BUILTIN / "four-lamp-rear-combination.json")))
    assert run_cli("presets", "show", "Four-lamp rear combination").stdout == proc.stdout


@pytest.mark.slow
@pytest.mark.parametrize("name", ["../presets/paper-baseline.json", "/etc/passwd", "no-such-preset"])
def test_cli_show_refuses_paths_and_unknown_names(name):
    proc = run_cli("presets", "show", name)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert len(proc.stderr.splitlines()) == 1 and name in proc.stderr


# ---------------------------------------------------------------------------------------------
# Thumbnails


@pytest.mark.slow
def test_thumbnail_beside_a_writable_library_refreshes_when_the_preset_changes(tmp_path):
    lib = P.Library("mine", str(tmp_path / "lib"), writable=True)
    os.mkdir(lib.folder)
    cache = tmp_path / "cache"
    entry = P.save_preset(lib, "Red tail", parse_scene(builtin_doc()))
    path = P.thumbnail_path(entry, cache)
    assert Path(path).parent == Path(lib.folder) / ".thumbnails"
    assert Path(path).name == f"red-tail-{P.thumbnail_digest(entry)}.png"
    assert P.make_thumbnail(entry, path, size=32) == path
    image, scene = imageio.read_image(path)
    assert image.shape == (32, 32, 3) and image.max() > 0 and scene["name"] == "Red tail"

    changed = parse_scene(builtin_doc())
    changed["lamps"][0]["bulb"]["on"] = False
    entry2 = P.save_preset(lib, "Red tail", changed, overwrite=True)
    path2 = P.thumbnail_path(entry2, cache)
    assert path2 != path and not os.path.exists(path2)
    P.make_thumbnail(entry2, path2, size=32)
    assert files_in(Path(lib.folder) / ".thumbnails") == [Path(path2).name]  # the stale one is gone
    # the hidden folder is not a preset and the listing ignores it
    entries, warnings = P.list_presets([lib])
    assert [e.name for e in entries] == ["Red tail"] and warnings == []
    assert not cache.exists()
    P.delete_preset(entry2)
    assert files_in(Path(lib.folder) / ".thumbnails") == []


def _thumbnail_library(tmp_path: Path, writable: bool) -> tuple[P.Library, P.PresetEntry]:
    folder = tmp_path / "lib"
    folder.mkdir()
    (folder / "red-tail.json").write_text(json.dumps(builtin_doc()))
    lib = P.Library("lib", str(folder), writable=writable)
    (entry,), warnings = P.list_presets([lib])
    assert warnings == []
    return lib, entry


@pytest.mark.slow
def test_a_read_only_library_without_thumbnails_uses_the_cache(tmp_path):
    lib, entry = _thumbnail_library(tmp_path, writable=False)
    cache = tmp_path / "cache"
    thumb = P.thumbnail_path(entry, cache)
    assert Path(thumb) == cache / f"red-tail-{P.thumbnail_digest(entry)}.png"  # never inside the read-only folder
    P.make_thumbnail(entry, thumb)
    image, _ = imageio.read_image(thumb)
    assert image.shape == (P.THUMBNAIL_SIZE, P.THUMBNAIL_SIZE, 3)
    assert np.isfinite(image).all() and image.max() > 0
    assert files_in(cache) == [Path(thumb).name] and files_in(Path(lib.folder)) == ["red-tail.json"]


def test_thumbnail_lookup_order(tmp_path):
    lib, entry = _thumbnail_library(tmp_path, writable=False)
    folder, cache = Path(lib.folder), tmp_path / "cache"
    name = P.thumbnail_name(entry)
    assert name == f"red-tail-{P.thumbnail_digest(entry)}.png"
    # a thumbnail made beside the presets by a designer who may write there serves read-only viewers too
    (folder / ".thumbnails").mkdir()
    P.make_thumbnail(entry, folder / ".thumbnails" / name, size=16)
    assert P.thumbnail_path(entry, cache) == str(folder / ".thumbnails" / name)
    # the shipped one comes first, for read-only and writable libraries alike
    (folder / "thumbnails").mkdir()
    P.make_thumbnail(entry, folder / "thumbnails" / name, size=16)
    assert P.thumbnail_path(entry, cache) == P.shipped_thumbnail(entry) == str(folder / "thumbnails" / name)
    writable_entry = dataclasses.replace(entry, library=dataclasses.replace(lib, writable=True))
    assert P.thumbnail_path(writable_entry, cache) == str(folder / "thumbnails" / name)
    # a thumbnail of another content (an old hash) is not this preset's
    changed = P.save_preset(writable_entry.library, "Red tail", dict(entry.scene, body={
        **entry.scene["body"], "color": [0.1, 0.2, 0.3]}), overwrite=True)
    assert P.shipped_thumbnail(changed) is None
    assert P.thumbnail_path(changed, cache) == str(folder / ".thumbnails" / P.thumbnail_name(changed))
    assert not cache.exists()


@pytest.mark.parametrize("hostile", ["link-out", "huge", "folder-link-out", "directory"])
def test_a_library_cannot_pass_off_other_files_as_thumbnails(tmp_path, hostile):
    lib, entry = _thumbnail_library(tmp_path, writable=False)
    folder, name = Path(lib.folder), P.thumbnail_name(entry)
    outside = tmp_path / "outside"
    outside.mkdir()
    P.make_thumbnail(entry, outside / name, size=16)  # a real thumbnail, but not in the library
    if hostile == "folder-link-out":
        os.symlink(outside, folder / "thumbnails")
        os.symlink(outside, folder / ".thumbnails")
    else:
        for sub in ("thumbnails", ".thumbnails"):
            (folder / sub).mkdir()
            target = folder / sub / name
            if hostile == "link-out":
                os.symlink(outside / name, target)
            elif hostile == "huge":
                with open(target, "wb") as f:
                    f.truncate(P.MAX_THUMBNAIL_BYTES + 1)
            else:
                target.mkdir()
    assert P.shipped_thumbnail(entry) is None
    assert P.thumbnail_path(entry, tmp_path / "cache") == str(tmp_path / "cache" / name)
    writable = dataclasses.replace(entry, library=dataclasses.replace(lib, writable=True))
    # A writable library is no different: the file there is never opened, the cache is used.
    assert P.thumbnail_path(writable, tmp_path / "cache") == str(tmp_path / "cache" / name)
    if hostile == "folder-link-out":  # neither made, removed nor listed through the link
        assert Path(P.thumbnail_path(writable, tmp_path / "cache")).parent == tmp_path / "cache"
        (outside / "stale-0123456789abcdef.png").write_bytes(b"someone else's")
        with pytest.raises(P.PresetError, match="thumbnails: is a link that leads out of the library"):
            shipping.make_shipped_thumbnails(lib)
        P.delete_preset(writable)
        assert files_in(outside) == sorted([name, "stale-0123456789abcdef.png"])


def test_libraries_list_only_their_json_files(tmp_path):
    entries, warnings = P.list_presets([P.builtin_library()])
    assert warnings == [] and (BUILTIN / P.SHIPPED_THUMBNAIL_FOLDER).is_dir()
    assert sorted(Path(e.file).name for e in entries) == sorted(p.name for p in BUILTIN.glob("*.json"))
    lib, entry = _thumbnail_library(tmp_path, writable=True)
    folder = Path(lib.folder)
    for sub in ("thumbnails", ".thumbnails", "old"):
        (folder / sub).mkdir()
        (folder / sub / "red-tail.json").write_text("{not a preset, and not listed")
    for name in ("README.md", "thumb.png", "red-tail.json.bak", "notes"):
        (folder / name).write_text("not a preset")
    entries, warnings = P.list_presets([lib])
    assert [e.file for e in entries] == [entry.file] and warnings == []


@pytest.mark.slow
def test_shipped_thumbnails_are_made_on_purpose(tmp_path):
    lib, entry = _thumbnail_library(tmp_path, writable=False)
    folder = Path(lib.folder)
    (folder / "amber.json").write_text(json.dumps(builtin_doc("paper-lens-color")))
    (folder / "broken.json").write_text("{")
    proc = run_cli("presets", "thumbnails", "--check", folder)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert f"red-tail.json: has no thumbnail red-tail-{P.thumbnail_digest(entry)}.png" in proc.stderr
    assert "broken.json: not valid JSON" in proc.stderr
    assert f"run python -m core_tracer presets thumbnails {folder}" in proc.stderr
    assert not (folder / "thumbnails").exists()  # --check changes nothing

    proc = run_cli("presets", "thumbnails", folder)
    assert proc.returncode == 2 and "broken.json" in proc.stderr  # the valid presets still get theirs
    (folder / "broken.json").unlink()
    made = sorted(Path(line.removeprefix("made: ")).name for line in proc.stdout.splitlines())
    assert made == sorted(files_in(folder / "thumbnails")) and len(made) == 2
    assert run_cli("presets", "thumbnails", "--check", folder).returncode == 0
    assert run_cli("presets", "thumbnails", folder).stdout == ""  # nothing to do

    # a preset edited without regenerating: the check fails and names the command; regenerating
    # makes the new thumbnail and removes the old one, and leaves other files alone
    (folder / "thumbnails" / "README.txt").write_text("made by python -m core_tracer presets thumbnails")
    doc = builtin_doc()
    doc["lamps"][0]["bulb"]["on"] = False
    (folder / "red-tail.json").write_text(json.dumps(doc))
    proc = run_cli("presets", "thumbnails", "--check", folder)
    assert proc.returncode == 2 and "red-tail.json: has no thumbnail" in proc.stderr
    assert f"red-tail-{P.thumbnail_digest(entry)}.png: belongs to no current preset" in proc.stderr
    proc = run_cli("presets", "thumbnails", folder)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.count("made: ") == 1 and proc.stdout.count("removed: ") == 0  # made over the old one
    (new,) = [e for e in P.list_presets([lib])[0] if Path(e.file).name == "red-tail.json"]
    assert P.shipped_thumbnail(new) is not None and new.digest != entry.digest
    assert len(files_in(folder / "thumbnails")) == 3  # two thumbnails and the README
    (folder / "amber.json").unlink()
    proc = run_cli("presets", "thumbnails", folder)
    assert proc.stdout.count("removed: ") == 1
    assert files_in(folder / "thumbnails") == sorted(["README.txt", P.thumbnail_name(new)])
    assert os.stat(P.shipped_thumbnail(new)).st_mode & 0o644 == 0o644  # readable by whoever installs it


@pytest.mark.slow
def test_deleting_a_preset_removes_its_thumbnails(tmp_path):
    lib, entry = _thumbnail_library(tmp_path, writable=True)
    for sub in ("thumbnails", ".thumbnails"):
        P.make_thumbnail(entry, Path(lib.folder) / sub / P.thumbnail_name(entry), size=16)
    (Path(lib.folder) / "thumbnails" / "keep.png").write_bytes(b"not ours")
    P.delete_preset(entry)
    assert files_in(Path(lib.folder) / ".thumbnails") == []
    assert files_in(Path(lib.folder) / "thumbnails") == ["keep.png"]


@pytest.mark.slow
def test_a_change_of_display_makes_thumbnails_stale(tmp_path, monkeypatch):
    lib, entry = _thumbnail_library(tmp_path, writable=False)
    made, _, _ = shipping.make_shipped_thumbnails(lib, size=16)
    assert shipping.check_shipped_thumbnails(lib).ok
    monkeypatch.setattr(P, "THUMBNAIL_LOOK", P.THUMBNAIL_LOOK + "; another view")
    state = shipping.check_shipped_thumbnails(lib)
    assert [e.file for e in state.missing] == [entry.file] and state.stale == (Path(made[0]).name,)


@pytest.mark.slow
def test_shipped_thumbnails_need_blenders_colour_configuration(tmp_path):
    lib, _ = _thumbnail_library(tmp_path, writable=False)
    env = {**os.environ, "LAMP_OCIO_CONFIG": str(tmp_path / "missing.ocio")}
    proc = subprocess.run([sys.executable, "-m", "core_tracer", "presets", "thumbnails", lib.folder], cwd=ROOT,
                          capture_output=True, text=True, timeout=120, env=env)
    assert_bad_input(proc, "cannot make shipped thumbnails", "LAMP_OCIO_CONFIG names no file", "Standard")
    assert not (Path(lib.folder) / "thumbnails").exists()

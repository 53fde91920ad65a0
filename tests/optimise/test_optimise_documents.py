"""Optimise files are documents like presets (issue 33 item 3): ``storage`` a SQLite file in the
file's folder (or a server's URL), never a database that holds anything but an Optuna study this
program made; ``base`` confined to the file's folder; resuming a study whose parameters changed
refused in one line naming what changed."""

from __future__ import annotations

import json
import os
import sqlite3

import pytest
from helpers import BASELINE, assert_bad_input, baseline_doc, run_cli

from core_tracer.optimise import spec, storage
from core_tracer.scene.reading import SceneError


def doc(**edits) -> dict:
    out = {"schema": spec.SCHEMA, "base": baseline_doc(),
           "parameters": [{"parameter": "cuts.height", "range": [0.5, 2.0]}],
           "objectives": [{"measure": "lens_luminance", "goal": "maximise"}],
           "size": [12, 12], "trials": 2, "seed": 1}
    out.update(edits)
    return out


def tables(path) -> list[str]:
    with sqlite3.connect(path) as db:
        return sorted(r[0] for r in db.execute("SELECT name FROM sqlite_master WHERE type = 'table'"))


@pytest.mark.parametrize("storage", ["sqlite:////etc/passwd.db", "sqlite:///../out.db", "sqlite:///~/x.db",
                                     "sqlite:///file:x.db?mode=rwc&uri=true", "sqlite://", "sqlite:///",
                                     "sqlite:///a/../../b.db", "oracle://x", "file:///tmp/x.db", "opt.db",
                                     "sqlite:///x.db\x00y"])
def test_storage_outside_the_folder_or_of_another_kind_is_refused(tmp_path, storage):
    with pytest.raises(SceneError) as e:
        spec.from_doc(doc(storage=storage), str(tmp_path))
    assert e.value.path == "storage" and "allowed" in e.value.message


def test_a_relative_sqlite_name_is_the_file_folder_not_the_working_directory(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path.parent)
    opt = spec.from_doc(doc(storage="sqlite:///runs/opt.db"), str(tmp_path))
    assert opt.storage == "sqlite:///" + str(tmp_path / "runs" / "opt.db")


def test_a_link_out_of_the_folder_is_refused(tmp_path):
    outside = tmp_path / "outside"
    inside = tmp_path / "inside"
    outside.mkdir()
    inside.mkdir()
    os.symlink(outside, inside / "link")
    with pytest.raises(SceneError, match="leads outside"):
        spec.from_doc(doc(storage="sqlite:///link/opt.db"), str(inside))
    (outside / "base.json").write_text(json.dumps(baseline_doc()))
    with pytest.raises(SceneError, match="leads outside"):
        spec.from_doc(doc(base="link/base.json"), str(inside))


@pytest.mark.parametrize("base", [str(BASELINE), "~/base.json", "../presets/paper-baseline.json", "a/../../b.json",
                                  "\ud800.json", "a\x00.json"])
def test_a_base_outside_the_folder_is_refused(tmp_path, base):
    with pytest.raises(SceneError) as e:
        spec.from_doc(doc(base=base), str(tmp_path))
    assert e.value.path == "base" and "this file's folder" in e.value.message


def test_a_base_inside_the_folder_loads(tmp_path):
    (tmp_path / "designs").mkdir()
    (tmp_path / "designs" / "b.json").write_text(json.dumps(baseline_doc()))
    assert spec.from_doc(doc(base="designs/b.json"), str(tmp_path)).base["lamps"]


def test_an_unrelated_sqlite_database_is_refused_without_a_table_added(tmp_path):
    db = tmp_path / "accounts.db"
    with sqlite3.connect(db) as c:
        c.execute("CREATE TABLE accounts (id INTEGER, owner TEXT)")
        c.execute("INSERT INTO accounts VALUES (1, 'someone')")
    before = db.read_bytes()
    opt = spec.from_doc(doc(storage="sqlite:///accounts.db"), str(tmp_path))
    with pytest.raises(SceneError) as e:
        storage.open_study(opt)
    assert e.value.path == "storage" and "accounts" in e.value.message and "nothing was changed" in e.value.message
    assert tables(db) == ["accounts"] and db.read_bytes() == before


def test_a_file_that_is_not_a_database_is_refused_untouched(tmp_path):
    (tmp_path / "notes.db").write_text("my notes\n" * 100)
    opt = spec.from_doc(doc(storage="sqlite:///notes.db"), str(tmp_path))
    with pytest.raises(SceneError, match="not a SQLite database"):
        storage.open_study(opt)
    assert (tmp_path / "notes.db").read_text() == "my notes\n" * 100


@pytest.mark.slow
def test_the_cli_refuses_an_unrelated_database_in_one_line(tmp_path):
    db = tmp_path / "shop.db"
    with sqlite3.connect(db) as c:
        c.execute("CREATE TABLE orders (id INTEGER)")
    path = tmp_path / "o.optimise.json"
    path.write_text(json.dumps(doc(storage="sqlite:///shop.db")))
    assert_bad_input(run_cli("optimise", path, "--workers", "0", timeout=120), "storage", "orders")
    assert tables(db) == ["orders"]


@pytest.mark.slow
def test_a_study_of_that_name_not_made_here_is_refused(tmp_path):
    import optuna

    optuna.create_study(storage=f"sqlite:///{tmp_path / 'shared.db'}", study_name="theirs")
    opt = spec.from_doc(doc(storage="sqlite:///shared.db", name="theirs"), str(tmp_path))
    with pytest.raises(SceneError, match="not made by an optimisation file"):
        storage.open_study(opt)


def test_a_step_of_1e_300_is_refused(tmp_path):
    with pytest.raises(SceneError) as e:
        spec.from_doc(doc(parameters=[{"parameter": "cuts.height", "range": [0.5, 2.0], "step": 1e-300}]),
                      str(tmp_path))
    assert e.value.path == "parameters[0].step" and "1.5e-06" in e.value.message


@pytest.mark.slow
@pytest.mark.parametrize("changed, words", [
    ({"parameters": [{"parameter": "cuts.height", "values": [0.5, 1.0]}]},
     ("was a range [0.5, 2] in the study", "now values [0.5, 1.0]")),
    ({"parameters": [{"parameter": "cuts.height", "range": [0.5, 2.0], "step": 0.5}]},
     ("now a range [0.5, 2] step 0.5",)),
    ({"parameters": [{"parameter": "lens.ior", "range": [1.45, 1.6]}]}, ("varies cuts.height, this file lens.ior",)),
])
def test_resuming_a_changed_study_is_refused_naming_the_change(tmp_path, changed, words):
    path = tmp_path / "o.optimise.json"
    path.write_text(json.dumps(doc()))
    first = run_cli("optimise", path, "--workers", "0", timeout=300)
    assert first.returncode == 0, first.stderr
    path.write_text(json.dumps(doc(**changed)))
    line = assert_bad_input(run_cli("optimise", path, "--workers", "0", timeout=300), "parameters", *words)
    assert "another name" in line


def test_the_examples_bases_are_copies_of_the_presets_beside_them():
    from helpers import PRESETS, ROOT

    examples = ROOT / "docs" / "examples"
    for name in ("liked-look", "even-stop-lamp"):
        opt = spec.load(str(examples / f"{name}.optimise.json"))
        base = json.loads((examples / f"{name}.optimise.json").read_text())["base"]
        assert (examples / base).read_bytes() == (PRESETS / base).read_bytes(), f"{base} drifted from presets/"
        assert opt.storage == "sqlite:///" + str(examples / f"{name}.optimise.optuna.db")


@pytest.mark.parametrize("name", ["\x1b[31mred", "two\nlines", "\ud800"])
def test_a_name_with_control_characters_is_refused(tmp_path, name):
    with pytest.raises(SceneError) as e:
        spec.from_doc(doc(name=name), str(tmp_path))
    assert e.value.path == "name" and "printable" in e.value.message


@pytest.mark.slow
def test_a_name_with_dollars_draws_its_history(tmp_path):
    path = tmp_path / "o.optimise.json"
    path.write_text(json.dumps(doc(name="$\\frac{x}{$ cost $5")))
    done = run_cli("optimise", path, "--workers", "0", timeout=300)
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "o.optimise-results" / "history.png").stat().st_size > 0


def test_trials_json_holds_no_nan_even_when_a_measure_had_none(tmp_path):
    import optuna

    from core_tracer.optimise import results

    opt = spec.from_doc(doc(storage="sqlite:///t.db"), str(tmp_path))
    study = storage.open_study(opt)
    trial = study.ask()
    trial.set_user_attr("measures", {"lens_luminance": float("nan"), "lit_fraction": float("inf")})
    study.tell(trial, 1.0)
    assert isinstance(study, optuna.Study)
    results.write_trials(opt, study, str(tmp_path / "trials.json"))
    text = (tmp_path / "trials.json").read_text()

    def no_constants(name):
        raise ValueError(name)

    row = json.loads(text, parse_constant=no_constants)["trials"][0]
    assert row["measures"] == {"lens_luminance": None, "lit_fraction": None}


@pytest.mark.parametrize("title", ["\x1b[2J cleared", "bell\x07", "two\nlines"])
def test_a_study_title_with_control_characters_is_refused(title):
    from core_tracer.study import definition as st

    with pytest.raises(SceneError) as e:
        st.Study.build(baseline_doc(), [{"parameter": "lens.ior", "values": [1.45, 1.6]}], (16, 16), title=title)
    assert e.value.path == "title" and "printable" in e.value.message

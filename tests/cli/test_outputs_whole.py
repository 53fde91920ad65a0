"""All or nothing: a render's ``--passes`` folder and a study's ``--save-study`` and
``--save-variants`` are written whole or not at all, and never mixed with an earlier run's files;
an interrupt at a chosen moment (a real SIGINT or SIGTERM, at a checkpoint) leaves the outputs as
they were (issue 21)."""

from __future__ import annotations

import json
import os
import signal

import pytest
from helpers import BASELINE, assert_bad_input, run_cli, signal_and_wait, start_cli_at

pytestmark = pytest.mark.slow  # subprocesses and signals

RENDER = ("render", BASELINE, "--width", "16", "--height", "16")


def files(folder) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())} if folder.exists() else {}


def old_passes(folder) -> dict[str, bytes]:
    """A passes folder of an earlier render, with passes this render does not make."""
    folder.mkdir()
    for name in ("lens_surface", "bulb", "stale_a", "stale_b", "stale_c", "stale_d", "stale_e", "stale_f"):
        (folder / f"{name}.exr").write_bytes(b"old " + name.encode())
    return files(folder)


def passes_of_one_render(tmp_path) -> set[str]:
    proc = run_cli(*RENDER, "-o", tmp_path / "ref.exr", "--passes", tmp_path / "ref-passes")
    assert proc.returncode == 0, proc.stderr
    return set(files(tmp_path / "ref-passes"))


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
@pytest.mark.parametrize("existing", [False, True])
def test_an_interrupt_while_passes_are_written_leaves_the_passes_folder_as_it_was(tmp_path, sig, existing):
    out = tmp_path / "out"
    out.mkdir()
    before = old_passes(out / "passes") if existing else {}
    proc = start_cli_at("render:pass", tmp_path / "reached", *RENDER, "-o", out / "lamp.exr",
                        "--passes", out / "passes")  # waits after the first pass is written
    _, err = signal_and_wait(proc, sig)
    assert (proc.returncode, err.strip()) == ((130, "interrupted") if sig == signal.SIGINT else (143, "terminated"))
    assert files(out / "passes") == before
    assert sorted(os.listdir(out)) == (["passes"] if existing else [])  # no temporary folder, no image


def test_an_interrupt_as_the_passes_are_complete_leaves_the_old_passes(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    before = old_passes(out / "passes")
    proc = start_cli_at("folder:written", tmp_path / "reached", *RENDER, "-o", out / "lamp.exr",
                        "--passes", out / "passes")
    _, err = signal_and_wait(proc, signal.SIGTERM)
    assert proc.returncode == 143, err
    assert files(out / "passes") == before
    assert sorted(os.listdir(out)) in (["passes"], ["lamp.exr", "passes"])  # the image is whole if there


def test_a_passes_folder_holds_one_renders_passes_only(tmp_path):
    expected = passes_of_one_render(tmp_path)
    old_passes(tmp_path / "passes")
    proc = run_cli(*RENDER, "-o", tmp_path / "lamp.exr", "--passes", tmp_path / "passes")
    assert proc.returncode == 0, proc.stderr
    assert set(files(tmp_path / "passes")) == expected
    assert all(not data.startswith(b"old ") for data in files(tmp_path / "passes").values())
    assert sorted(os.listdir(tmp_path)) == ["lamp.exr", "passes", "ref-passes", "ref.exr"]


@pytest.mark.parametrize("other", ["notes.txt", "sub/", ".hidden.exr"])
def test_a_passes_folder_holding_other_files_is_refused_before_rendering(tmp_path, other):
    folder = tmp_path / "passes"
    folder.mkdir()
    if other.endswith("/"):
        (folder / other).mkdir()
    else:
        (folder / other).write_text("mine")
    (folder / "bulb.exr").write_bytes(b"old")
    proc = run_cli(*RENDER, "-o", tmp_path / "lamp.exr", "--passes", folder)
    assert_bad_input(proc, "passes: --passes holds other files than passes (.exr files)", "replaced whole")
    assert sorted(p.name for p in folder.iterdir()) == sorted([other.rstrip("/"), "bulb.exr"])
    assert not (tmp_path / "lamp.exr").exists()


def test_the_output_inside_the_passes_folder_is_refused(tmp_path):
    (tmp_path / "passes").mkdir()
    proc = run_cli(*RENDER, "-o", tmp_path / "passes" / "lamp.exr", "--passes", tmp_path / "passes")
    assert_bad_input(proc, "--passes holds the output image")


STUDY = ("study", BASELINE, "--size", "8x8", "--workers", "0")


def variants(folder) -> dict[str, dict]:
    return {name: json.loads(data) for name, data in files(folder).items()}


@pytest.mark.parametrize("point, sig", [("study:variant", signal.SIGINT), ("study:rendered", signal.SIGTERM),
                                        ("study:composed", signal.SIGINT), ("write:written", signal.SIGTERM),
                                        ("folder:written", signal.SIGINT)])
def test_an_interrupted_study_leaves_no_side_files(tmp_path, point, sig):
    proc = start_cli_at(point, tmp_path / "reached", *STUDY, "--vary", "lens.ior=1.4,1.5,1.6", "-o",
                        tmp_path / "sheet.png", "--save-study", tmp_path / "study.json", "--save-variants",
                        tmp_path / "variants")
    _, err = signal_and_wait(proc, sig)
    assert proc.returncode == (130 if sig == signal.SIGINT else 143), err
    left = sorted(os.listdir(tmp_path))
    assert left == ["reached"] or point == "folder:written" and left == ["reached", "sheet.png"], left


def test_save_variants_into_a_used_folder_replaces_the_whole_set(tmp_path):
    first = run_cli(*STUDY, "--vary", "lens.ior=1.4:1.6:6", "-o", tmp_path / "a.png", "--save-variants",
                    tmp_path / "variants")
    assert first.returncode == 0, first.stderr
    assert len(files(tmp_path / "variants")) == 6
    second = run_cli(*STUDY, "--vary", "cuts.height=0.5,1,2", "-o", tmp_path / "b.png", "--save-variants",
                     tmp_path / "variants")
    assert second.returncode == 0, second.stderr
    saved = variants(tmp_path / "variants")
    assert sorted(saved) == ["variant-00.json", "variant-01.json", "variant-02.json"]
    assert [v["lamps"][0]["cuts"]["height"] for v in saved.values()] == [0.5, 1, 2]
    assert not [n for n in os.listdir(tmp_path) if n.startswith(".")]  # no temporary folder left


def test_save_variants_into_a_folder_of_other_files_is_refused(tmp_path):
    folder = tmp_path / "variants"
    folder.mkdir()
    (folder / "my-design.json").write_text("{}")
    proc = run_cli(*STUDY, "--vary", "lens.ior=1.4,1.5", "-o", tmp_path / "a.png", "--save-variants", folder)
    assert_bad_input(proc, "variants: --save-variants holds other files than variant presets")
    assert os.listdir(folder) == ["my-design.json"] and not (tmp_path / "a.png").exists()


def test_side_files_without_a_sheet_are_still_written(tmp_path):
    proc = run_cli(*STUDY, "--vary", "lens.ior=1.4,1.5", "--save-study", tmp_path / "s.json", "--save-variants",
                   tmp_path / "v")
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "s.json").exists() and sorted(os.listdir(tmp_path / "v")) == ["variant-00.json",
                                                                                       "variant-01.json"]

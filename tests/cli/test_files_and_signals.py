"""Files and signals: permissions follow the umask, concurrent saves never both win, outputs are
checked before rendering, memory is estimated before rendering, and SIGINT or SIGTERM at any point
of a render or a study leaves no temporary file, no temporary folder and no partial output."""

from __future__ import annotations

import json
import multiprocessing
import os
import shutil
import signal
import subprocess
import sys
import time
import tracemalloc
from pathlib import Path

import numpy as np
import pytest
import save_race
from helpers import ROOT, assert_bad_input, child_pids, process_gone, run_cli, signal_and_wait, start_cli_at

from core_tracer import budget, fileio
from core_tracer.cli import main as cli
from core_tracer.images import imageio
from core_tracer.library import presets as P
from core_tracer.scene.validate import load_scene
from core_tracer.study import definition as st

pytestmark = pytest.mark.slow

BASELINE = ROOT / "presets" / "paper-baseline.json"


def assert_refused(proc: subprocess.CompletedProcess, *needles: str) -> None:
    assert_bad_input(proc, *needles)
    assert proc.stdout == ""


# ---------------------------------------------------------------------------------------------
# Permissions


@pytest.fixture
def umask():
    old = os.umask(0o022)

    def set_mask(mask: int) -> None:
        os.umask(mask)

    yield set_mask
    os.umask(old)


@pytest.mark.parametrize("mask, mode", [(0o022, 0o644), (0o077, 0o600), (0o002, 0o664)])
def test_written_files_get_the_permissions_the_umask_gives(tmp_path, umask, mask, mode):
    umask(mask)
    scene = load_scene(BASELINE)
    image = np.full((4, 4, 3), 0.25, np.float32)
    fileio.atomic_write_text(tmp_path / "a.txt", "x")
    imageio.write_image(tmp_path / "a.exr", image, scene)
    imageio.write_image(tmp_path / "a.png", image, scene)
    library = P.Library("Team", str(tmp_path / "team"), writable=True)
    os.mkdir(library.folder)
    entry = P.save_preset(library, "Red", scene)
    study = st.Study.build(scene, [st.parse_vary("lens.ior=1.4,1.5")], (8, 8))
    study.save(tmp_path / "study.json")
    files = [tmp_path / "a.txt", tmp_path / "a.exr", tmp_path / "a.png", Path(entry.file), tmp_path / "study.json"]
    assert {f.name: oct(f.stat().st_mode & 0o777) for f in files} == {f.name: oct(mode) for f in files}


def test_the_cli_output_is_readable_by_the_team_under_umask_022(tmp_path):
    out = tmp_path / "out.png"
    proc = subprocess.run(["sh", "-c", f'umask 022 && exec "{sys.executable}" -m core_tracer render "{BASELINE}" '
                                       f'-o "{out}" --width 8 --height 8'], cwd=ROOT, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert out.stat().st_mode & 0o777 == 0o644


# ---------------------------------------------------------------------------------------------
# Saving the same new name at the same moment


def test_concurrent_saves_of_one_new_name_never_both_succeed(tmp_path):
    designers, rounds = 4, 40
    folder = tmp_path / "team"
    folder.mkdir()
    ctx = multiprocessing.get_context("spawn")  # a fresh interpreter each (this one may hold Blender)
    barrier = ctx.Barrier(designers)
    results = ctx.Queue()
    procs = [ctx.Process(target=save_race.designer, args=(str(folder), who, rounds, barrier, results))
             for who in range(designers)]
    for p in procs:
        p.start()
    outcomes = [results.get(timeout=120) for _ in range(designers * rounds)]
    for p in procs:
        p.join(timeout=60)
        assert p.exitcode == 0
    for r in range(rounds):
        saved = [who for rr, who, what in outcomes if rr == r and what == "saved"]
        taken = [what for rr, who, what in outcomes if rr == r and what != "saved"]
        assert len(saved) == 1, (r, saved)
        assert len(taken) == designers - 1
        assert all("round-" in t and "exists already" in t for t in taken), taken
        # The file holds the design of the one who was told "saved".
        doc = json.loads((folder / f"round-{r}.json").read_text())
        assert doc["author"] == f"designer {saved[0]}"
    assert sorted(os.listdir(folder)) == sorted(f"round-{r}.json" for r in range(rounds))  # no temporary left


def test_saving_over_an_existing_name_without_overwrite_changes_nothing(tmp_path):
    library = P.Library("Team", str(tmp_path), writable=True)
    scene = load_scene(BASELINE)
    first = P.save_preset(library, "Red", scene)
    before = Path(first.file).read_bytes()
    with pytest.raises(P.PresetExistsError, match="exists already"):
        P.save_preset(library, "Red", dict(scene, author="someone else"))
    assert Path(first.file).read_bytes() == before
    assert os.listdir(tmp_path) == ["red.json"]
    P.save_preset(library, "Red", dict(scene, author="someone else"), overwrite=True)
    assert json.loads(Path(first.file).read_text())["author"] == "someone else"


# ---------------------------------------------------------------------------------------------
# Outputs that cannot be written are found before rendering


def test_an_output_path_that_is_a_folder_is_refused_before_rendering(tmp_path):
    (tmp_path / "out.png").mkdir()
    assert_refused(run_cli("render", BASELINE, "-o", tmp_path / "out.png"), f"{tmp_path / 'out.png'}: ", "folder")
    assert_refused(run_cli("study", BASELINE, "--vary", "lens.ior=1.4,1.5", "-o", tmp_path / "out.png"),
                   f"{tmp_path / 'out.png'}: ", "folder")
    assert os.listdir(tmp_path) == ["out.png"] and os.listdir(tmp_path / "out.png") == []


def _without_root_powers() -> tuple[str, ...]:
    """A command prefix under which a read-only folder is read-only, even for root."""
    if os.geteuid() != 0:
        return ()
    if shutil.which("setpriv") is None:
        pytest.skip("running as root without setpriv: a read-only folder cannot be made")
    return ("setpriv", "--bounding-set=-dac_override,-dac_read_search")


@pytest.mark.parametrize("command", ["render", "study", "render-passes", "study-save"])
def test_a_read_only_output_folder_is_refused_before_rendering_naming_the_users_path(tmp_path, command):
    folder = tmp_path / "shared"
    folder.mkdir()
    prefix = _without_root_powers()
    out = folder / "out.png"
    args = {"render": ("render", BASELINE, "-o", out, "--width", "8", "--height", "8"),
            "render-passes": ("render", BASELINE, "-o", tmp_path / "ok.png", "--passes", folder / "passes"),
            "study": ("study", BASELINE, "--vary", "lens.ior=1.4,1.5", "--size", "8x8", "-o", out),
            "study-save": ("study", BASELINE, "--vary", "lens.ior=1.4,1.5", "--save-study", folder / "s.json",
                           "-o", tmp_path / "ok.png")}[command]
    folder.chmod(0o555)
    try:
        proc = run_cli(*args, prefix=prefix)
    finally:
        folder.chmod(0o755)
    named = {"render": out, "study": out, "render-passes": folder / "passes", "study-save": folder / "s.json"}[command]
    assert_refused(proc, f"error: {named}: ", "Permission denied")
    assert ".tmp" not in proc.stderr
    assert os.listdir(folder) == [] and sorted(os.listdir(tmp_path)) == ["shared"]


def test_a_failed_write_names_the_users_file_not_the_temporary_one(tmp_path):
    gone = tmp_path / "gone" / "out.json"
    with pytest.raises(FileNotFoundError) as info:
        fileio.atomic_write_text(gone, "x")
    assert info.value.filename == str(gone)
    folder_in_the_way = tmp_path / "out.exr"
    (folder_in_the_way / "inside").mkdir(parents=True)
    with pytest.raises(OSError) as info:
        imageio.write_image(folder_in_the_way, np.zeros((2, 2, 3), np.float32))
    assert info.value.filename == str(folder_in_the_way)
    assert sorted(os.listdir(tmp_path)) == ["out.exr"]


# ---------------------------------------------------------------------------------------------
# Memory and time, estimated before rendering


def test_a_render_that_does_not_fit_the_memory_budget_is_refused_before_rendering(tmp_path):
    proc = run_cli("render", BASELINE, "-o", tmp_path / "big.exr", "--width", "8192", "--height", "8192",
                   "--passes", tmp_path / "passes")
    need = budget.render_bytes(8192, 8192, True, "exr")
    assert need > budget.MEMORY_BUDGET
    assert_refused(proc, "image: 8192x8192 px with --passes", f"needs about {need / 2**30:.1f} GB",
                   "allowed at most 4.0 GB", "without --passes")
    assert os.listdir(tmp_path) == []
    # Without the passes the same image fits: only the image and the writer's copy are held.
    assert budget.render_bytes(8192, 8192, False, "exr") < budget.MEMORY_BUDGET


def test_render_keeps_the_passes_only_with_passes(tmp_path):
    """The eight passes (96 bytes a pixel) are held only when --passes asks for them. The image is large
    enough that the passes (192 MB) dwarf the tracer's bands in flight, which vary with the threads."""
    width, height = 2048, 1024
    peaks = {}
    for passes in (False, True):
        args = ["render", str(BASELINE), "-o", str(tmp_path / f"{passes}.exr"), "--width", str(width),
                "--height", str(height)]
        if passes:
            args += ["--passes", str(tmp_path / "passes")]
        tracemalloc.start()
        try:
            assert cli.main(args) == 0
            peaks[passes] = tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()
    pass_bytes = 8 * width * height * 3 * 4
    # (the tracer's bands in flight differ from run to run by a few MB, far less than the passes)
    assert peaks[True] - peaks[False] > 0.75 * pass_bytes, peaks


def _crafted_sheet(path: Path, size: int, axes: list[dict]) -> None:
    """A sheet whose header holds a study nobody should run (the header is text anyone can write)."""
    doc = {"schema": "lamp-study/1", "base": json.loads(BASELINE.read_text()), "axes": axes, "size": [size, size]}
    imageio.write_image(path, np.zeros((4, 4, 3), np.float32), attributes={st.STUDY_ATTRIBUTE: json.dumps(doc)})


def test_a_study_is_bounded_by_its_total_pixels(tmp_path):
    sheet = tmp_path / "crafted.png"
    axes = [{"parameter": "lens.ior", "range": [1.4, 1.6], "steps": 8},
            {"parameter": "cuts.height", "range": [0.5, 2], "steps": 8}]
    _crafted_sheet(sheet, 2048, axes)
    proc = run_cli("study", "--study", sheet, "-o", tmp_path / "out.png")
    assert_refused(proc, f"{sheet}: ", "64 variants of 2048x2048 px are 268,435,456 pixels",
                   "allowed at most 16,777,216 in one study", "at most 512x512 px each")
    assert sorted(os.listdir(tmp_path)) == ["crafted.png"]
    # The same from the command line, and at the limit it is accepted (not rendered here).
    proc = run_cli("study", BASELINE, "--vary", "lens.ior=1.4:1.6:8", "--vary", "cuts.height=0.5:2:8",
                   "--size", "2048x2048", "-o", tmp_path / "out.png")
    assert_refused(proc, "size: 64 variants of 2048x2048 px")
    base = load_scene(BASELINE)
    assert len(st.Study.build(base, axes, (512, 512))) == 64
    with pytest.raises(st.SceneError, match="size: 64 variants of 513x512"):
        st.Study.build(base, axes, (513, 512))


# ---------------------------------------------------------------------------------------------
# Signals at every step


INT, TERM = signal.SIGINT, signal.SIGTERM
# Every point of both commands; each signal at half of them, both at the temporary file's two points.
CASES = [("render", "render:checked", TERM), ("render", "render:band", INT), ("render", "render:band", TERM),
         ("render", "render:rendered", INT), ("render", "write:created", INT), ("render", "write:created", TERM),
         ("render", "write:written", INT), ("render", "write:written", TERM),
         ("study", "study:checked", INT), ("study", "study:started", TERM), ("study", "study:variant", INT),
         ("study", "study:variant", TERM), ("study", "study:rendered", INT), ("study", "study:rendered", TERM),
         ("study", "study:composed", TERM), ("study", "write:created", TERM), ("study", "write:written", INT)]


@pytest.mark.skipif(not os.path.isdir("/proc"), reason="finds the worker processes through /proc")
@pytest.mark.parametrize("command, point, sig", CASES, ids=[f"{c}-{p}-{s.name}" for c, p, s in CASES])
def test_a_signal_at_any_step_leaves_nothing_behind(tmp_path, command, point, sig):
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    temp = tmp_path / "tmp"  # the temporary folder of the program: lamp-study-* folders go here
    temp.mkdir()
    marker = tmp_path / "reached"
    env = dict(os.environ, TMPDIR=str(temp))
    if command == "render":
        args = ["render", BASELINE, "-o", out_dir / "lamp.exr", "--width", "96", "--height", "400",
                "--passes", out_dir / "passes"]
    else:
        args = ["study", BASELINE, "--vary", "lens.ior=1.4,1.5,1.6", "--size", "16x16", "--workers", "2",
                "--engine", "processes",
                "-o", out_dir / "sheet.png", "--save-variants", out_dir / "variants"]
    proc = start_cli_at(point, marker, *args, env=env)  # waits there for the signal
    workers = child_pids(proc.pid)
    out, err = signal_and_wait(proc, sig)
    expected = (130, "interrupted") if sig == signal.SIGINT else (143, "terminated")
    assert (proc.returncode, err.strip()) == expected, err
    assert out == ""
    leftovers = sorted(str(p.relative_to(out_dir)) for p in out_dir.rglob("*"))
    # --save-variants writes the variant presets before rendering: they may be there, complete.
    leftovers = [p for p in leftovers if not (p == "variants" or p.startswith("variants/variant-"))]
    assert leftovers == [] or leftovers == ["passes"] and command == "render", leftovers
    assert os.listdir(temp) == []
    assert all(process_gone(pid) for pid in workers)
    if command == "study" and point in ("study:started", "study:variant"):
        assert workers  # the workers ran when the signal came, and are gone now


@pytest.mark.skipif(not os.path.isdir("/proc"), reason="finds the worker processes through /proc")
def test_the_folder_of_a_study_killed_with_sigkill_is_removed_by_the_next_study(tmp_path):
    """SIGKILL leaves no chance to clean up; the next study removes what the dead one left."""
    temp = tmp_path / "tmp"
    temp.mkdir()
    marker = tmp_path / "reached"
    env = dict(os.environ, TMPDIR=str(temp))
    args = ["study", BASELINE, "--vary", "lens.ior=1.4,1.5,1.6", "--size", "16x16", "--workers", "1",
            "--engine", "processes", "-o", tmp_path / "sheet.png"]
    proc = start_cli_at("study:variant", marker, *args, env=env)
    workers = child_pids(proc.pid)
    signal_and_wait(proc, signal.SIGKILL)
    (left,) = os.listdir(temp)
    assert left.startswith(f"lamp-study-{proc.pid}-")
    # A live process's folder is never touched (this test's own pid stands in for a running study).
    (temp / f"lamp-study-{os.getpid()}-running").mkdir()
    deadline = time.monotonic() + 60
    while not all(process_gone(pid) for pid in workers):  # the orphaned worker notices and stops
        assert time.monotonic() < deadline
        time.sleep(0.05)
    env = dict(os.environ, TMPDIR=str(temp))
    proc = run_cli(*args, env=env)
    assert proc.returncode == 0, proc.stderr
    assert os.listdir(temp) == [f"lamp-study-{os.getpid()}-running"]


def test_a_study_sheet_is_held_within_the_memory_budget():
    budget.check_study((512, 512), 64, (4500, 4700))  # the largest study: about 1.3 GB
    with pytest.raises(st.SceneError, match=r"size: the study needs about 8\.\d GB of memory; allowed at most 4\.0 GB"):
        budget.check_study((64, 64), 4, (20000, 9000))  # a sheet made enormous by its labels

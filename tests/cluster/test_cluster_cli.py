"""The study command on the Dask engine: the cache figures it prints, Ctrl-C and SIGTERM at every
step leave no sheet, no scratch folder and no worker process (a terminal's Ctrl-C, which reaches
the whole process group, included), and a scheduler that is not there is one line."""

from __future__ import annotations

import os
import signal
import subprocess
import time

import pytest
from helpers import (
    BASELINE,
    ROOT,
    cli_command,
    descendants,
    process_gone,
    run_cli,
    signal_and_wait,
    start_cli_at,
)

from core_tracer.checkpoints import ENV_MARKER, ENV_POINT

pytestmark = [pytest.mark.slow, pytest.mark.skipif(not os.path.isdir("/proc"), reason="reads /proc")]

STUDY = ("study", BASELINE, "--vary", "lens.ior=1.4:1.6:3", "--size", "64x64", "--workers", "2",
         "--engine", "dask")
# The same study on the default engine, the local worker pool (cluster/local_pool.py), and the words
# each summary names it with.
ENGINES = {"dask": (STUDY, "local Dask cluster: 2 worker processes x 1 thread"),
           "pool": (STUDY[:-2], "local worker pool: 2 worker processes x 1 thread")}


def environment(tmp_path) -> dict:
    temp = tmp_path / "tmp"
    temp.mkdir(exist_ok=True)
    env = dict(os.environ, TMPDIR=str(temp), LAMP_STYLING_CACHE=str(tmp_path / "cache"))
    env.pop("DASK_SCHEDULER_ADDRESS", None)  # the default engine is then the local pool
    return env


@pytest.mark.parametrize("engine", ENGINES)
def test_the_study_command_renders_on_dask_and_then_from_its_cache(tmp_path, engine):
    study, named = ENGINES[engine]
    env = environment(tmp_path)
    first = run_cli(*study, "-o", tmp_path / "a.exr", env=env)
    assert first.returncode == 0, first.stderr
    assert named in first.stdout
    assert "(3 rendered, 0 from the cache)" in first.stdout
    wider = [a if a != "lens.ior=1.4:1.6:3" else "lens.ior=1.4,1.5,1.6,1.7" for a in study]
    second = run_cli(*wider, "-o", tmp_path / "b.exr", env=env)
    assert second.returncode == 0, second.stderr
    assert "(1 rendered, 3 from the cache)" in second.stdout  # 1.7 is new
    assert os.listdir(tmp_path / "tmp") == []  # the cluster's scratch space went with it


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("point, sig", [("study:started", signal.SIGINT), ("study:variant", signal.SIGTERM),
                                        ("study:variant", signal.SIGINT)])
def test_a_signal_during_a_dask_study_leaves_nothing(tmp_path, point, sig, engine):
    env = environment(tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    proc = start_cli_at(point, tmp_path / "reached", *ENGINES[engine][0], "-o", out / "sheet.png", env=env)
    family = descendants(proc.pid)
    stdout, err = signal_and_wait(proc, sig)
    expected = (130, "interrupted") if sig == signal.SIGINT else (143, "terminated")
    assert (proc.returncode, err.strip()) == expected, err
    assert stdout == "" and os.listdir(out) == [] and os.listdir(tmp_path / "tmp") == []
    if engine == "dask" or point == "study:variant":  # the pool forks its workers at the first task
        assert len(family) >= 2  # the workers (and their nannies' helpers) ran
    deadline = time.monotonic() + 10
    while not all(process_gone(p) for p in family):
        assert time.monotonic() < deadline, [p for p in family if not process_gone(p)]
        time.sleep(0.05)


def test_a_terminals_ctrl_c_reaches_the_workers_too_and_ends_in_one_line(tmp_path):
    """Ctrl-C in a terminal signals the whole process group: the workers get it as well."""
    env = environment(tmp_path)
    marker = tmp_path / "reached"
    env.update({ENV_POINT: "study:variant", ENV_MARKER: str(marker)})
    proc = subprocess.Popen(cli_command(*STUDY, "-o", tmp_path / "sheet.png"), cwd=ROOT, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        deadline = time.monotonic() + 120
        while not marker.exists():
            assert proc.poll() is None and time.monotonic() < deadline, proc.communicate()
            time.sleep(0.01)
        family = descendants(proc.pid)
        os.killpg(proc.pid, signal.SIGINT)
        _, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert (proc.returncode, err.strip()) == (130, "interrupted"), err
    assert not (tmp_path / "sheet.png").exists()
    deadline = time.monotonic() + 10
    while not all(process_gone(p) for p in family):
        assert time.monotonic() < deadline
        time.sleep(0.05)


def test_a_scheduler_that_is_not_there_is_one_line(tmp_path):
    proc = run_cli(*STUDY[:-2], "--scheduler", "tcp://127.0.0.1:9", "-o", tmp_path / "s.png",
                   env=dict(environment(tmp_path), DASK_DISTRIBUTED__COMM__TIMEOUTS__CONNECT="2s"))
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.count("\n") == 1 and "--scheduler" in proc.stderr and "Traceback" not in proc.stderr
    assert not (tmp_path / "s.png").exists()


def test_workers_0_with_a_scheduler_is_refused_in_one_line(tmp_path):
    proc = run_cli(*STUDY[:-2], "--workers", "0", "--scheduler", "tcp://127.0.0.1:9", "-o", tmp_path / "s.png")
    assert proc.returncode == 2 and "--workers" in proc.stderr and "allowed 1 or more" in proc.stderr

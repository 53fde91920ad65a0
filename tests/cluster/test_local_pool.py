"""The local worker pool (``cluster.local_pool``, issue 34 item 3): a study's cells on this machine
without Dask's start-up and without Dask, the same images as one process. (Its cache and its
Ctrl-C/SIGTERM are checked with the Dask engine's, tests/cluster/test_cluster_cli.py.)"""

from __future__ import annotations

import os
import subprocess
import sys
import time

import numpy as np
import pytest
from helpers import BASELINE, ROOT, process_gone, run_cli

from core_tracer.cluster import local_pool
from core_tracer.images.imageio import read_image

pytestmark = [pytest.mark.slow, pytest.mark.skipif(not os.path.isdir("/proc"), reason="reads /proc")]

STUDY = ("study", BASELINE, "--vary", "lens.ior=1.4:1.6:3", "--size", "48x48")


def environment(tmp_path) -> dict:
    env = dict(os.environ, LAMP_STYLING_CACHE=str(tmp_path / "cache"))
    env.pop("DASK_SCHEDULER_ADDRESS", None)  # the default engine is then the local pool
    return env


def test_a_study_on_the_pool_is_the_same_sheet_as_in_one_process(tmp_path):
    env = environment(tmp_path)
    for name, engine in (("pool.exr", ()), ("here.exr", ("--workers", "0"))):
        done = run_cli(*STUDY, *engine, "--no-cache", "-o", tmp_path / name, env=env)
        assert done.returncode == 0, done.stderr
    assert np.array_equal(read_image(str(tmp_path / "pool.exr"))[0], read_image(str(tmp_path / "here.exr"))[0])


def test_the_local_path_needs_no_dask_and_starts_at_once(tmp_path):
    """Blender's Python has no Dask: a study on the pool never imports it. The pool's workers are
    forked, so the first task's answer comes without an interpreter's start (a local Dask cluster
    took 5-14 s here)."""
    code = f"""
import sys, time
sys.path.insert(0, {str(ROOT)!r})
from core_tracer.cluster import local_pool
from core_tracer.study import on_cluster as cluster_study
from core_tracer.scene.reading import read_json
from core_tracer.study import definition as st
study = st.Study.build(read_json({str(BASELINE)!r}), [st.parse_vary("lens.ior=1.4,1.6")], (16, 16))
images, count = cluster_study.run_study(study, None, 2)
assert count.rendered == 2 and images[0].shape == (16, 16, 3)
start = time.perf_counter()
with local_pool.LocalPool(2) as pool:
    pid = pool.submit(__import__("os").getpid).result()
print(time.perf_counter() - start, pid, "distributed" in sys.modules)
"""
    env = environment(tmp_path)
    done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    seconds, pid, dask = done.stdout.split()
    assert dask == "False" and int(pid) != os.getpid()
    assert float(seconds) < 2.0, seconds  # measured 0.01-0.05 s on the loaded 2-core machine


def test_a_scheduler_by_name_or_address_goes_to_dask(monkeypatch):
    monkeypatch.delenv("DASK_SCHEDULER_ADDRESS", raising=False)
    assert not local_pool.dask_wanted(None)
    assert local_pool.dask_wanted("local") and local_pool.dask_wanted("tcp://10.0.0.1:8786")
    monkeypatch.setenv("DASK_SCHEDULER_ADDRESS", "tcp://10.0.0.1:8786")
    assert local_pool.dask_wanted(None)


def test_the_workers_end_with_a_command_killed_outright(tmp_path):
    """SIGKILL leaves no cleanup to run: a forked worker, which holds both ends of its task queue,
    would wait on it for ever; the kernel ends it with its parent (PR_SET_PDEATHSIG)."""
    code = f"""
import os, sys, time
sys.path.insert(0, {str(ROOT)!r})
from core_tracer.cluster import local_pool
pool = local_pool.LocalPool(2)
pool.submit(time.sleep, 0.01).result()
print(" ".join(str(p) for p in pool.executor._processes), flush=True)
time.sleep(600)
"""
    proc = subprocess.Popen([sys.executable, "-c", code], env=environment(tmp_path), stdout=subprocess.PIPE, text=True)
    try:
        workers = [int(p) for p in proc.stdout.readline().split()]
        assert len(workers) == 2 and not any(process_gone(p) for p in workers)
    finally:
        proc.kill()
        proc.wait()
    deadline = time.monotonic() + 10
    while not all(process_gone(p) for p in workers):
        assert time.monotonic() < deadline, [p for p in workers if not process_gone(p)]
        time.sleep(0.05)

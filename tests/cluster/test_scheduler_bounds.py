"""Schedulers and workers bounded (issue 33 item 2): a scheduler that accepts and never answers
ends ``study`` within its connect timeout, and Ctrl-C or SIGTERM end it at once while it waits, in
one line; malformed addresses (``--scheduler``, ``DASK_SCHEDULER_ADDRESS``) refused before use;
worker counts bounded by the machine; an error that is not the connection names its own cause."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import threading
import time

import pytest
from helpers import BASELINE, ROOT, assert_bad_input, cli_command, run_cli
from needs import require

from core_tracer.cluster import engine
from core_tracer.scene.reading import SceneError

require("distributed")

STUDY = ("study", BASELINE, "--vary", "lens.ior=1.4,1.6", "--size", "24x24", "--no-cache")


class MuteServer:
    """A TCP server on 127.0.0.1 that accepts every connection and never sends a byte."""

    def __init__(self) -> None:
        self.sock = socket.socket()
        self.sock.bind(("127.0.0.1", 0))
        self.sock.listen(16)
        self.address = f"tcp://127.0.0.1:{self.sock.getsockname()[1]}"
        self.accepted = threading.Event()
        self.conns: list[socket.socket] = []
        threading.Thread(target=self._serve, daemon=True).start()

    def _serve(self) -> None:
        while True:
            try:
                conn, _ = self.sock.accept()
            except OSError:
                return
            self.conns.append(conn)
            self.accepted.set()

    def close(self) -> None:
        for c in self.conns:
            c.close()
        self.sock.close()


@pytest.fixture
def mute():
    server = MuteServer()
    yield server
    server.close()


@pytest.mark.slow
def test_a_scheduler_that_accepts_and_never_answers_ends_the_study_in_one_line(tmp_path, mute):
    env = dict(os.environ, DASK_DISTRIBUTED__COMM__TIMEOUTS__CONNECT="2s")
    start = time.monotonic()
    done = run_cli(*STUDY, "--scheduler", mute.address, "-o", tmp_path / "s.png", env=env, timeout=120)
    assert mute.accepted.is_set()
    assert_bad_input(done, "--scheduler", "no answer from", "within 4 s")
    assert time.monotonic() - start < 60
    assert not (tmp_path / "s.png").exists()


@pytest.mark.slow
@pytest.mark.parametrize("sig, word", [(signal.SIGINT, "interrupted"), (signal.SIGTERM, "terminated")])
def test_ctrl_c_and_sigterm_end_a_study_waiting_on_a_mute_scheduler_at_once(tmp_path, mute, sig, word):
    proc = subprocess.Popen(cli_command(*STUDY, "--scheduler", mute.address, "-o", tmp_path / "s.png"), cwd=ROOT,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert mute.accepted.wait(120), "the study never connected"
        time.sleep(0.5)  # inside Dask's handshake, which never ends
        sent = time.monotonic()
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert time.monotonic() - sent < 10
    assert err.strip() == word and "Traceback" not in err
    assert not (tmp_path / "s.png").exists()


@pytest.mark.parametrize("address", ["tcp://", "http://host:1", "tcp://a b:1", "tcp://host:99999", "tcp://host:-1",
                                     "host", "tcp://[::1", ":::", "tcp://host:1/path", "tcp://h\x01:1",
                                     "inproc://x", "tcp://user@host:1", "x" * 300, "tcp://host:port",
                                     "tcp://-bad-:1", "ucx://host:1", "tcp://host:1?x=1", "tcp://\ud800:1"])
def test_a_malformed_address_is_refused_before_use(address):
    with pytest.raises(SceneError) as e:
        engine.check_address(address)
    assert e.value.path == "--scheduler" and "allowed tcp://HOST:PORT" in e.value.message
    assert "\n" not in e.value.message and "\x01" not in e.value.message


@pytest.mark.parametrize("address, normal", [("tcp://127.0.0.1:8786", "tcp://127.0.0.1:8786"),
                                             ("host.example:8786", "tcp://host.example:8786"),
                                             ("tls://[::1]:8786", "tls://[::1]:8786")])
def test_well_formed_addresses_pass(address, normal):
    assert engine.check_address(address) == normal


@pytest.mark.slow
def test_a_malformed_dask_scheduler_address_is_named_as_the_variable(tmp_path):
    env = dict(os.environ, DASK_SCHEDULER_ADDRESS="tcp://nowhere:99999")
    done = run_cli(*STUDY, "--engine", "dask", "-o", tmp_path / "s.png", env=env)
    assert_bad_input(done, "DASK_SCHEDULER_ADDRESS", "port from 1 to 65535")


@pytest.mark.slow
@pytest.mark.parametrize("command", ["study", "optimise"])
def test_100000_workers_are_refused_in_one_line(tmp_path, command):
    if command == "study":
        done = run_cli(*STUDY, "--workers", "100000", "-o", tmp_path / "s.png", timeout=60)
    else:
        spec = ROOT / "docs" / "examples" / "even-stop-lamp.optimise.json"  # refused before its study opens
        done = run_cli("optimise", spec, "--workers", "100000", "-o", tmp_path / "out", timeout=60)
    assert_bad_input(done, "--workers", "100000 is out of range", f"to {engine.max_workers()} on this machine")


def test_the_worker_bound_follows_the_machine():
    assert 1 <= engine.max_workers() <= engine.WORKERS_PER_CORE * (os.cpu_count() or 1)
    engine.check_workers(engine.max_workers())
    with pytest.raises(SceneError):
        engine.check_workers(engine.max_workers() + 1)


@pytest.mark.slow
@pytest.mark.parametrize("cache", ["/dev/null", "x" * 5000])
def test_a_cache_that_cannot_be_a_folder_names_the_cache_not_the_scheduler(tmp_path, cache):
    """Every OSError used to be 'cannot reach the scheduler', even a file where the cache folder should be."""
    done = run_cli(*STUDY[:-1], "--engine", "dask", "--cache", cache, "-o", tmp_path / "s.png")
    line = assert_bad_input(done, "--cache", "cannot hold the cache")
    assert "scheduler" not in line


@pytest.mark.slow
def test_optimise_on_a_mute_scheduler_ends_in_one_line(tmp_path, mute):
    import shutil

    for name in ("liked-look.optimise.json", "liked-look.exr", "paper-baseline.json"):  # its study stays in tmp
        shutil.copy(ROOT / "docs" / "examples" / name, tmp_path / name)
    spec = tmp_path / "liked-look.optimise.json"
    env = dict(os.environ, DASK_DISTRIBUTED__COMM__TIMEOUTS__CONNECT="2s")
    done = run_cli("optimise", spec, "--scheduler", mute.address, "--no-cache", "-o", tmp_path / "out", env=env,
                   timeout=120)
    assert mute.accepted.is_set()
    assert_bad_input(done, "--scheduler", "no answer from")

"""``states`` and ``relight`` from the command line (docs/measures.md, "Lighting states")."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from helpers import run_cli

ROOT = Path(__file__).resolve().parents[2]
PRESET = ROOT / "presets" / "four-lamp-night-lit-photometric.json"


@pytest.fixture(scope="module")
def states(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("states") / "night.npz"
    done = run_cli("states", PRESET, "-o", path, "--width", 48, "--height", 32, "--samples", 1)
    assert done.returncode == 0, done.stderr
    assert "one walk for 8 states and the surroundings" in done.stdout  # one walk, not a render per state
    assert "state 1 of" not in done.stdout
    return path


@pytest.mark.slow
def test_relight_lists_the_states_and_writes_images(states, tmp_path):
    listed = run_cli("relight", states, "--list")
    assert listed.returncode == 0
    assert "Turn (lamp 3, P21/5W) (also lamps[2].stop)" in listed.stdout  # named by function (issue 31)
    assert listed.stdout.splitlines()[1].split()[:2] == ["on", "tail"]
    assert listed.stdout.splitlines()[2].split()[:2] == ["off", "tail.stop_filament"]
    exr, only_tail = tmp_path / "design.exr", tmp_path / "tail.exr"
    assert run_cli("relight", states, "-o", exr).returncode == 0
    done = run_cli("relight", states, "-o", only_tail, "--off", "stop,turn,reversing")
    assert done.returncode == 0 and "lit: surroundings, tail" in done.stdout, done.stdout
    old_keys = tmp_path / "tail-old-keys.exr"  # the keys of earlier versions still work
    old_off = "lamps[1].stop,lamps[2].stop,lamps[3].stop"
    assert run_cli("relight", states, "-o", old_keys, "--off", old_off).returncode == 0
    import OpenImageIO as oiio

    def luminance(path):
        image = oiio.ImageBuf(str(path))
        return image.get_pixels(oiio.FLOAT)[..., image.spec().channelnames.index("Y")]

    design, tail = luminance(exr), luminance(only_tail)
    assert np.array_equal(tail, luminance(old_keys))
    off = design - tail  # cd/m2: the three lamps switched off
    assert off.min() >= -1e-5 * design.max() and off.max() > 1000.0
    png = tmp_path / "stop.png"
    assert run_cli("relight", states, "-o", png, "--level", "stop=500", "--ev100", "12").returncode == 0
    assert png.stat().st_size > 0


@pytest.mark.slow
@pytest.mark.parametrize("args, words", [
    (["--on", "lamps[7].stop"], "error: lamps[7].stop: not a state of this design; allowed surroundings"),
    (["--level", "lamps[0].stop=lots"], "error: --level: 'lamps[0].stop=lots' is not KEY=VALUE"),
    (["--level", "turn=-5"], "error: turn: -5.0 is out of range; allowed [0, 100000] lm"),
    (["--on", "lamps[0].stop", "--off", "lamps[0].stop"], "error: --off: lamps[0].stop is also given to --on"),
    (["--on", "turn", "--off", "lamps[2].stop"], "error: --off: lamps[2].stop is also given to --on"),
])
def test_bad_states_are_refused_in_one_line(states, tmp_path, args, words):
    out = tmp_path / "x.png"
    done = run_cli("relight", states, "-o", out, *args)
    assert done.returncode == 2 and done.stderr.strip().startswith(words), done.stderr
    assert len(done.stderr.strip().splitlines()) == 1 and not out.exists()


@pytest.mark.slow
def test_a_file_that_is_not_a_states_file_is_refused(tmp_path):
    bogus = tmp_path / "bogus.npz"
    np.savez(bogus, header=np.zeros(3))
    done = run_cli("relight", bogus, "-o", tmp_path / "x.png")
    assert done.returncode == 2 and "is not a light-states file of this version" in done.stderr
    assert len(done.stderr.strip().splitlines()) == 1
    done = run_cli("states", PRESET, "-o", tmp_path / "x.exr")
    assert done.returncode == 2 and "allowed a name ending .npz" in done.stderr

"""``python -m core_tracer measure`` run as a program (subprocess, as Blender's extension CLI is tested)."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest


def _run(repo_root, *args, timeout=600):
    return subprocess.run([sys.executable, "-m", "core_tracer", "measure", *map(str, args)], cwd=repo_root,
                          capture_output=True, text=True, timeout=timeout)


def test_a_paper_scene_is_refused_naming_the_field(repo_root, tmp_path):
    proc = _run(repo_root, repo_root / "presets" / "four-lamp-night-lit.json", "-o", tmp_path / "out")
    assert proc.returncode == 2
    assert proc.stderr.count("\n") == 1 and "light_model" in proc.stderr and "photometric" in proc.stderr
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("option", [["--function", "3=stop"], ["--function", "0=brake"], ["--pixel-mm", "0"],
                                    ["--replicates", "0"]])
def test_bad_options_are_one_line_naming_the_option(repo_root, tmp_path, option):
    proc = _run(repo_root, repo_root / "presets" / "photometric-stop-lamp.json", "-o", tmp_path / "out", *option)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.count("\n") == 1 and option[0] in proc.stderr and "allowed" in proc.stderr


@pytest.mark.slow
def test_measure_the_stop_lamp(repo_root, tmp_path):
    """The shipped photometric stop lamp (a P21/5W stop filament behind a red lens) measured as a stop
    lamp: measures.json holds both regulations' rows, its red colour and the homogeneity figures;
    the page is written."""
    out = tmp_path / "report"
    proc = _run(repo_root, repo_root / "presets" / "photometric-stop-lamp.json", "-o", out, "--pixel-mm", "3",
                "--replicates", "2", "--no-beam-files")
    assert proc.returncode == 0, proc.stderr
    result = json.loads((out / "measures.json").read_text(encoding="utf-8"))
    assert set(result["functions"]) == {"stop"}
    assert set(result["verdicts"]) == {"R148 S1", "FMVSS stop"}
    hv = next(r for r in result["rows"] if r["function"] == "R148 S1" and r["point"] == "H-V" and r["kind"] == "min")
    assert hv["required"] == 60 and hv["simulated"] > 0 and hv["stderr"] >= 0
    assert result["functions"]["stop"]["colour"]["inside"] == {"UN R48 §2.29": True, "SAE J578": True}
    assert 0 < result["homogeneity"]["stop"]["lmin_over_lmax"] <= 1
    assert (out / "measures.png").stat().st_size > 50_000
    assert sorted(p.name for p in out.iterdir()) == ["measures.json", "measures.png"]

"""``python -m core_tracer measure`` run as a program (subprocess, as Blender's extension CLI is tested)."""

from __future__ import annotations

import json

import pytest
from helpers import run_cli


@pytest.mark.slow
def test_a_paper_scene_is_refused_naming_the_field(repo_root, tmp_path):
    proc = run_cli("measure", repo_root / "presets" / "four-lamp-night-lit.json", "-o", tmp_path / "out")
    assert proc.returncode == 2
    assert proc.stderr.count("\n") == 1 and "light_model" in proc.stderr and "photometric" in proc.stderr
    assert not (tmp_path / "out").exists()


@pytest.mark.slow
@pytest.mark.parametrize("option", [["--function", "3=stop"], ["--function", "0=brake"], ["--pixel-mm", "0"],
                                    ["--replicates", "0"]])
def test_bad_options_are_one_line_naming_the_option(repo_root, tmp_path, option):
    proc = run_cli("measure", repo_root / "presets" / "photometric-stop-lamp.json", "-o", tmp_path / "out", *option)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.count("\n") == 1 and option[0] in proc.stderr and "allowed" in proc.stderr


@pytest.mark.slow
def test_measure_the_stop_lamp(repo_root, tmp_path):
    """The shipped photometric stop lamp (a P21/5W stop filament behind a red lens) measured as a stop
    lamp: measures.json holds both regulations' rows, its red colour and the homogeneity figures;
    the page is written."""
    out = tmp_path / "report"
    proc = run_cli("measure", repo_root / "presets" / "photometric-stop-lamp.json", "-o", out, "--pixel-mm", "3",
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


def _strict_json(path) -> dict:
    """measures.json read as strict JSON (RFC 8259): NaN, Infinity and -Infinity refused."""

    def refuse(constant):
        raise ValueError(f"{path}: {constant} is not JSON")

    return json.loads(path.read_text(encoding="utf-8"), parse_constant=refuse)


@pytest.mark.slow
def test_a_missing_output_parent_is_refused_before_any_work(repo_root, tmp_path):
    """Before: the measuring ran a minute, then the folder could not be made."""
    proc = run_cli("measure", repo_root / "presets" / "photometric-stop-lamp.json", "-o", tmp_path / "no" / "report",
                   timeout=60)
    assert proc.returncode == 2, proc.stderr
    assert proc.stdout == "" and proc.stderr.count("\n") == 1 and "does not exist" in proc.stderr
    assert "--output" in proc.stderr and str(tmp_path / "no") in proc.stderr


@pytest.mark.slow
def test_a_failing_verdict_exits_1_and_one_replicate_writes_strict_json(repo_root, tmp_path):
    """The stop lamp measured as a tail lamp fails R1's 17 cd maximum: exit 1 (before: 0), ``--exit-zero``
    keeps 0; with one replicate the standard errors are missing: null, not NaN (before: 101 NaN)."""
    scene = repo_root / "presets" / "photometric-stop-lamp.json"
    options = ["--function", "0=tail", "--pixel-mm", "5", "--replicates", "1", "--no-beam-files"]
    proc = run_cli("measure", scene, "-o", tmp_path / "a", *options)
    assert proc.returncode == 1, proc.stderr
    assert "fails R148 R1" in proc.stdout.splitlines()[-1]
    result = _strict_json(tmp_path / "a" / "measures.json")
    assert result["verdicts"] == {"R148 R1": False, "FMVSS taillamp": False}
    assert all(row["stderr"] is None for row in result["rows"] if row["kind"] == "min")
    assert all(err is None for *_, err in result["intensities_cd"]["tail"])
    assert run_cli("measure", scene, "-o", tmp_path / "b", *options, "--exit-zero").returncode == 0


@pytest.mark.slow
def test_measures_json_names_its_schema_tool_date_and_scene(repo_root, tmp_path):
    import datetime

    from core_tracer import __version__
    from core_tracer.library.presets import digest
    from core_tracer.scene import load_scene

    scene = repo_root / "presets" / "photometric-stop-lamp.json"
    proc = run_cli("measure", scene, "-o", tmp_path / "a", "--pixel-mm", "5", "--replicates", "2", "--no-beam-files")
    assert proc.returncode == 0, proc.stderr
    result = _strict_json(tmp_path / "a" / "measures.json")
    assert result["schema"] == "lamp-measures/1"
    assert result["tool"] == {"name": "core_tracer", "version": __version__}
    when = datetime.datetime.fromisoformat(result["date"])
    assert abs((datetime.datetime.now(datetime.UTC) - when).total_seconds()) < 600
    assert result["scene_digest"] == digest(load_scene(scene))
    assert all(row["stderr"] is not None for row in result["rows"] if row["kind"] == "min")

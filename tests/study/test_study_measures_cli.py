"""``study --measure/--sort/--filter`` from the command line."""

from __future__ import annotations

import pytest
from helpers import BASELINE, PRESETS, run_cli

from core_tracer.study import definition as st

STOP = PRESETS / "photometric-stop-lamp.json"


@pytest.mark.slow
@pytest.mark.parametrize(("args", "line"), [
    (["--measure", "grid.passes"], "error: --measure: grid.passes is not a measure; allowed colour.distance_outside"),
    (["--sort=-grid.passes"], "error: --sort: \"-grid.passes\" is not a measure, or \"-\" and one; allowed"),
    (["--filter", "grid.pass=1"], "error: --filter: \"grid.pass=1\" is not MEASURE OPERATOR NUMBER"),
])
def test_bad_measure_options_are_one_line(tmp_path, args, line):
    done = run_cli("study", STOP, "--vary", "lens.ior=1.45,1.6", *args, "-o", tmp_path / "s.png")
    assert done.returncode == 2 and done.stderr.startswith(line) and done.stderr.count("\n") == 1
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_measures_of_a_paper_design_are_refused(tmp_path):
    done = run_cli("study", BASELINE, "--vary", "lens.ior=1.45,1.6", "--measure", "grid.pass", "-o", tmp_path / "s.png")
    assert done.returncode == 2 and "--measure: measures need a photometric design" in done.stderr


@pytest.mark.slow
def test_a_filtered_study_names_the_left_out_and_keeps_its_fields(tmp_path):
    sheet = tmp_path / "s.png"
    # A deep cut spreads the light: its H-V intensity is the lower (see docs/study-sorted-by-measure.png).
    args = ("study", STOP, "--vary", "cuts.height=0.5,3", "--size", "32x24", "--workers", "1", "--engine",
            "processes", "--measure", "intensity.hv_cd", "--filter", "intensity.hv_cd>100", "--cache", tmp_path / "c")
    done = run_cli(*args, "-o", sheet, timeout=600)
    assert done.returncode == 0, done.stderr
    assert "measured 2 variants in" in done.stdout and "left out by the filter: #2" in done.stdout
    again = run_cli(*args, "-o", tmp_path / "again.png", timeout=600)  # the values come from the cache
    seconds = float(again.stdout.split("measured 2 variants in ")[1].split(" s")[0])
    assert seconds < 2.0 and "left out by the filter: #2" in again.stdout
    study = st.Study.load(sheet)  # the sheet carries the measures with the study
    assert study.measured.names == ("intensity.hv_cd",) and str(study.measured.filters[0]) == "intensity.hv_cd>100"

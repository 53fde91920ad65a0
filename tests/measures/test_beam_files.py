"""Beam files a lighting tool accepts (issue 31, item 5): read back by two parsers the project did not
write, photompy 0.3.1 (IES and EULUMDAT, MIT) and pyldt (eulumdat-py 1.0.0, MIT); the LM-63-2002
keywords; LORL and DFF from the flux; the colour fields; the design's and the file's names; the grid.

The slow test measures the photometric stop lamp: interpolating its IES file with photompy's own
bilinear interpolation gives the report's grid points within 2 % beyond the two estimates' standard
errors, and photompy's integral of the file is the light-traced flux leaving the lamp within 2 %."""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest

from core_tracer.measures import export as E
from core_tracer.measures.directions import direction

photompy = pytest.importorskip("photompy")


def cosine_beam(grid: E.BeamGrid, peak: float = 300.0, flux: float = 440.0, out: float | None = 100.0,
                xy=(0.69, 0.30)) -> E.Distribution:
    """I = peak cos γ on the lamp's hemisphere: Φ = π × peak (a Lambertian plate)."""
    c, gamma = grid.c_angles(), grid.gamma_angles()
    cd = np.repeat(peak * np.cos(np.radians(gamma))[None, :], len(c), axis=0)
    return E.Distribution(c, gamma, cd, flux, "stop", out, 0.1 if out else None, xy, "Round stop lamp", "2026-12-07")


def test_the_integral_of_a_cosine_beam_is_pi_times_its_peak():
    for grid in (E.BeamGrid(), E.COARSE_GRID):
        dist = cosine_beam(grid)
        assert dist.integral_lm() == pytest.approx(math.pi * 300.0, rel=3e-3)  # linear between the γ angles
        assert dist.dff_percent == pytest.approx(100.0)


def test_lorl_is_the_flux_leaving_over_the_bulbs():
    """Before: LORL 100 % and DFF 0 % for every lamp, whatever left it."""
    dist = cosine_beam(E.BeamGrid(), out=51.4)
    assert dist.lorl_percent == pytest.approx(100 * 51.4 / 440)
    untraced = cosine_beam(E.BeamGrid(), out=None)  # optics light tracing does not follow: the integral
    assert untraced.lorl_percent == pytest.approx(100 * math.pi * 300 / 440, rel=2e-3)


def test_ies_has_the_lm63_2002_keywords_and_reads_strictly_in_photompy(tmp_path):
    dist = cosine_beam(E.BeamGrid())
    E.write_ies(dist, tmp_path / "stop.ies")
    ies = photompy.IESFile.read(tmp_path / "stop.ies", strict=True)
    keywords = ies.header.keywords
    for required in ("TEST", "TESTLAB", "ISSUEDATE", "MANUFAC"):  # LM-63-2002's required keywords
        assert keywords.get(required), required
    assert keywords["ISSUEDATE"] == "2026-12-07" and "Round stop lamp" in keywords["LUMINAIRE"]
    assert "red light" in keywords["LAMP"] and "no CCT" in keywords["LAMP"]
    np.testing.assert_allclose(ies.photometry.thetas[:len(dist.gamma_deg)], dist.gamma_deg)
    assert ies.photometry.total_optical_power() == pytest.approx(dist.integral_lm(), rel=0.01)


def test_ldt_reads_back_in_two_parsers_with_its_fields(tmp_path):
    """Before: the file name always lamp.ldt, CCT 2856 K and Ra 100 for red light, LORL 100, DFF 0."""
    import pyldt

    dist = cosine_beam(E.BeamGrid(), out=51.4)
    E.write_ldt(dist, tmp_path / "stop.ldt")
    ours = photompy.LDTFile.read(tmp_path / "stop.ldt")
    theirs = pyldt.LdtReader.read(tmp_path / "stop.ldt")
    for header in (ours.header, theirs.header):
        assert header.lorl == pytest.approx(100 * 51.4 / 440, abs=0.05)
        assert header.dff == pytest.approx(100.0)
    assert theirs.header.file_name == "stop.ldt" and "Round stop lamp" in theirs.header.luminaire_name
    assert theirs.header.lamp_cri == ["n/a"] and ours.header.lamps[0].color == "n/a"
    assert ours.header.dg == 0  # γ not equally spaced: 2.5° to 50°, then 5°
    np.testing.assert_allclose(theirs.header.g_angles[:len(dist.gamma_deg)], dist.gamma_deg)
    got = np.array(theirs.intensities)[:, :len(dist.gamma_deg)] * 440.0 / 1000.0
    np.testing.assert_allclose(got, dist.cd, rtol=1e-5)


def test_white_light_gets_a_cct_by_mccamy():
    """Illuminant A, xy (0.44757, 0.40745) (CIE 015:2018 Table 1), is 2856 K; McCamy is within 2 K."""
    assert E.mccamy_cct((0.44757, 0.40745)) == pytest.approx(2856, abs=2)
    what, cct, rendering = E.light_colour(cosine_beam(E.BeamGrid(), xy=(0.44757, 0.40745)))
    assert cct == "2857K" and rendering == "n/a" and "white light" in what


@pytest.mark.parametrize("text", ["10", "10,x", "7,2.5", "10,0.1", "10,2.5,5,1"])
def test_a_bad_beam_grid_is_refused_in_one_line(repo_root, tmp_path, text):
    proc = subprocess.run([sys.executable, "-m", "core_tracer", "measure", str(repo_root / "presets" /
                           "photometric-stop-lamp.json"), "-o", str(tmp_path / "out"), "--beam-grid", text],
                          cwd=repo_root, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1 and "--beam-grid" in proc.stderr, proc.stderr
    assert proc.stdout == ""


@pytest.mark.slow
def test_the_stop_lamps_files_reproduce_its_report(repo_root, tmp_path):
    from core_tracer.measures import report
    from core_tracer.scene import load_scene

    scene = load_scene(repo_root / "presets" / "photometric-stop-lamp.json")
    measured = report.measure(scene, pixel_mm=2.0, replicates=2)
    dist = E.measure_distributions(scene, measured.functions, pixel_mm=2.0, replicates=2)["stop"]
    E.write_ies(dist, tmp_path / "stop.ies")
    E.write_ldt(dist, tmp_path / "stop.ldt")
    ies = photompy.IESFile.read(tmp_path / "stop.ies", strict=True)
    points = measured.intensities["stop"]
    peak = max(cd for cd, _ in points.values())
    checked = 0
    for (h, v), (cd, err) in points.items():
        if cd < 0.05 * peak:  # a point of a few cd: its relative error says nothing
            continue
        d = direction(h, v)
        gamma, c = math.degrees(math.acos(-d[1])), math.degrees(math.atan2(d[2], d[0])) % 360.0
        got = float(ies.photometry.get_intensity(gamma, c))
        assert got == pytest.approx(dist.at(c, gamma), rel=1e-5)  # photompy interpolates as we do
        allowed = 0.02 * cd + 2.0 * math.hypot(err, dist.stderr_at(c, gamma))
        assert abs(got - cd) <= allowed, ((h, v), cd, err, got, dist.stderr_at(c, gamma))
        checked += 1
    assert checked >= 30
    assert dist.out_lm == pytest.approx(51.4, rel=0.03)  # 440 lm in, about 51 lm out (light-traced)
    assert ies.photometry.total_optical_power() == pytest.approx(dist.out_lm, rel=0.02)
    ldt = photompy.LDTFile.read(tmp_path / "stop.ldt")
    assert ldt.header.lorl == pytest.approx(100 * dist.out_lm / 440, abs=0.05)

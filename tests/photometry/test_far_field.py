"""LED far-field files (core_tracer.photometry.far_field): IES LM-63 files written by photompy (a writer
we did not write) and EULUMDAT files written by measures.export read back, their symmetries unfolded;
the die luminance pattern f normalised so the die emits its flux; bad files refused in one line."""

from __future__ import annotations

import math

import numpy as np
import pytest
from needs import require

from core_tracer.measures import export
from core_tracer.photometry import far_field

photompy = require("photompy")


def _shape(c_deg: np.ndarray, gamma_deg: np.ndarray) -> np.ndarray:
    """A smooth LED-like distribution with a C dependence: (1 + 0.3 cos C + 0.1 cos 2C) cos^2 γ in front."""
    c, g = np.radians(c_deg), np.radians(gamma_deg)
    return 100.0 * (1.0 + 0.3 * np.cos(c) + 0.1 * np.cos(2 * c)) * np.maximum(np.cos(g), 0.0) ** 2


def _write_ies(tmp_path, phis: np.ndarray, name: str = "led.ies") -> str:
    thetas = np.arange(0.0, 180.0 + 1e-9, 2.5)
    values = _shape(phis[:, None], thetas[None, :])
    ies = photompy.create_ies(thetas, phis, values, manufacturer="test", lumcat="led", test="far field",
                              testlab="none", issuedate="2026-12-07")
    path = tmp_path / name
    ies.write(str(path))
    return str(path)


@pytest.mark.parametrize("phis, symmetric_in", [
    (np.arange(0.0, 360.0, 15.0), None),  # the full circle without its 360° plane
    (np.arange(0.0, 180.0 + 1e-9, 15.0), "bilateral"),  # mirrored about the C0-C180 plane
])
def test_ies_files_by_another_writer_read_back(tmp_path, phis, symmetric_in):
    far = far_field.read_far_field(_write_ies(tmp_path, phis))
    assert far.c_deg[0] == 0.0 and far.c_deg[-1] == 360.0
    # at the file's own nodes, and mirrored ones (the shape is symmetric about C0-C180)
    for c in (0.0, 15.0, 90.0, 165.0, 195.0, 270.0, 345.0):
        for g in (0.0, 20.0, 45.0, 70.0):
            assert far.at(c, g) == pytest.approx(_shape(c, g), rel=2e-4, abs=0.01), (c, g)


def test_a_rotationally_symmetric_ies_file_is_the_same_in_every_plane(tmp_path):
    far = far_field.read_far_field(_write_ies(tmp_path, np.array([0.0])))
    for c in (0.0, 77.0, 200.0):
        assert far.at(c, 30.0) == pytest.approx(_shape(0.0, 30.0), rel=2e-4)


def test_a_quadrant_symmetric_ies_file_mirrors_into_four(tmp_path):
    phis = np.arange(0.0, 90.0 + 1e-9, 15.0)
    thetas = np.arange(0.0, 180.0 + 1e-9, 5.0)
    values = (1.0 + 0.4 * np.cos(2 * np.radians(phis)))[:, None] * np.maximum(np.cos(np.radians(thetas)), 0)[None, :]
    path = tmp_path / "quad.ies"
    photompy.create_ies(thetas, phis, 100.0 * values, manufacturer="t", lumcat="l", test="t", testlab="t",
                        issuedate="2026-12-07").write(str(path))
    far = far_field.read_far_field(path)
    for c in (30.0, 150.0, 210.0, 330.0):  # cos 2C is the same at all four
        assert far.at(c, 40.0) == pytest.approx(100.0 * (1 + 0.4 * math.cos(math.radians(60))) *
                                                math.cos(math.radians(40)), rel=2e-4)


def test_a_eulumdat_file_of_the_export_reads_back_its_intensities(tmp_path):
    c = np.arange(0.0, 360.0, 30.0)
    gamma = np.arange(0.0, 90.0 + 1e-9, 10.0)
    dist = export.Distribution(c, gamma, _shape(c[:, None], gamma[None, :]), flux_lm=250.0)
    export.write_ldt(dist, tmp_path / "lamp.ldt")
    export.write_ies(dist, tmp_path / "lamp.ies")
    from_ldt = far_field.read_far_field(tmp_path / "lamp.ldt")
    from_ies = far_field.read_far_field(tmp_path / "lamp.ies")
    for ci in (0.0, 45.0, 200.0, 359.0):
        for g in (0.0, 15.0, 55.0, 90.0):
            expected = dist.at(ci, g)
            assert from_ies.at(ci, g) == pytest.approx(expected, rel=1e-5, abs=1e-9)
            # cd/klm of the flux: the shape is the same, scaled by 1000 / flux
            assert from_ldt.at(ci, g) == pytest.approx(expected * 1000.0 / 250.0, rel=1e-5, abs=1e-9)


def test_the_pattern_of_a_lambertian_file_is_one_and_emits_the_flux(tmp_path):
    """A file of I ∝ cos γ gives f = 1 (a Lambertian die) to the grid's interpolation error; any file's
    f averages to 1 over the cosine-weighted hemisphere (the die emits its flux)."""
    thetas = np.arange(0.0, 90.0 + 1e-9, 1.0)
    phis = np.array([0.0])
    path = tmp_path / "lambert.ies"
    photompy.create_ies(thetas, phis, 500.0 * np.cos(np.radians(thetas))[None, :], manufacturer="t", lumcat="l",
                        test="t", testlab="t", issuedate="2026-12-07").write(str(path))
    pattern = far_field.Pattern.of(far_field.read_far_field(path))
    cos_t = np.cos(np.radians([0.0, 30.0, 60.0, 85.0]))
    np.testing.assert_allclose(pattern.factor(cos_t, np.zeros(4)), 1.0, rtol=3e-3)
    shaped = far_field.Pattern.of(far_field.read_far_field(_write_ies(tmp_path, np.arange(0.0, 360.0, 15.0))))
    rng = np.random.default_rng(1)
    u = rng.uniform(0, 1, 400_000)
    cos_theta = np.sqrt(u)  # cosine-distributed directions
    phi = rng.uniform(0, 360, len(u))
    assert shaped.factor(cos_theta, phi).mean() == pytest.approx(1.0, abs=0.005)
    assert shaped.factor(np.array([-0.2]), np.array([0.0]))[0] == 0.0  # nothing behind the die


@pytest.mark.parametrize("text, message", [
    ("IESNA:LM-63-2002\nTILT=INCLUDE\n", "TILT=INCLUDE"),
    ("IESNA:LM-63-2002\n[TEST] x\n", "no TILT= line"),
    ("IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 2 1 3 2 0 0 0\n1 1 0\n0 90\n0\n1 1\n", "photometric type 3"),
    ("IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 2 1 1 2 0 0 0\n1 1 0\n0 90\n0\n1\n", "expected"),
    ("IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 2 1 1 2 0 0 0\n1 1 0\n90 0\n0\n1 1\n", "must increase"),
    ("IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 2 1 1 2 0 0 0\n1 1 0\n0 90\n0\n1 -1\n", "negative"),
    ("IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 2 1 1 2 0 0 0\n1 1 0\n90 180\n0\n1 1\n", "no light in front"),
])
def test_bad_files_are_refused_in_one_line(tmp_path, text, message):
    path = tmp_path / "bad.ies"
    path.write_text(text)
    with pytest.raises(far_field.FarFieldError, match=message) as info:
        far_field.Pattern.of(far_field.read_far_field(path))
    assert "\n" not in str(info.value) and str(info.value).startswith("bad.ies: ")

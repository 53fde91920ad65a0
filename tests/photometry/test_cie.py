"""CIE 1931 on bands against colour-science: XYZ of illuminant A and LEDs at 81 bands, the
Rec.709 matrix, the luminous efficacy, Km."""

from __future__ import annotations

import numpy as np
import pytest

from core_tracer.photometry import cie, sources
from core_tracer.photometry.bands import Bands
from core_tracer.photometry.spectrum import Spectrum

VISIBLE = np.arange(380.0, 781.0)


def _colour_xyz(colour, spectrum: Spectrum) -> np.ndarray:
    """colour-science's XYZ of a radiance curve over 380–780 nm at 1 nm, k = Km (not its own 683)."""
    sd = colour.SpectralDistribution(spectrum.at(VISIBLE), VISIBLE)
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().trim(colour.SpectralShape(380, 780, 1))
    return colour.sd_to_XYZ(sd, cmfs, k=cie.KM, method="Integration")


SPECTRA = {
    "illuminant A": sources.incandescent,
    "red LED 630/20": lambda: sources.led(630.0, 20.0),
    "amber LED 592/17": lambda: sources.led(592.0, 17.0),
    "white LED-B5": sources.white_led,
}


# Band means times band integrals of the CMFs differ from ∫ S x̄ dλ only by the covariance of S and
# x̄ inside each band. Measured at 81 bands (4.94 nm): illuminant A, xy 1.4e-5 and Y 2e-5; the
# narrow LEDs (half width 17–20 nm), xy 3.3e-4 and Y 1.6e-3; LED-B5, xy 2.3e-4 and Y 3.4e-4.
# At 400 bands (1 nm) all are within 4e-5 in xy and 2e-4 in Y (the trapezoid rule's own error).
TOLERANCE_81 = {"illuminant A": (5e-5, 1e-4), "red LED 630/20": (5e-4, 2.5e-3),
                "amber LED 592/17": (5e-4, 2.5e-3), "white LED-B5": (5e-4, 1e-3)}


def _ours_and_colour_sciences(colour, name: str, bands: int) -> tuple[np.ndarray, np.ndarray]:
    """XYZ of the spectrum ``name`` from its means in ``bands`` uniform bands, and colour-science's."""
    spectrum = SPECTRA[name]()
    b = Bands.uniform(bands)
    return spectrum.band_means(b) @ cie.xyz_matrix(b), _colour_xyz(colour, spectrum)


@pytest.mark.slow
@pytest.mark.parametrize("name", SPECTRA)
def test_81_bands_give_colour_sciences_xyz(colour, name):
    ours, reference = _ours_and_colour_sciences(colour, name, 81)
    xy_tol, y_tol = TOLERANCE_81[name]
    assert ours[1] == pytest.approx(reference[1], rel=y_tol)
    np.testing.assert_allclose(cie.xy(ours), colour.XYZ_to_xy(reference), atol=xy_tol)


@pytest.mark.parametrize("name", SPECTRA)
def test_1_nm_bands_converge_to_colour_sciences_xyz(colour, name):
    ours, reference = _ours_and_colour_sciences(colour, name, 400)
    assert ours[1] == pytest.approx(reference[1], rel=5e-4)
    np.testing.assert_allclose(cie.xy(ours), colour.XYZ_to_xy(reference), atol=5e-5)


def test_xyz_of_a_curve_at_1_nm_is_colour_sciences(colour):
    np.testing.assert_allclose(cie.spectrum_xyz(sources.incandescent()),
                               _colour_xyz(colour, sources.incandescent()), rtol=2e-5)


def test_km_makes_a_540_thz_line_683_lm_per_w():
    # CIE ILV 17-730 note 3: Km = 683 V(555) / V(555.016); ȳ is linear between its 1 nm samples.
    wavelengths, xyz_bar = cie.cmfs()
    v_540thz = np.interp(555.016, wavelengths, xyz_bar[:, 1])
    assert cie.KM * v_540thz == pytest.approx(683.0, abs=1e-3)  # 683.0004 with ȳ linear at 1 nm
    assert cie.K_CD == 683.0


def test_equal_energy_radiance_luminance_is_km_times_the_area_under_v():
    b = Bands.uniform(40)
    wavelengths, xyz_bar = cie.cmfs()
    inside = (wavelengths >= 380) & (wavelengths <= 780)
    expected = cie.KM * np.trapz(xyz_bar[inside, 1], wavelengths[inside])
    assert np.ones(40) @ cie.luminance_weights(b) == pytest.approx(expected, rel=1e-12)


def test_rec709_matrix_is_colour_sciences(colour):
    np.testing.assert_allclose(cie.XYZ_TO_LINEAR_REC709,
                               colour.RGB_COLOURSPACES["ITU-R BT.709"].matrix_XYZ_to_RGB, atol=1e-8)
    # D65 white goes to equal R, G, B; illuminant A stays warm (no chromatic adaptation).
    white = cie.xyz_to_linear_rec709(colour.xy_to_XYZ(np.array(cie.D65_WHITE_XY)))
    np.testing.assert_allclose(white, white[1], rtol=1e-12)
    a = cie.xyz_to_linear_rec709(cie.spectrum_xyz(sources.incandescent()))
    assert a[0] > a[1] > a[2] > 0


def test_xy_of_black_is_the_given_white():
    out = cie.xy(np.array([[0.0, 0.0, 0.0], [1.0, 2.0, 1.0]]))
    np.testing.assert_allclose(out, [cie.D65_WHITE_XY, [0.25, 0.5]])


@pytest.mark.parametrize("name", SPECTRA)
def test_luminous_efficacy_against_colour_sciences_v(colour, name):
    spectrum = SPECTRA[name]()
    v = colour.colorimetry.SDS_LEFS_PHOTOPIC["CIE 1924 Photopic Standard Observer"]
    s = spectrum.at(VISIBLE)
    expected = cie.KM * np.trapz(s * v[VISIBLE], VISIBLE) / np.trapz(s, VISIBLE)
    assert cie.luminous_efficacy(spectrum) == pytest.approx(expected, rel=1e-9)


def test_luminous_efficacy_of_a_flat_spectrum_and_no_power():
    flat = Spectrum(np.array([380.0, 780.0]), np.array([1.0, 1.0]))
    assert 100 < cie.luminous_efficacy(flat) < 200  # 683 × mean V over 380–780 nm ≈ 181 lm/W
    with pytest.raises(ValueError, match="no power"):
        cie.luminous_efficacy(Spectrum(np.array([380.0, 780.0]), np.array([0.0, 0.0])))

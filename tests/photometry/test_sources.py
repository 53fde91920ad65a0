"""Sources: the Lambertian sphere bulb's luminance, spectra against colour-science, R48 colours of
the presets, the CSV reader's refusals, the named bulbs."""

from __future__ import annotations

import math

import numpy as np
import pytest

from core_tracer.photometry import cie, materials, regulation, sources
from core_tracer.photometry.bands import Bands

pytestmark = pytest.mark.filterwarnings("ignore:Aligning")  # colour-science telling it interpolates

ALL_SPECTRA = sorted(sources.SPECTRA)


def test_sphere_luminance_gives_back_its_flux():
    # Independent of the formula: a Lambertian surface of luminance L emits ∫ L cos θ dω = π L per
    # unit area (integrated numerically here over the hemisphere), times the sphere's area 4π r².
    flux, radius_mm = 440.0, 4.5
    lum = sources.bulb_luminance(flux, radius_mm)
    theta = np.linspace(0.0, math.pi / 2, 20001)
    exitance_per_l = np.trapz(np.cos(theta) * np.sin(theta) * 2 * math.pi, theta)
    r = radius_mm * 1e-3
    assert lum * exitance_per_l * 4 * math.pi * r * r == pytest.approx(flux, rel=1e-8)
    assert lum == pytest.approx(flux / (4 * math.pi ** 2 * r * r), rel=1e-15)


@pytest.mark.parametrize("k", [1, 3, 5, 8, 16, 81])
@pytest.mark.parametrize("name", ALL_SPECTRA)
def test_bulb_band_radiance_has_the_flux_luminance_at_every_k(k, name):
    b = Bands.uniform(k)
    radiance = sources.bulb_spectral_radiance(21.0 if "led" in name else 440.0, sources.named_spectrum(name), 3.0, b)
    expected = (21.0 if "led" in name else 440.0) / (4 * math.pi ** 2 * 3e-3 ** 2)
    assert radiance @ cie.luminance_weights(b) == pytest.approx(expected, rel=1e-12)
    assert np.all(radiance >= 0)


def test_bulb_radiance_keeps_the_spectral_shape():
    b = Bands.uniform(20)
    shape = sources.incandescent().band_means(b)
    radiance = sources.bulb_spectral_radiance(35.0, sources.incandescent(), 2.0, b)
    np.testing.assert_allclose(radiance / radiance.max(), shape / shape.max(), rtol=1e-12)


def test_led_is_colour_sciences_ohno_2005(colour):
    for peak, width in [(630.0, 20.0), (592.0, 17.0), (455.0, 25.0)]:
        ours = sources.led(peak, width)
        theirs = colour.sd_single_led(peak, shape=colour.SpectralShape(360, 830, 1), half_spectral_width=width)
        np.testing.assert_allclose(ours.at(theirs.wavelengths), theirs.values, rtol=0, atol=1e-15)


def test_led_full_width_at_half_maximum_is_0_921_width():
    s = sources.led(600.0, 40.0, step_nm=0.01)
    above = s.wavelengths_nm[s.values >= 0.5]
    assert (above[-1] - above[0]) / 40.0 == pytest.approx(0.921, abs=2e-3)


def test_incandescent_is_illuminant_a(colour):
    a = colour.SDS_ILLUMINANTS["A"]
    np.testing.assert_allclose(sources.incandescent().at(a.wavelengths), a.values, rtol=1e-9)
    xy = cie.xy(cie.spectrum_xyz(sources.incandescent()))
    np.testing.assert_allclose(xy, colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["A"], atol=2e-4)


@pytest.mark.parametrize("name, region", [
    ("red_led", "red"), ("amber_led", "amber"), ("amber_coated", "amber"), ("incandescent", "white"),
    ("white_led", "white"),
])
def test_presets_meet_r48_colours_at_81_bands(name, region):
    # (At 8 bands the red LED reads (0.644, 0.355), outside R48 red: coarse bands misplace narrow
    # spectra. benchmarks/bench_bands.py measures how the colour converges with K.)
    for k in (81, 400):
        b = Bands.uniform(k)
        xyz = sources.named_spectrum(name).band_means(b) @ cie.xyz_matrix(b)
        assert regulation.in_region(cie.xy(xyz), region), (name, k, cie.xy(xyz))


def test_illuminant_a_through_the_red_cut_on_filter_against_colour(colour):
    # The filter's curve is evaluated by its formula and multiplied by colour-science's own
    # illuminant A (aligned to 1 nm by colour's interpolator); colour integrates at 1 nm.
    red = materials.FILTERS["red"]
    a = colour.SDS_ILLUMINANTS["A"].copy().align(colour.SpectralShape(380, 780, 1))
    filtered = colour.SpectralDistribution(a.values * red.transmittance(a.wavelengths), a.wavelengths)
    expected = colour.XYZ_to_xy(colour.sd_to_XYZ(filtered, method="Integration"))
    product = sources.incandescent().times(red.spectrum())
    np.testing.assert_allclose(cie.xy(cie.spectrum_xyz(product)), expected, atol=1e-6)  # measured 7e-8
    # Through bands: the filter's 7 nm edge costs 2.6e-4 in xy at 81 bands, 3e-5 at 400 (measured).
    for k, tol in ((81, 5e-4), (400, 5e-5)):
        b = Bands.uniform(k)
        ours = cie.xy(product.band_means(b) @ cie.xyz_matrix(b))
        np.testing.assert_allclose(ours, expected, atol=tol)
        assert regulation.in_region(ours, "red")


def test_named_spectrum_refuses_unknown_names():
    with pytest.raises(ValueError, match="not one of incandescent"):
        sources.named_spectrum("neon")


@pytest.mark.parametrize("peak, width, words", [(300.0, 20.0, "LED peak"), (600.0, 0.1, "LED width"),
                                                (float("nan"), 20.0, "LED peak")])
def test_led_refuses_bad_parameters(peak, width, words):
    with pytest.raises(ValueError, match=words):
        sources.led(peak, width)


# ---------------------------------------------------------------------------------------------
# CSV


def test_csv_reads_comments_header_and_separators(tmp_path):
    path = tmp_path / "bulb.csv"
    path.write_text("# measured at 13.5 V\nnm,relative\n380,0.1\n400;0.2\n420\t0.4\n\n780,1.0\n", encoding="utf-8")
    s = sources.from_csv(path)
    np.testing.assert_allclose(s.wavelengths_nm, [380, 400, 420, 780])
    np.testing.assert_allclose(s.values, [0.1, 0.2, 0.4, 1.0])
    assert s.name == "bulb.csv"


BAD_CSV = {
    "three columns": ("380,1,2\n400,1,2\n", "line 1: expected two columns"),
    "words": ("nm,value\n380,1\nhello,2\n", "line 3: 'hello,2' is not two numbers"),
    "nan": ("380,1\n400,nan\n", "line 2: values must be finite"),
    "inf": ("380,inf\n400,1\n", "line 1: values must be finite"),
    "decreasing": ("400,1\n380,1\n", "line 2: wavelength 380 nm does not increase"),
    "repeated": ("400,1\n400,1\n", "does not increase"),
    "range": ("100,1\n400,1\n", "line 1: wavelength 100 nm is outside 200 to 2000 nm"),
    "negative": ("380,1\n400,-0.5\n", "line 2: value -0.5 is negative"),
    "one row": ("380,1\n", "found 1 rows of nm,value; allowed 2 to 20000"),
    "empty": ("", "found 0 rows"),
    "all zero": ("380,0\n400,0\n", "every value is 0"),
    "two headers": ("nm,value\nwavelength,power\n380,1\n", "line 2: 'wavelength,power' is not two numbers"),
}


@pytest.mark.parametrize("case", BAD_CSV)
def test_csv_refusals_are_one_line_naming_the_file(tmp_path, case):
    text, words = BAD_CSV[case]
    path = tmp_path / "measured.csv"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(sources.SpectrumFileError) as e:
        sources.from_csv(path)
    message = str(e.value)
    assert message.startswith("measured.csv: ") and words in message and "\n" not in message


def test_csv_refuses_missing_folders_large_and_binary_files(tmp_path):
    with pytest.raises(sources.SpectrumFileError, match="missing.csv: cannot read"):
        sources.from_csv(tmp_path / "missing.csv")
    with pytest.raises(sources.SpectrumFileError, match="not a regular file"):
        sources.from_csv(tmp_path)
    big = tmp_path / "big.csv"
    big.write_text("380,1\n" * 100, encoding="utf-8")
    with pytest.raises(sources.SpectrumFileError, match="big.csv: file is 600 bytes; allowed at most 500 bytes"):
        sources.from_csv(big, max_bytes=500)
    binary = tmp_path / "binary.csv"
    binary.write_bytes(b"\xff\xfe\x00380,1")
    with pytest.raises(sources.SpectrumFileError, match="not UTF-8"):
        sources.from_csv(binary)


def test_csv_row_limit(tmp_path):
    path = tmp_path / "long.csv"
    rows = np.linspace(200.0, 2000.0, sources.CSV_MAX_ROWS + 1)
    path.write_text("".join(f"{nm:.6f},1\n" for nm in rows), encoding="utf-8")
    with pytest.raises(sources.SpectrumFileError, match="more than 20000 rows"):
        sources.from_csv(path)


# ---------------------------------------------------------------------------------------------
# Named bulbs


def test_named_bulbs_are_cited_and_usable():
    b = Bands.uniform(8)
    for name, bulb in sources.BULB_TYPES.items():
        assert bulb.name == name and ("R37" in bulb.source or "R128" in bulb.source)
        assert bulb.spectrum in sources.SPECTRA
        for state in bulb.states.values():
            assert state.flux_lm > 0
            radiance = sources.bulb_spectral_radiance(state.flux_lm, sources.named_spectrum(bulb.spectrum), 3.0, b)
            assert radiance @ cie.luminance_weights(b) > 0


def test_two_filament_bulbs_have_both_states_with_the_sheet_fluxes():
    bulb = sources.BULB_TYPES["P21/5W"]
    assert bulb.states["stop"].flux_lm == 440.0 and bulb.states["tail"].flux_lm == 35.0
    amber = sources.BULB_TYPES["PY21/5W"]
    assert (amber.states["stop"].flux_lm, amber.states["tail"].flux_lm) == (270.0, 21.0)
    assert amber.states["stop"].value == "objective" and amber.spectrum == "amber_coated"

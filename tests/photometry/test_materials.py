"""Materials: dispersion from n_d and Abbe number, filters and Beer–Lambert, metal mirrors, Smits
RGB upsampling against colour-science and round trips."""

from __future__ import annotations

import math

import numpy as np
import pytest

from core_tracer.photometry import cie, materials
from core_tracer.photometry.bands import Bands
from core_tracer.photometry.illuminants import illuminant_d65

F, D, C = materials.LINE_F_NM, materials.LINE_D_NM, materials.LINE_C_NM


@pytest.mark.parametrize("n_d, abbe", [(1.491, 59.2), (1.585, 29.1), (1.4914, 52.6), (1.9, 20.0), (1.3, 90.0)])
def test_dispersion_reproduces_n_d_and_the_abbe_number(n_d, abbe):
    n_f, n_d_out, n_c = materials.refractive_index(n_d, abbe, [F, D, C])
    assert n_d_out == pytest.approx(n_d, abs=1e-14)
    assert (n_d_out - 1.0) / (n_f - n_c) == pytest.approx(abbe, rel=1e-12)
    lam = np.linspace(380.0, 780.0, 81)
    assert np.all(np.diff(materials.refractive_index(n_d, abbe, lam)) < 0)  # normal dispersion


# Sultanova, Kasarova, Nikolov, Acta Phys. Pol. A 116:585 (2009), measured indices (±0.001) at
# 436.8, 486.1, 632.8, 703, 833 nm. The two-term Cauchy through n_d and V_d follows them within 0.0025.
MEASURED = {
    "pmma": ((436.8, 1.502), (486.1, 1.497), (632.8, 1.489), (703.0, 1.486), (833.0, 1.484)),
    "polycarbonate": ((436.8, 1.612), (486.1, 1.599), (632.8, 1.580), (703.0, 1.575), (833.0, 1.569)),
}


@pytest.mark.parametrize("key", MEASURED)
def test_dispersion_follows_the_measured_indices(key):
    material = materials.MATERIALS[key]
    lam, measured = np.array(MEASURED[key]).T
    np.testing.assert_allclose(material.index(lam), measured, atol=0.0025)


@pytest.mark.parametrize("n_d, abbe, words", [(0.99, 50.0, "n_d"), (float("nan"), 50.0, "n_d"),
                                              (1.5, 0.0, "Abbe number"), (1.5, float("inf"), "Abbe number")])
def test_dispersion_refuses_bad_input(n_d, abbe, words):
    with pytest.raises(ValueError, match=words):
        materials.refractive_index(n_d, abbe, 550.0)


def test_index_one_has_no_dispersion():
    """A lens's lowest ior, 1 (the scene allows it: a lens that is not there), is 1 at every
    wavelength; a custom material at ior 1 once ended a photometric render with a traceback."""
    np.testing.assert_array_equal(materials.refractive_index(1.0, 30.0, np.array([380.0, 587.56, 780.0])), 1.0)


def test_beer_lambert_round_trip():
    t = np.array([0.9, 0.5, 0.01, 1.0])
    alpha = materials.absorption_per_mm(t, 3.0)
    np.testing.assert_allclose(np.exp(-alpha * 3.0), t, rtol=1e-12)
    np.testing.assert_allclose(np.exp(-alpha * 6.0), t * t, rtol=1e-12)  # twice as thick: squared
    assert alpha[-1] == 0.0


@pytest.mark.parametrize("t, d, words", [(0.0, 3.0, "above 0"), (1.2, 3.0, "at most 1"), (0.5, 0.0, "thickness"),
                                         (float("nan"), 3.0, "transmittance")])
def test_beer_lambert_refuses_bad_input(t, d, words):
    with pytest.raises(ValueError, match=words):
        materials.absorption_per_mm(t, d)


def test_cut_on_filter_shape():
    f = materials.cut_on_filter(600.0, 10.0, 0.02, 0.9)
    assert f.transmittance(600.0) == pytest.approx(0.46)
    assert f.transmittance(380.0) == pytest.approx(0.02, abs=1e-9)
    assert f.transmittance(780.0) == pytest.approx(0.9, abs=1e-7)
    lam = np.linspace(380, 780, 401)
    assert np.all(np.diff(f.transmittance(lam)) >= 0)
    assert np.all(materials.FILTERS["clear"].transmittance(lam) == 1.0)
    for preset in materials.FILTERS.values():  # every preset converts to a finite absorption
        assert np.all(np.isfinite(materials.absorption_per_mm(preset.transmittance(lam), preset.thickness_mm)))


@pytest.mark.parametrize("field, value", [("edge_nm", 50.0), ("slope_nm", 0.0), ("t_min", -0.1), ("t_max", 1.5)])
def test_cut_on_filter_refuses_out_of_range(field, value):
    args = {"edge_nm": 600.0, "slope_nm": 10.0, "t_min": 0.0, "t_max": 0.9, field: value}
    with pytest.raises(ValueError, match="filter"):
        materials.cut_on_filter(**args)


def test_normal_reflectance_of_a_dielectric():
    assert materials.normal_reflectance(np.array(1.5 + 0j)) == pytest.approx(0.04)
    assert materials.normal_reflectance(np.array(1.49 + 0j), 1.49) == 0.0


def test_metal_mirrors():
    al = materials.mirror_reflectance("aluminium")
    ag = materials.mirror_reflectance("silver")
    assert np.all((al.values > 0.8) & (al.values < 1.0)) and np.all((ag.values > 0.8) & (ag.values < 1.0))
    # aluminium's interband absorption near 1.5 eV (827 nm) is the dip of its reflectance
    assert 800.0 <= al.wavelengths_nm[np.argmin(al.values)] <= 840.0
    visible = np.linspace(400.0, 700.0, 31)
    assert np.all(al.at(visible) > 0.89)
    assert np.all(ag.at(visible[visible >= 450]) > al.at(visible[visible >= 450]))  # silver is the brighter
    with pytest.raises(ValueError, match="mirror finish"):
        materials.mirror_reflectance("gold")


# ---------------------------------------------------------------------------------------------
# Smits (1999)


@pytest.mark.seed(7)
def test_smits_weights_give_colour_sciences_spectrum(colour, rng):
    wavelengths, basis = materials.smits_basis()
    for rgb in [*rng.random((20, 3)), (1.0, 1.0, 1.0), (0.0, 0.0, 0.0), (0.3, 0.3, 0.9), (0.9, 0.3, 0.3)]:
        theirs = colour.recovery.RGB_to_sd_Smits1999(np.asarray(rgb))
        ours = basis @ materials.smits_weights(np.asarray(rgb))
        np.testing.assert_allclose(ours, theirs.values, atol=1e-12)


def _round_trip(rgb: tuple[float, float, float], bands: Bands) -> np.ndarray:
    """RGB → Smits reflectance → seen under D65 → XYZ → linear Rec.709, white normalised to 1."""
    d65 = illuminant_d65().band_means(bands)
    m = cie.xyz_matrix(bands)
    reflectance = materials.rgb_to_reflectance(np.asarray(rgb, dtype=np.float64), bands)
    return cie.xyz_to_linear_rec709((reflectance * d65) @ m / (d65 @ m)[1])


# Measured at 400 bands: greys within 7e-4; saturated primaries and secondaries within 0.098 (blue
# comes back at 0.903, yellow's blue at 0.097: Smits built his bases for a white of equal energy);
# mid colours within 0.03.
@pytest.mark.parametrize("rgb, tol", [
    ((1.0, 1.0, 1.0), 1e-3), ((0.5, 0.5, 0.5), 1e-3), ((0.18, 0.18, 0.18), 1e-3),
    ((1.0, 0.0, 0.0), 0.1), ((0.0, 1.0, 0.0), 0.1), ((0.0, 0.0, 1.0), 0.1),
    ((0.0, 1.0, 1.0), 0.1), ((1.0, 0.0, 1.0), 0.1), ((1.0, 1.0, 0.0), 0.1),
    ((0.8, 0.3, 0.1), 0.03), ((0.2, 0.4, 0.7), 0.03),
])
def test_smits_round_trip(rgb, tol):
    np.testing.assert_allclose(_round_trip(rgb, Bands.uniform(400)), rgb, atol=tol)


def test_reflectance_is_linear_in_grey_and_vectorised(rng):
    b = Bands.uniform(12)
    image = rng.random((5, 7, 3))
    out = materials.rgb_to_reflectance(image, b)
    assert out.shape == (5, 7, 12)
    np.testing.assert_allclose(out[2, 3], materials.rgb_to_reflectance(image[2, 3], b))
    np.testing.assert_allclose(materials.rgb_to_reflectance(np.array([0.25] * 3), b),
                               0.25 * materials.rgb_to_reflectance(np.ones(3), b))
    # negative RGB (out of gamut pixels) reads as 0: no negative reflectance
    assert np.all(materials.rgb_to_reflectance(np.array([-1.0, 0.5, 0.2]), b) >= 0)


def test_illuminant_variant_white_is_d65_of_unit_luminance():
    b = Bands.uniform(81)
    xyz = materials.rgb_to_illuminant(np.ones(3), b) @ cie.xyz_matrix(b)
    assert xyz[1] == pytest.approx(1.0, rel=1e-12)
    np.testing.assert_allclose(cie.xy(xyz), cie.D65_WHITE_XY, atol=3e-4)
    doubled = materials.rgb_to_illuminant(np.full(3, 2.0), b) @ cie.xyz_matrix(b)
    assert doubled[1] == pytest.approx(2.0 * xyz[1], rel=1e-12)
    assert math.isfinite(float(doubled.sum()))

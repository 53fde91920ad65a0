"""The CIE 13.3-1995 general colour rendering index Ra (``photometry.colour_rendering``) against
colour-science 0.4.6's ``colour_rendering_index``: illuminants A, FL2 and LED-B5 and the light a
reversing lamp sends out, within 0.5; the CCT search against Planckian radiators it must find."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from core_tracer.measures import export
from core_tracer.photometry import colour_rendering as cr
from core_tracer.photometry.daylight import daylight_spectrum

pytestmark = pytest.mark.filterwarnings("ignore")


def _theirs(colour, wavelengths, values) -> float:
    sd = colour.SpectralDistribution(np.asarray(values), np.asarray(wavelengths))
    return float(colour.colour_rendering_index(sd))


@pytest.mark.parametrize("name, expected", [("A", 100.0), ("FL2", 64.2), ("LED-B5", 80.3)])
def test_ra_of_cie_illuminants_agrees_with_colour_science(colour, name, expected):
    sd = colour.SDS_ILLUMINANTS[name]
    ours = cr.general_cri(sd.wavelengths, sd.values)
    assert ours == pytest.approx(_theirs(colour, sd.wavelengths, sd.values), abs=0.5)
    assert ours == pytest.approx(expected, abs=0.5)


def _reversing_lamp_scene(repo_root):
    from core_tracer.scene import load_scene

    scene = load_scene(repo_root / "presets" / "four-lamp-night-lit-photometric.json")
    assert scene["lamps"][3]["lens"]["filter"] == "clear"  # the reversing lamp: white light
    return scene


def test_ra_of_the_reversing_lamps_light_agrees_with_colour_science(colour, repo_root):
    """The four-lamp preset's reversing lamp (a P21/5W behind a clear lens: incandescent, Ra ≈ 100)
    and the same lamp with a white LED behind a smoked lens (a light off illuminant A's shape)."""
    scene = _reversing_lamp_scene(repo_root)
    emitted = export.emitted_spectrum(scene, [3])
    ours = cr.general_cri(emitted.wavelengths_nm, emitted.values)
    assert ours == pytest.approx(_theirs(colour, emitted.wavelengths_nm, emitted.values), abs=0.5)
    assert ours > 99.0
    led = copy.deepcopy(scene)
    led["lamps"][3]["bulb"] = {**led["lamps"][3]["bulb"], "type": "custom", "spectrum": "white_led", "flux_lm": 300.0}
    led["lamps"][3]["lens"]["filter"] = "smoke"
    emitted = export.emitted_spectrum(led, [3])
    ours = cr.general_cri(emitted.wavelengths_nm, emitted.values)
    assert ours == pytest.approx(_theirs(colour, emitted.wavelengths_nm, emitted.values), abs=0.5)
    assert 60.0 < ours < 95.0


@pytest.mark.parametrize("cct", [1800.0, 2856.0, 4500.0, 6504.0, 12000.0])
def test_the_cct_search_finds_a_planckian_radiators_temperature(cct):
    lam, xyz_bar, _ = cr._grid()
    uv = cr._uv(cr.planck(lam, cct) @ xyz_bar)
    assert cr.cct_of_uv(uv) == pytest.approx(cct, rel=1e-5)


def test_the_reference_is_planckian_below_5000_k_and_daylight_above():
    lam = np.arange(360.0, 831.0, 5.0)
    np.testing.assert_allclose(cr.reference_illuminant(lam, 4999.0), cr.planck(lam, 4999.0))
    np.testing.assert_allclose(cr.reference_illuminant(lam, 6504.0), daylight_spectrum(6504.0).at(lam))


def test_a_spectrum_without_light_is_refused_in_one_line():
    with pytest.raises(ValueError, match="no visible light"):
        cr.general_cri(np.array([360.0, 830.0]), np.zeros(2))
    with pytest.raises(ValueError, match="finite"):
        cr.general_cri(np.array([360.0, 830.0]), np.array([1.0, np.nan]))

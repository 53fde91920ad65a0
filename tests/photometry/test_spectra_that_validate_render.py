"""Spectra that pass ``validate`` render (issue 33 item 4): every check the render makes on a lamp's
spectra is made when the scene is loaded (``raytrace.spectral.check_lamps``: visible light, finite
integrals, a radius whose luminance is finite, filters' transmittance), so a generated hostile
bulb or curve is either refused in one line naming its field, or renders a finite image (the
generated cases: tests/test_fuzz_round3.py, "spectra and curves")."""

from __future__ import annotations

import hostile_files as H
import numpy as np
import pytest
from helpers import PRESETS

from core_tracer.cli.common import load_scene_file
from core_tracer.photometry import sources
from core_tracer.raytrace import spectral
from core_tracer.scene.reading import SceneError


@pytest.mark.parametrize("bulb, field, words", [
    ({"type": "custom", "spectrum": "led", "led_peak_nm": 830.0, "led_width_nm": 1.0, "flux_lm": 100.0},
     "lamps[0].bulb.led_peak_nm", "no usable light in 380 to 780 nm"),
    ({"type": "custom", "spectrum": "led", "led_peak_nm": 360.0, "led_width_nm": 1.0, "flux_lm": 100.0},
     "lamps[0].bulb.led_peak_nm", "no usable light"),
    ({"radius": 1e-320}, "lamps[0].bulb.radius", "allowed 0.001 mm or more"),
])
def test_a_bulb_the_render_cannot_light_is_refused_when_loaded(tmp_path, bulb, field, words):
    with pytest.raises(SceneError) as e:
        load_scene_file(H.spectrum_scene_file(tmp_path, bulb))
    assert e.value.path.endswith(field) and words in e.value.message


@pytest.mark.parametrize("curve, words", [
    ("800,1\n900,1\n", "outside the visible range 380 to 780 nm"),
    ("200,0.5\n300,0.9\n", "outside the visible range"),
    ("400,1.7e308\n500,1.7e308\n", "too large to integrate"),
])
def test_a_curve_the_render_would_misread_is_refused_in_one_line(tmp_path, curve, words):
    with pytest.raises(SceneError) as e:
        load_scene_file(H.spectrum_scene_file(tmp_path, bulb_curve=curve))
    assert e.value.path.endswith("lamps[0].bulb.spectrum_file") and words in e.value.message


def test_a_spectrum_only_outside_the_visible_range_is_not_flat_white(tmp_path):
    """Before: held at its end value over 380-780 nm, an 800-900 nm curve lit the lamp white."""
    with pytest.raises(sources.SpectrumFileError, match="outside the visible range"):
        (tmp_path / "ir.csv").write_text("800,1\n900,1\n")
        sources.from_csv(tmp_path / "ir.csv")


def test_a_filter_with_one_zero_row_renders_finite(tmp_path):
    curve = "".join(f"{380 + 10 * i},{0.0 if i == 12 else 0.9}\n" for i in range(41))
    assert H.refused_or_renders(H.spectrum_scene_file(tmp_path, lens_curve=curve)) == "rendered"


def test_bulb_luminance_is_refused_where_it_overflows_not_divided_by_zero():
    with pytest.raises(ValueError, match="too small"):
        sources.bulb_luminance(440.0, 1e-320)
    assert sources.bulb_luminance(440.0, 8.0) == pytest.approx(440.0 / (4 * np.pi ** 2 * 0.008 ** 2))


def test_check_lamps_passes_every_photometric_preset():
    for path in sorted(PRESETS.glob("*photometric*.json")):
        spectral.check_lamps(load_scene_file(path))

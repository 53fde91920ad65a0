"""The far-field round trip of an LED source (issue 32): a lamp's beam exported as IES and EULUMDAT
(``measures.export``, as ``measure`` writes them) and given as the far-field file of one LED die at
the origin behind a window gives the same R148 grid again, within 2 % at every point.

"The same" is what the file says at the grid's directions: the exporter's own interpolation
(``Distribution.at``) scaled by the die's flux over the file's flux in front of the die. The file's
flux is integrated here by the midpoint rule on a 0.25° grid of that interpolation, apart from the
reader's normalisation (``far_field.Pattern``). The LED is measured by rendered views
(``intensity.rendered_intensity``): the die's luminance I / (A cos θ) integrated over its projected
area, which is the far field whatever the die's size.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from helpers import PRESETS

from core_tracer.measures import export, intensity, regulation_grid
from core_tracer.measures.directions import direction
from core_tracer.raytrace import spectral
from core_tracer.scene import beside
from core_tracer.scene.validate import parse_scene

pytestmark = pytest.mark.slow

LED_FLUX_LM = 10.0
DIE_MM = 3.0


def _file_flux(dist: export.Distribution, step: float = 0.25) -> float:
    """∫ I dΩ over γ < 90° of the exporter's interpolation, midpoint rule on a ``step``° grid (cd·sr)."""
    gamma = np.arange(step / 2, 90.0, step)
    c = np.arange(step / 2, 360.0, step)
    at = np.vectorize(dist.at)
    values = at(c[:, None], gamma[None, :])
    dg, dc = math.radians(step), math.radians(step)
    return float((values * np.sin(np.radians(gamma))[None, :]).sum() * dg * dc)


def _c_gamma(h: float, v: float) -> tuple[float, float]:
    """(C, γ) of the direction (H, V) in the exporter's frame: γ from −y, C from +x toward +z."""
    d = direction(h, v)
    return math.degrees(math.atan2(d[2], d[0])) % 360.0, math.degrees(math.acos(max(-1.0, min(1.0, -d[1]))))


def _led_scene(folder, far_field_file: str) -> dict:
    doc = json.loads((PRESETS / "photometric-stop-lamp.json").read_text())
    doc["light"] = {"direction": [0.3, -1.0, 0.6], "ambient": 0.0, "illuminance_lux": 0.0}
    doc["environment"] = {"world": "none"}
    doc["body"] = {**doc["body"], "size": [30.0, 30.0], "depth": 5.0}
    lamp = doc["lamps"][0]
    lamp["cuts"]["height"] = 0.0
    lamp["lens"] = {**lamp["lens"], "material": "custom", "ior": 1.0001, "abbe": 100.0, "filter": "clear",
                    "radius": 12.0, "thickness": 0.1}
    lamp["source"] = "led"
    lamp["led"] = {"position": [0.0, 0.3, 0.0], "die_size": [DIE_MM, DIE_MM], "flux_lm": LED_FLUX_LM,
                   "spectrum": "red_led", "distribution": "file", "far_field_file": far_field_file}
    path = folder / "led.json"
    path.write_text(json.dumps(doc))
    return beside.with_spectrum_files(path, parse_scene(doc))


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    """The shipped photometric stop lamp's beam as ``measure`` exports it (C 30° × γ 10°), written beside
    an LED design; coarse pixels: the file only has to be some real lamp's."""
    folder = tmp_path_factory.mktemp("round_trip")
    lamp = parse_scene(json.loads((PRESETS / "photometric-stop-lamp.json").read_text()))
    dist = export.measure_distribution(lamp, pixel_mm=2.0, replicates=1)
    export.write_ies(dist, folder / "lamp.ies")
    export.write_ldt(dist, folder / "lamp.ldt")
    return folder, dist


@pytest.mark.parametrize("name, points", [("lamp.ies", None), ("lamp.ldt", 4)])
def test_a_lamps_exported_beam_as_an_led_far_field_gives_the_r148_grid_again(exported, monkeypatch, name, points):
    monkeypatch.setattr(spectral, "finish_reflectance", lambda reflector, bands: np.zeros(bands.k))
    folder, dist = exported
    scene = _led_scene(folder, name)
    scale = LED_FLUX_LM / _file_flux(dist)  # cd of the LED per cd of the file
    grid = regulation_grid.test_points("R148 S1")[:points]
    worst = 0.0
    for point, h, v, _minimum in grid:
        expected = scale * dist.at(*_c_gamma(h, v))
        got = intensity.rendered_intensity(scene, h, v, pixel_mm=0.05, replicates=3, seed=2)
        error = abs(got.cd / expected - 1.0)
        worst = max(worst, error)
        assert error < 0.02, (point, h, v, got.cd, expected)
    print(f"{name}: worst of {len(grid)} R148 S1 points {100 * worst:.2f} %")

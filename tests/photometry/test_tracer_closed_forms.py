"""The photometric mode's tracer against closed forms (issue 22, "Tests that must exist"), through
the real tracer (``render_passes``) on a bulb seen straight on by an orthographic camera whose
window (8 mm) lies inside the bulb's silhouette (radius 8 mm), so every pixel is a bulb pixel:

- a bare Lambertian sphere bulb of flux Φ: luminance Φ / (4π² r²) cd/m² on every pixel;
- a clear non-absorbing slab of index n at normal incidence before it: (1 − r)² / (1 − r²) of that,
  r = ((n − 1)/(n + 1))², the internal reflections summed as the tracer walks them (to the cut-off);
- a red cut-on filter of known curve: the xy of illuminant A times that curve, computed here
  independently with colour-science (``colour.sd_to_XYZ``).

"Bare" is a lens of index 1 with a clear filter (no Fresnel reflection, no absorption): the eye
ray reaches the bulb with nothing taken away, and nothing else lights it (no sun, no surroundings).
"""

from __future__ import annotations

import copy
import json
import math

import numpy as np
import pytest
from helpers import PRESETS

from core_tracer import render_passes
from core_tracer.photometry import materials
from core_tracer.photometry.bands import Bands
from core_tracer.photometry.cie import xyz_matrix
from core_tracer.raytrace import spectral
from core_tracer.raytrace.engine.rays import CUTOFF
from core_tracer.scene.validate import parse_scene

pytestmark = pytest.mark.slow

FLUX_LM = 440.0
RADIUS_MM = 8.0
SIZE = 9


def bulb_scene(ior: float = 1.0, abbe: float = 100.0, lens_filter: dict | None = None, thickness: float = 3.0) -> dict:
    """The photometric stop lamp reduced to a bare bulb behind a flat lens, at night with no light
    but the bulb's, seen on the axis by an orthographic camera 8 mm wide."""
    doc = json.loads((PRESETS / "photometric-stop-lamp.json").read_text())
    doc["camera"] = {"type": "orthographic", "position": [0, -500, 0], "target": [0, 0, 0], "up": [0, 0, 1],
                     "width": 8.0, "exposure": "ev100", "ev100": 15.0}
    doc["image"] = {"width": SIZE, "height": SIZE, "samples": 1}
    doc["light"] = {"direction": [0.3, -1.0, 0.6], "ambient": 0.0, "illuminance_lux": 0.0}
    doc["environment"] = {"world": "none"}
    lamp = doc["lamps"][0]
    lamp["cuts"]["height"] = 0.0
    lamp["lens"] = {**lamp["lens"], "material": "custom", "ior": ior, "abbe": abbe, "thickness": thickness,
                    "specular": 0.0, "diffuse_color": [0.0, 0.0, 0.0],
                    **(lens_filter or {"filter": "clear"})}
    lamp["bulb"] = {**lamp["bulb"], "type": "custom", "flux_lm": FLUX_LM, "spectrum": "incandescent",
                    "radius": RADIUS_MM, "offset": [0.0, 0.0, 0.0], "on": True}
    lamp["bulb"].pop("state", None)
    return parse_scene(doc)


def _xyz(scene: dict, bands: int | None = None) -> np.ndarray:
    result = render_passes(scene, bands=bands)
    assert result.stats["light_model"] == "photometric"
    return result.image.astype(np.float64)


def test_a_bare_bulb_shows_flux_over_four_pi_squared_r_squared():
    expected = FLUX_LM / (4.0 * math.pi ** 2 * (RADIUS_MM * 1e-3) ** 2)  # cd/m², Lambertian sphere
    luminance = _xyz(bulb_scene())[..., 1]
    assert luminance.shape == (SIZE, SIZE)
    np.testing.assert_allclose(luminance, expected, rtol=1e-5)
    doubled = copy.deepcopy(bulb_scene())
    doubled["lamps"][0]["bulb"]["flux_lm"] = 2 * FLUX_LM
    doubled["lamps"][0]["bulb"]["radius"] = RADIUS_MM  # same size: twice the flux is twice the luminance
    np.testing.assert_allclose(_xyz(doubled)[..., 1], 2 * expected, rtol=1e-5)


def _slab_transmittance(r: np.ndarray) -> np.ndarray:
    """(1 − r)² Σ r^(2m) over the passes the tracer keeps: a branch is followed while its weight in
    some band is at least the cut-off (every band at once, as the tracer's ``alive``)."""
    total = np.zeros_like(r)
    inside = 1.0 - r  # entered the slab, heading for the bulb
    while inside.max() >= CUTOFF:
        out = inside * (1.0 - r)
        if out.max() >= CUTOFF:
            total += out
        back = inside * r  # reflected at the inner face
        if back.max() < CUTOFF:
            break
        inside = back * r  # reflected again at the outer face, toward the bulb
    return total


@pytest.mark.parametrize("n", [1.3, 1.49, 1.9, 2.4])
def test_a_clear_slab_transmits_the_multiple_reflection_sum(n):
    bare = _xyz(bulb_scene())
    scene = bulb_scene(ior=n, abbe=100.0)
    bands = Bands.uniform(spectral.DEFAULT_BANDS)
    n_band = materials.refractive_index(n, 100.0, bands.centres_nm)
    r = ((n_band - 1.0) / (n_band + 1.0)) ** 2
    walked = _slab_transmittance(r)
    # the closed form (1 − r)²/(1 − r²) = (1 − r)/(1 + r); the walk leaves out the passes below
    # the cut-off (at n = 1.3 the second pass, (1 − r)² r² = 2.8e-4)
    assert np.all(np.abs(walked - (1.0 - r) / (1.0 + r)) < CUTOFF)
    seen = _xyz(scene)
    # per band: the bulb's band radiance × the slab's band transmittance, to XYZ
    from core_tracer.photometry import sources

    bulb = sources.bulb_spectral_radiance(FLUX_LM, sources.incandescent(), RADIUS_MM, bands)
    expected = (bulb * walked) @ xyz_matrix(bands)
    np.testing.assert_allclose(seen, np.broadcast_to(expected, seen.shape), rtol=1e-5)
    ratio = seen[..., 1] / bare[..., 1]
    r_d = ((n - 1) / (n + 1)) ** 2
    assert abs(float(ratio.mean()) - (1 - r_d) / (1 + r_d)) < 2e-3  # the luminance ratio, at n_d


def _cut_on(lam: np.ndarray, edge: float, slope: float, lo: float, hi: float) -> np.ndarray:
    """The logistic cut-on the scene states (docs/scene-format.md, filter_edge_nm ...), written out here."""
    return lo + (hi - lo) / (1.0 + np.exp(-(lam - edge) / slope))


@pytest.mark.parametrize("edge, slope", [(605.0, 7.0), (620.0, 15.0)])
def test_a_red_filter_gives_the_xy_of_illuminant_a_through_its_curve(colour, edge, slope):
    lens_filter = {"filter": "custom", "filter_edge_nm": edge, "filter_slope_nm": slope,
                   "filter_range": [0.001, 0.9], "filter_thickness": 3.0}
    scene = bulb_scene(lens_filter=lens_filter, thickness=3.0)  # the curve holds at the lens's thickness
    shape = colour.SpectralShape(360, 830, 1)
    illuminant_a = colour.SDS_ILLUMINANTS["A"].copy().align(shape)
    lam = illuminant_a.wavelengths
    through = colour.SpectralDistribution(dict(zip(lam, illuminant_a.values * _cut_on(lam, edge, slope, 0.001, 0.9),
                                                   strict=True)))
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    expected = np.asarray(colour.XYZ_to_xy(colour.sd_to_XYZ(through, cmfs, method="Integration")))
    # 81 bands (5 nm) against the 1 nm integral (measured 0.00024 and 0.00018); the default K
    # against 81 bands within the K-convergence limit, 0.001 (measured 0.0007 and 0.0005 at K = 40)
    fine = _chromaticity(_xyz(scene, bands=81))
    assert np.abs(fine - expected).max() < 3e-4, (fine.mean(axis=(0, 1)), expected)
    default = _chromaticity(_xyz(scene))
    assert np.abs(default - fine).max() < 1e-3, (default.mean(axis=(0, 1)), fine.mean(axis=(0, 1)))


def _chromaticity(XYZ: np.ndarray) -> np.ndarray:
    return XYZ[..., :2] / XYZ.sum(axis=-1, keepdims=True)

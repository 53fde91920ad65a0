"""Lamps the measures are checked on: the shipped stop lamp made into a bulb at the focus of a bare
paraboloid (a lens of index 1.0001 with no filter and no cuts, no glow), and into a bare bulb (the same
with the reflector's finish made black), whose intensities have closed forms."""

from __future__ import annotations

import numpy as np
import pytest

from core_tracer.raytrace import spectral
from core_tracer.scene import parse_scene, read_json

# n_d must lie above 1 (``materials.cauchy_coefficients``); at 1.0001 the lens's Fresnel reflectance
# is ((n − 1)/(n + 1))² = 2.5e-9 and its refraction turns rays by under 0.01°: a lens that is not there.
WINDOW_IOR = 1.0001


def paraboloid_document(repo_root) -> dict:
    doc = read_json(repo_root / "presets" / "photometric-stop-lamp.json")
    lamp = doc["lamps"][0]
    lamp["lens"].update(material="custom", ior=WINDOW_IOR, abbe=100.0, filter="clear")
    lamp["cuts"]["height"] = 0.0
    lamp["reflector"]["scatter_share"] = 0.0  # a pure mirror of the finish's reflectance
    return doc


@pytest.fixture
def paraboloid_lamp(repo_root) -> dict:
    """A P21/5W stop filament (440 lm, radius 8 mm) at the focus (f = 18 mm) of an aluminised
    paraboloid of rim radius 45 mm, socket radius 5 mm, behind a lens that is not there."""
    return parse_scene(paraboloid_document(repo_root))


@pytest.fixture
def bare_bulb(repo_root, monkeypatch) -> dict:
    """The paraboloid lamp with a black reflector (its finish's reflectance 0): the bulb alone in a
    black cup, seen through a window."""
    monkeypatch.setattr(spectral, "finish_reflectance", lambda reflector, bands: np.zeros(bands.k))
    return parse_scene(paraboloid_document(repo_root))


@pytest.fixture(scope="session")
def colour():
    """colour-science, the independent estimator of the colour tests (as tests/photometry/conftest.py)."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        import colour as colour_module
    return colour_module

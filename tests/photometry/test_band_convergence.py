"""K by measurement (issue 22 item 2): every photometric preset rendered by the tracer at the default
K (``spectral.DEFAULT_BANDS``) and at 81 bands (5 nm): the lit lens's intensity-weighted xy within
0.001 and its mean luminance within 0.5 % (the whole image for an unlit preset). The measure is
``benchmarks/bench_photometric_bands.py``'s, which prints the figures at several K."""

from __future__ import annotations

import sys

import numpy as np
import pytest
from helpers import ROOT

from core_tracer import load_scene
from core_tracer.raytrace import spectral

sys.path.insert(0, str(ROOT / "benchmarks"))
import bench_photometric_bands as bench  # noqa: E402

pytestmark = pytest.mark.slow

PRESETS = bench.photometric_presets()
# Narrow LED spectra (20 nm wide) are not yet met at the default K: measured at 48 px, the LED stop lamp's
# lit-lens luminance is 2.04 % off 81 bands at K = 40 and 0.55 % at 60, the light-guide tail lamp's xy 0.00145
# at 40 and 0.00039 at 60 (K ~ N^-3). Known and open (issue 32: K per scene from its narrowest spectrum); strict,
# so the day they meet the limits this says so.
# (The rear combination meets them: its lit lens is dominated by the white and amber lamps.)
NARROW_LED = {"led-stop-lamp", "led-stop-lamp-freeform-lens-photometric", "led-light-guide-tail-lamp"}


def _marked(path):
    if path.stem in NARROW_LED:
        return pytest.param(path, marks=pytest.mark.xfail(strict=True, reason="narrow LED spectra need K > 40"))
    return path


def test_every_photometric_preset_is_measured():
    assert len(PRESETS) >= 8


@pytest.mark.parametrize("path", [_marked(p) for p in PRESETS], ids=lambda p: p.stem)
def test_default_bands_meet_81_bands(path):
    table, luminance, xy, pixels = bench.errors(load_scene(path), [spectral.DEFAULT_BANDS], size=48, samples=1)
    xy_error, luminance_error = table[spectral.DEFAULT_BANDS]
    assert pixels > 20 and luminance > 0 and np.isfinite(xy).all()
    assert xy_error <= bench.XY_LIMIT, (path.stem, xy_error)
    assert luminance_error <= bench.LUMINANCE_LIMIT, (path.stem, luminance_error)

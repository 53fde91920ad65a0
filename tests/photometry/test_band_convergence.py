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


def test_every_photometric_preset_is_measured():
    assert len(PRESETS) >= 8


@pytest.mark.parametrize("path", PRESETS, ids=lambda p: p.stem)
def test_default_bands_meet_81_bands(path):
    table, luminance, xy, pixels = bench.errors(load_scene(path), [spectral.DEFAULT_BANDS], size=48, samples=1)
    xy_error, luminance_error = table[spectral.DEFAULT_BANDS]
    assert pixels > 20 and luminance > 0 and np.isfinite(xy).all()
    assert xy_error <= bench.XY_LIMIT, (path.stem, xy_error)
    assert luminance_error <= bench.LUMINANCE_LIMIT, (path.stem, luminance_error)

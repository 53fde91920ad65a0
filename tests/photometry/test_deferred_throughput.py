"""The photometric mode's deferred attenuation (``spectral.Throughput``, docs/photometric.md "Speed"):
the expansion at a leaf against the per-band product computed directly, the interpolation from the
wavelength nodes, the cut-off's bound, and a render with Fresnel at the nodes against one with
Fresnel per band."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import PRESETS

from core_tracer import load_scene, render_passes
from core_tracer.photometry.materials import refractive_index
from core_tracer.raytrace import spectral
from core_tracer.raytrace.engine.rays import CUTOFF, alive
from core_tracer.raytrace.engine.render import make_context

K = spectral.DEFAULT_BANDS


@pytest.fixture(scope="module")
def stop_lamp_context():
    scene = load_scene(PRESETS / "photometric-stop-lamp.json")
    return make_context(scene, 16, 16)


def _random_branches(ctx, rng, n=2000):
    lamps = len(ctx.lamps.ior)
    lamp = rng.integers(0, lamps, n)
    travelled = np.column_stack([rng.uniform(0, 12, n), rng.uniform(0, 3, n), rng.integers(0, 4, n)]).astype(float)
    return lamp, travelled


def test_bands_are_the_per_band_product(stop_lamp_context, rng):
    """With a node at each band's centre, a leaf's bands are F(λ) exp(−α d_lens − β d_plate) ρ(λ)^m."""
    ctx = stop_lamp_context
    lamps = ctx.lamps
    throughput = spectral.Throughput.of(lamps, ctx.photometric.bands, nodes=K)
    lamp, travelled = _random_branches(ctx, rng)
    fresnel = rng.uniform(0.0, 1.0, (len(lamp), K))
    expected = (fresnel * np.exp(-lamps.absorption[lamp] * travelled[:, :1] - lamps.plate_absorption[lamp]
                                 * travelled[:, 1:2]) * lamps.reflector_bands[lamp] ** travelled[:, 2:])
    np.testing.assert_allclose(throughput.bands(fresnel, travelled, lamp), expected, rtol=1e-5, atol=1e-300)


def test_nodes_interpolate_linearly_in_inverse_square_wavelength(stop_lamp_context):
    """A Fresnel product linear in 1/λ² (as n is: two-term Cauchy) is expanded exactly from 8 nodes,
    and the nodes' indices are the material's n at the nodes' wavelengths."""
    ctx = stop_lamp_context
    bands = ctx.photometric.bands
    throughput = spectral.Throughput.of(ctx.lamps, bands, nodes=8)
    u_nodes, u_bands = 1.0 / throughput.nodes_nm**2, 1.0 / bands.centres_nm**2
    values = 0.3 + 2e4 * u_nodes
    np.testing.assert_allclose(values @ throughput.to_bands, 0.3 + 2e4 * u_bands, rtol=1e-6)
    np.testing.assert_allclose(throughput.to_bands.sum(axis=0), 1.0, rtol=1e-6)
    assert (throughput.to_bands >= 0).all()
    lens = load_scene(PRESETS / "photometric-stop-lamp.json")["lamps"][0]["lens"]
    n_d, abbe = spectral.index_of(lens)
    np.testing.assert_allclose(throughput.ior_nodes[0], refractive_index(n_d, abbe, throughput.nodes_nm), rtol=1e-12)


def test_cut_off_bound_never_ends_a_branch_the_bands_keep(stop_lamp_context, rng):
    """The bound (largest node × ``reach``) is at or above every band; ``alive`` keeps every branch
    some band of which is at or above the cut-off, and ends every branch whose bound is below it."""
    ctx = stop_lamp_context
    throughput = ctx.throughput
    lamp, travelled = _random_branches(ctx, rng, 5000)
    k = rng.uniform(0.0, 1.0, (len(lamp), len(throughput.nodes_nm))) * 10.0 ** rng.uniform(-4.5, 0, (len(lamp), 1))
    bands = throughput.bands(k, travelled, lamp)
    bound = k.max(axis=1) * throughput.reach(travelled, lamp)
    assert (bound >= bands.max(axis=1) * (1 - 1e-6)).all()
    going = alive(k, (throughput, travelled, lamp))
    assert going[bands.max(axis=1) >= CUTOFF].all()
    assert not going[bound < CUTOFF].any()


@pytest.mark.slow
@pytest.mark.parametrize("preset", ["photometric-stop-lamp", "four-lamp-night-lit-photometric"])
def test_render_with_nodes_matches_fresnel_per_band(preset, monkeypatch):
    """The lit lens (luminance at least 1/10 of the 99th percentile) rendered with Fresnel at the
    default nodes against Fresnel per band: mean luminance within 0.1 %, xy of its summed XYZ within
    0.0002 (benchmarks/bench_fresnel_nodes.py measures 3e-5 and 1e-5 at most over the presets)."""
    scene = load_scene(PRESETS / f"{preset}.json")
    images = {}
    for nodes in (K, spectral.FRESNEL_NODES):
        monkeypatch.setattr(spectral, "FRESNEL_NODES", nodes)
        images[nodes] = render_passes(scene, 64, 40, keep_passes=False, threads=1).image.astype(np.float64)
    exact, nodes = images[K], images[spectral.FRESNEL_NODES]
    lit = exact[..., 1] >= 0.1 * np.percentile(exact[..., 1], 99)
    assert lit.sum() > 20
    assert abs(nodes[..., 1][lit].mean() / exact[..., 1][lit].mean() - 1) < 1e-3
    xy = [image[lit].sum(axis=0)[:2] / image[lit].sum() for image in (exact, nodes)]
    assert np.abs(xy[0] - xy[1]).max() < 2e-4

"""The lookups every sample makes — where its ray goes through the pixel, what the surroundings give
it — are the straightforward formulas' values exactly, only found with less work: the filter's
inverse distribution without a binary search, each pixel's shift once, the world image padded
instead of wrapped, the rays that miss the lamp looked up without tracing them."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import scene_with, write_exr

from core_tracer.raytrace import engine, environment, pixel_filter
from core_tracer.raytrace.camera import eye_rays, make_camera


@pytest.mark.seed(5)
def test_filter_offsets_are_np_interp_of_the_inverse_distribution_value_for_value(rng):
    cdf, x = pixel_filter._inverse_cdf_table("blackman-harris")
    # uniform numbers, and the table's own knots and their neighbours (the ends of the intervals)
    u = np.concatenate([rng.random(200_000), cdf[:-1], np.nextafter(cdf[1:-1], 0.0),
                        np.nextafter(cdf[:-1], 1.0), np.arange(4096) / 4096, [np.nextafter(1.0, 0.0)]])
    np.testing.assert_array_equal(pixel_filter.offsets_of("blackman-harris", u), np.interp(u, cdf, x))


@pytest.mark.parametrize("sample_major", [True, False])
def test_grid_offsets_are_the_per_ray_offsets(sample_major):
    pixels, samples = np.arange(1000, 1700), np.array([0, 3, 5, 12, 15])
    if sample_major:
        ray_pixels, ray_samples = np.tile(pixels, len(samples)), np.repeat(samples, len(pixels))
    else:
        ray_pixels, ray_samples = np.repeat(pixels, len(samples)), np.tile(samples, len(pixels))
    expected = pixel_filter.sample_offsets("blackman-harris", ray_pixels, ray_samples, 16)
    got = pixel_filter.grid_offsets("blackman-harris", pixels, samples, 16, sample_major)
    for a, b in zip(got, expected, strict=True):
        np.testing.assert_array_equal(a, b)


def _bilinear_wrapped(pixels: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Cycles' bilinear lookup of pixel centres, the image repeated at its borders (modulo)."""
    h, w = pixels.shape[:2]
    x, y = u * w - 0.5, (1.0 - v) * h - 0.5
    i, j = np.floor(x).astype(int), np.floor(y).astype(int)
    fx, fy = (x - i)[:, None], (y - j)[:, None]
    p = pixels.astype(np.float64)
    top = p[j % h, i % w] * (1 - fx) + p[j % h, (i + 1) % w] * fx
    bottom = p[(j + 1) % h, i % w] * (1 - fx) + p[(j + 1) % h, (i + 1) % w] * fx
    return top * (1 - fy) + bottom * fy


@pytest.mark.seed(3)
def test_radiance_at_the_seams_and_poles_repeats_the_border(tmp_path, rng):
    pixels = rng.random((16, 32, 3)).astype(np.float32)
    env = environment.Environment(pixels, 1.7, math.radians(30.0))
    # along the seam (u = 0 and 1), at the poles (v = 1, 0), and everywhere
    seam = [[-1.0, 0.0, 0.0], [-1.0, -0.0, 0.0], [-1.0, 1e-17, 0.3], [-1.0, -1e-17, -0.3]]
    turned = [[math.cos(a) * d[0] + math.sin(a) * d[1], -math.sin(a) * d[0] + math.cos(a) * d[1], d[2]]
              for d in seam for a in [math.radians(30.0)]]
    d = np.concatenate([np.array(turned), [[0.0, 0.0, 1.0], [0.0, 0.0, -1.0], [1e-9, 0.0, -1.0]],
                        rng.normal(size=(5000, 3))])
    d /= np.linalg.norm(d, axis=1)[:, None]
    u, v = env.texture_coordinates(d)
    assert u.min() == 0.0 or u.max() == 1.0
    np.testing.assert_allclose(env.radiance(d), 1.7 * _bilinear_wrapped(pixels, u, v), rtol=1e-12, atol=0)


def _bits(a: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(a).view(np.uint64)


@pytest.mark.seed(6)
def test_radiance_and_irradiance_are_the_plain_formulas_to_the_last_bits(rng):
    # The lookups work in place, a channel at a time on a padded copy of the image: the same
    # operations on every element as the plain expressions below. Equal within 2 ulp, not bit for
    # bit: numpy's vectorised arctan2/arcsin (AVX-512 here) gave 1-ulp differences once in a full
    # CI run (fresh clone of 41dc24e) and never alone; the lookups' own arithmetic is exact.
    pixels = (rng.random((16, 32, 3)) * 10.0).astype(np.float32)
    env = environment.Environment(pixels, 1.7, math.radians(30.0))
    d = rng.normal(size=(20_000, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    c, s = math.cos(env.rotation), math.sin(env.rotation)
    x, y = c * d[:, 0] - s * d[:, 1], s * d[:, 0] + c * d[:, 1]
    u = -np.arctan2(y, x) / (2.0 * math.pi) + 0.5
    v = np.arctan2(d[:, 2], np.hypot(x, y)) / math.pi + 0.5
    got_u, got_v = env.texture_coordinates(d)
    np.testing.assert_array_max_ulp(got_u, u, maxulp=2)
    np.testing.assert_array_max_ulp(got_v, v, maxulp=2)
    h, w = pixels.shape[:2]
    px, py = u * w - 0.5, (1.0 - v) * h - 0.5
    i, j = np.floor(px).astype(int), np.floor(py).astype(int)
    tx, ty = (px - np.floor(px))[:, None], (py - np.floor(py))[:, None]
    top = pixels[j % h, i % w] * (1.0 - tx) + pixels[j % h, (i + 1) % w] * tx  # float32 x float64: float64
    bottom = pixels[(j + 1) % h, i % w] * (1.0 - tx) + pixels[(j + 1) % h, (i + 1) % w] * tx
    np.testing.assert_allclose(env.radiance(d), (top * (1.0 - ty) + bottom * ty) * env.strength, rtol=1e-12, atol=0)
    n = environment.IRRADIANCE_LON, environment.IRRADIANCE_LAT
    ex = (np.arctan2(d[:, 1], d[:, 0]) + math.pi) / (2.0 * math.pi) * n[0]
    ey = (np.arcsin(np.clip(d[:, 2], -1.0, 1.0)) + 0.5 * math.pi) / math.pi * n[1]
    i0, j0 = np.floor(ex), np.minimum(np.floor(ey), n[1] - 1)
    tx, ty = (ex - i0)[:, None], (ey - j0)[:, None]
    i0, j0 = i0.astype(np.int64) % n[0], j0.astype(np.int64)
    i1 = (i0 + 1) % n[0]
    m = env._irradiance_map
    expected = ((m[j0, i0] * (1.0 - tx) + m[j0, i1] * tx) * (1.0 - ty)
                + (m[j0 + 1, i0] * (1.0 - tx) + m[j0 + 1, i1] * tx) * ty)
    np.testing.assert_allclose(env.irradiance(d), expected, rtol=1e-12, atol=0)


@pytest.mark.seed(4)
def test_rays_missing_the_lamp_are_looked_up_as_the_tracer_would_trace_them(tmp_path, rng):
    sky = write_exr(tmp_path / "sky.exr", rng.random((32, 64, 3)).astype(np.float32) + 0.1)
    scene = scene_with(**{"environment": {"world": "file", "file": sky}, "image": {"width": 48, "height": 36}})
    scene["camera"]["fov_deg"] = 50.0  # the lamp and plenty of surroundings around it
    cam = make_camera(scene["camera"], 48, 36)
    ctx = engine.context.Context(scene, cam, False, 16, "blackman-harris")
    pixels = np.arange(48 * 36)
    o, d = eye_rays(cam, np.tile(pixels, 4), pixel_filter.grid_offsets("blackman-harris", pixels, np.arange(4), 16,
                                                                        sample_major=True))
    split, whole = engine.rays.Band(len(o), ctx), engine.rays.Band(len(o), ctx)
    engine.walk.trace_eye_rays(ctx, split, o, d)
    engine.walk.trace_rays(ctx, whole, o, d)
    background = whole.acc[engine.rays.BACKGROUND_PASS]
    others = np.delete(whole.acc, engine.rays.BACKGROUND_PASS, axis=0)
    seeing_only_the_world = others.max(axis=(0, 2)) == 0
    assert seeing_only_the_world.mean() > 0.3 and (~seeing_only_the_world).sum() > 100
    assert (background[seeing_only_the_world] > 0).all()
    # The same values; to the last bit but for the surroundings' lookups, whose arctan2 (numpy's
    # SIMD code) was seen to differ in the last bit between two calls on equal directions.
    np.testing.assert_allclose(split.acc, whole.acc, rtol=1e-13, atol=0)
    np.testing.assert_array_equal(np.delete(split.acc, engine.rays.BACKGROUND_PASS, 0), others)
    assert split.segments == whole.segments


@pytest.mark.slow
@pytest.mark.seed(6)
def test_adaptive_pixels_that_see_only_the_world_are_the_traced_ones(tmp_path, monkeypatch, rng):
    """Busy pixels whose neighbourhood saw only the surroundings take their other samples from the
    world image directly (``adaptive._world_samples``): the image is the one tracing them gives."""
    sky = write_exr(tmp_path / "sky.exr", rng.random((32, 64, 3)).astype(np.float32) + 0.1)
    scene = scene_with(**{"environment": {"world": "file", "file": sky}})
    scene["camera"]["fov_deg"] = 50.0

    def render():
        return engine.render_passes(scene, 48, 36, samples=16, keep_passes=False, threads=1)

    looked_up = render()
    shortcut = engine.adaptive._world_samples
    taken = []

    def trace_them_all(ctx, band, pixels, idx, pilot, pilot_values):
        taken.append(len(idx) - len(shortcut(ctx, engine.rays.Band(band.n, ctx), pixels, idx, pilot, pilot_values)))
        return idx

    monkeypatch.setattr(engine.adaptive, "_world_samples", trace_them_all)
    traced = render()
    assert sum(taken) > 0.3 * 48 * 36  # most of the surroundings took the shortcut
    np.testing.assert_allclose(looked_up.image, traced.image, rtol=1e-6, atol=0)  # float32 images, last bit
    assert looked_up.stats["segments"] == traced.stats["segments"]
    assert looked_up.stats["busy_pixels"] == traced.stats["busy_pixels"]

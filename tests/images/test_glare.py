"""Glare (Spencer et al. 1995, photopic bloom): the PSF, energy, and what stays unchanged."""

from __future__ import annotations

import json

import numpy as np
import pytest
from helpers import FOUR_LAMPS, assert_bad_input, run_cli, scene_with

from core_tracer.images import glare
from core_tracer.scene.validate import load_scene

DEG_PER_PX = 0.0315  # the four-lamp preset's camera at 512 px


def _glare_on(scene: dict, threshold: float = 1.0, strength: float = 1.0) -> dict:
    scene["glare"] = {"on": True, "threshold": threshold, "strength": strength}
    return scene


def test_psf_decreases_with_angle():
    theta = np.linspace(0.0, 20.0, 20001)
    assert np.all(np.diff(glare.psf(theta)) < 0)


def test_kernel_is_normalised_and_radially_decreasing():
    k = glare.kernel(64, 96, DEG_PER_PX)
    assert k.shape == (127, 191)
    assert k.sum() == pytest.approx(1.0, abs=1e-12)
    cy, cx = 63, 95
    assert k.argmax() == cy * k.shape[1] + cx
    for ray in (k[cy, cx:], k[cy:, cx], k[cy, cx::-1], np.diagonal(k[cy:, cx:])):
        assert np.all(np.diff(ray) < 0)
    # symmetric: a point's glow is round
    assert np.allclose(k, k[::-1, ::-1], rtol=0, atol=1e-15)
    assert k[cy, cx + 7] == pytest.approx(k[cy + 7, cx], rel=1e-12)


def test_kernel_far_field_follows_the_psf():
    # Away from the centre a pixel holds the PSF at its centre times its area (f2 ~ 1/θ²).
    k = glare.kernel(64, 64, DEG_PER_PX)
    ratio = k[63, 63 + 40] / k[63, 63 + 20]
    assert ratio == pytest.approx(glare.psf(40 * DEG_PER_PX) / glare.psf(20 * DEG_PER_PX), rel=1e-9)


def _bright_image(rng: np.random.Generator, h: int = 48, w: int = 64) -> np.ndarray:
    image = rng.uniform(0.0, 0.8, (h, w, 3)).astype(np.float32)
    image[10, 5] = (40.0, 3.0, 0.5)  # near the edge: its glow would leave the frame
    image[30:33, 40:44] = (5.0, 9.0, 2.0)
    return image


@pytest.mark.seed(11)
def test_energy_is_conserved_per_channel(rng):
    image = _bright_image(rng)
    out = glare.spread(image, 1.0, 1.0, DEG_PER_PX)
    assert out is not image and out.dtype == np.float32
    before = image.astype(np.float64).sum(axis=(0, 1))
    after = out.astype(np.float64).sum(axis=(0, 1))
    assert np.allclose(after, before, rtol=1e-6, atol=0)
    assert not np.array_equal(out, image)


@pytest.mark.seed(11)
def test_image_without_bright_pixels_is_unchanged(rng):
    image = _bright_image(rng)
    image = np.minimum(image, 0.99)
    out = glare.spread(image, 1.0, 1.0, DEG_PER_PX)
    assert out is image
    assert glare.spread(image, 0.5, 0.0, DEG_PER_PX) is image  # strength 0 spreads nothing


def test_only_the_light_above_the_threshold_spreads():
    # Glare is linear in the light above the threshold: the dim pixels just add on.
    bright = np.zeros((40, 40, 3), np.float32)
    bright[20, 20] = (10.0, 10.0, 10.0)
    dim = np.full((40, 40, 3), 0.5, np.float32)
    both = glare.spread(bright + dim, 1.0, 1.0, DEG_PER_PX).astype(np.float64)
    alone = glare.spread(bright, 1.0, 1.0, DEG_PER_PX).astype(np.float64)
    # What stays in each pixel is its light up to the threshold; the rest is the spread light,
    # which scales with the excess (9.5 with the dim light under the bright pixel, 9 without).
    spread_both = both - np.minimum(bright + dim, 1.0)
    spread_alone = alone - np.minimum(bright, 1.0)
    assert np.allclose(spread_both, spread_alone * 9.5 / 9.0, rtol=1e-5, atol=1e-6)  # float32 output


@pytest.mark.seed(11)
def test_off_leaves_the_render_unchanged(rng):
    scene = load_scene(FOUR_LAMPS)
    assert scene["glare"] == {"on": False, "threshold": 1.0, "strength": 1.0}
    image = _bright_image(rng)
    assert glare.apply(image, scene) is image


def test_a_lit_lamp_glows_around_its_lens():
    from core_tracer import render
    scene = _glare_on(load_scene(FOUR_LAMPS))
    image = render(scene, 96, 96)
    out = glare.apply(image, scene)
    assert np.allclose(out.sum(axis=(0, 1), dtype=np.float64), image.sum(axis=(0, 1), dtype=np.float64), rtol=1e-6)
    black = image.max(axis=2) == 0.0  # the world around the body
    assert black.any() and (out[black] > 0).any()  # the glow reaches past the body
    # ... but it is a glow, not a smear: the light moved is a small part of the image's
    assert np.abs(out - image).sum() < 0.5 * image.sum()


@pytest.mark.slow
@pytest.mark.parametrize(("field", "value", "needle"), [
    ("strength", 2.0, "[0, 1]"),
    ("threshold", 0.0, "(0, 1e+06]"),
    ("on", 1, "true or false"),
])
def test_validation_names_the_field_and_range(tmp_path, field, value, needle):
    doc = json.loads(FOUR_LAMPS.read_text())
    doc["glare"] = {field: value}
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(doc))
    assert_bad_input(run_cli("validate", path), f"glare.{field}", needle)


def test_scene_with_glare_validates():
    scene = scene_with(**{"glare.on": True, "glare.strength": 0.5})
    assert scene["glare"] == {"on": True, "threshold": 1.0, "strength": 0.5}


@pytest.mark.slow
def test_glare_is_in_the_memory_budget(tmp_path):
    doc = json.loads(FOUR_LAMPS.read_text())
    doc["glare"] = {"on": True}
    path = tmp_path / "glare.json"
    path.write_text(json.dumps(doc))
    out = tmp_path / "big.exr"
    # 8192 x 8192 renders without glare; with it the FFT arrays do not fit: refused before rendering.
    assert_bad_input(run_cli("render", path, "-o", out, "--width", "8192", "--height", "8192"),
                     "image", "without glare", "allowed at most 4.0 GB")
    assert not out.exists()


@pytest.mark.slow
def test_cli_render_and_study_hold_the_glare(tmp_path):
    from core_tracer import render
    from core_tracer.images.imageio import read_image
    from core_tracer.study import run as study_run
    from core_tracer.study.definition import Study

    doc = json.loads(FOUR_LAMPS.read_text())
    doc["glare"] = {"on": True, "threshold": 1.5}
    doc["image"] = {"width": 40, "height": 30}
    path = tmp_path / "glare.json"
    path.write_text(json.dumps(doc))
    scene = load_scene(path)
    expected = glare.apply(render(scene), scene)
    proc = run_cli("render", path, "-o", tmp_path / "out.exr")
    assert proc.returncode == 0, proc.stderr
    image, header = read_image(tmp_path / "out.exr")
    assert header["glare"]["on"]
    np.testing.assert_array_equal(image, expected)  # the EXR holds the glared linear image
    assert not np.array_equal(image, render(scene))

    study = Study.from_doc({"schema": "lamp-study/1", "base": scene, "size": [40, 30],
                            "axes": [{"parameter": "lamps[0].lens.ior", "values": [1.45, 1.6]}]})
    here = study_run.run_study(study, workers=0)
    workers = study_run.run_study(study, workers=1)
    variant = study.variants[0].scene
    np.testing.assert_array_equal(here[0], glare.apply(render(variant, 40, 30), variant))
    np.testing.assert_array_equal(workers[0], here[0])


def test_a_point_spreads_by_the_psf_centred_on_it():
    image = np.zeros((101, 101, 3), np.float32)
    image[50, 50] = (1001.0, 1.0, 1.0)  # only red is above the threshold
    out = glare.spread(image, 1.0, 1.0, DEG_PER_PX).astype(np.float64)
    red = out[..., 0]
    assert red[50, 70] == pytest.approx(red[70, 50], rel=1e-9) == pytest.approx(red[50, 30], rel=1e-9)
    k = glare.kernel(101, 101, DEG_PER_PX)
    # a source in the middle keeps a constant share of its PSF: the glow has the kernel's shape
    assert red[50, 70] / red[50, 90] == pytest.approx(k[100, 120] / k[100, 140], rel=1e-6)
    assert red[50, 50] < 1001.0 and red.sum() == pytest.approx(1001.0, rel=1e-6)
    np.testing.assert_array_equal(out[..., 1:], image[..., 1:])  # green and blue untouched

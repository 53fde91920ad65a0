"""Outputs: band image → XYZ, luminance, xy; the EXR's named channels and units; EV100 exposure;
the false-colour map and its legend."""

from __future__ import annotations

import math

import numpy as np
import OpenImageIO as oiio
import pytest

from core_tracer.images import imageio
from core_tracer.images import photometric as photometric_images
from core_tracer.photometry import cie, output, sources
from core_tracer.photometry.bands import Bands


def _bulb_image(bands: Bands) -> tuple[np.ndarray, float]:
    radiance = sources.bulb_spectral_radiance(440.0, sources.incandescent(), 3.0, bands)
    image = np.zeros((6, 9, bands.k))
    image[1:4, 2:7] = radiance
    return image, sources.bulb_luminance(440.0, 3.0)


def test_band_image_luminance_and_xy():
    b = Bands.uniform(16)
    image, lum = _bulb_image(b)
    np.testing.assert_allclose(output.luminance(image, b)[1:4, 2:7], lum, rtol=1e-12)
    assert np.all(output.luminance(image, b)[0] == 0)
    xy = output.chromaticity(output.band_image_to_xyz(image, b))
    np.testing.assert_allclose(xy[2, 3], cie.xy(sources.incandescent().band_means(b) @ cie.xyz_matrix(b)))
    np.testing.assert_allclose(xy[0, 0], cie.D65_WHITE_XY)
    with pytest.raises(ValueError, match="16 bands"):
        output.band_image_to_xyz(np.zeros((2, 2, 15)), b)


def test_exr_channels_units_and_values(tmp_path):
    b = Bands.uniform(8)
    image, lum = _bulb_image(b)
    xyz = output.band_image_to_xyz(image, b)
    path = tmp_path / "lamp.exr"
    photometric_images.write_photometric_exr(path, xyz, channels=("X", "Y", "Z", "L", "x", "y"), bands=b)
    planes, attrs = photometric_images.read_photometric_exr(path)
    assert sorted(planes) == sorted(["X", "Y", "Z", "L", "x", "y"])  # EXR keeps channels by name, not order
    np.testing.assert_allclose(planes["Y"][2, 3], lum, rtol=1e-6)  # float32
    np.testing.assert_allclose(planes["L"], planes["Y"])
    np.testing.assert_allclose(np.stack([planes["x"], planes["y"]], -1), cie.xy(xyz), atol=1e-7)
    assert "Y: CIE 1931 2 deg Y = luminance in cd/m2" in attrs[output.UNITS_ATTRIBUTE]
    assert attrs["lamp:km"] == "683.002"
    assert [float(v) for v in attrs[output.BANDS_ATTRIBUTE].split()] == list(b.edges_nm)
    inp = oiio.ImageInput.open(str(path))  # another reader sees the same: float channels, zip
    assert inp.spec().format == oiio.FLOAT and inp.spec().nchannels == 6
    inp.close()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["lamp.exr"]  # no temporary left


def test_exr_refuses_other_formats_and_channels(tmp_path):
    xyz = np.ones((2, 2, 3))
    with pytest.raises(imageio.SceneError, match=".exr"):
        photometric_images.write_photometric_exr(tmp_path / "lamp.png", xyz)
    with pytest.raises(ValueError, match="channel"):
        photometric_images.write_photometric_exr(tmp_path / "lamp.exr", xyz, channels=("R",))
    assert not any(tmp_path.iterdir())


def test_exposure_maps_saturation_luminance_to_one():
    for ev in (-2.0, 0.0, 7.5, 15.0):
        assert 1.2 * 2.0 ** ev * output.exposure_scale(ev) == pytest.approx(1.0, rel=1e-15)
    assert output.exposure_scale(1.0) == pytest.approx(0.5 * output.exposure_scale(0.0))
    # a meter reading 12.5 cd/m² picks EV100 = 100/12.5 → log2(100) ... = log2(L·8)
    assert output.ev100_for_average_luminance(12.5) == pytest.approx(math.log2(100.0))
    with pytest.raises(ValueError, match="EV100"):
        output.exposure_scale(float("nan"))


def test_scene_linear_keeps_out_of_gamut_red():
    b = Bands.uniform(81)
    red = sources.led(630.0, 20.0).band_means(b) @ cie.xyz_matrix(b)
    rgb = output.scene_linear_rec709(red, 10.0)
    assert rgb[0] > 0 and (rgb[1] < 0 or rgb[2] < 0)  # outside Rec.709: not clipped by us


def test_false_colour_is_monotone_with_a_legend():
    lum = np.outer(np.logspace(4, -1, 50), np.ones(30))
    image = photometric_images.false_colour(lum, 0.1, 1e4)
    assert image.shape == (50, 30 + photometric_images.LEGEND_WIDTH, 3)
    assert image.min() >= 0.0 and image.max() <= 1.0
    column = image[:, 5]
    brightness = column.sum(axis=1)
    assert brightness[0] > brightness[-1]  # bright (white end) at the top, dark blue at the bottom
    legend = image[:, 30:]
    assert (legend == 1.0).all(axis=2).sum() > 50  # white ink: the labels and ticks
    dark = photometric_images.false_colour(np.zeros((4, 4)), 1.0, 10.0, legend=False)
    assert (dark == 0).all()
    with pytest.raises(ValueError, match="range"):
        photometric_images.false_colour(lum, 10.0, 1.0)


def test_false_colour_png(tmp_path):
    lum = np.outer(np.logspace(5, -1, 120), np.ones(160))
    path = tmp_path / "false.png"
    lo, hi = photometric_images.write_false_colour_png(path, lum)
    assert (lo, hi) == (10.0, 1e5)
    inp = oiio.ImageInput.open(str(path))
    spec = inp.spec()
    assert (spec.width, spec.height) == (160 + photometric_images.LEGEND_WIDTH, 120)
    assert spec.getattribute("lamp:false_colour") == "log10 luminance 10 to 100000 cd/m2"
    inp.close()

"""A photometric EXR as other tools read it (issue 31 item 3): a red stop lamp's render written by the
CLI, read back by OpenImageIO (the header: chromaticities of CIE XYZ, whiteLuminance, units, EV100;
the values: X, Y, Z in cd/m²) and by Blender's own reader (``bpy.data.images.load``: the colour
space "Linear CIE-XYZ E" chosen by itself, the pixels red in its scene-linear Rec.709 and through
its view). Before, the file had no chromaticities and Blender took X, Y, Z for R, G, B (a gold lamp)."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import STOP_LAMP, lit_lens_ratios, run_cli

from core_tracer.images import display, imageio
from core_tracer.images import photometric as photometric_images
from core_tracer.photometry import cie, output

pytestmark = pytest.mark.blender

SIZE = ("--width", "48", "--height", "48", "--samples", "1")


@pytest.fixture(scope="module")
def red_exr(tmp_path_factory):
    path = tmp_path_factory.mktemp("exr") / "stop.exr"
    proc = run_cli("render", STOP_LAMP, "-o", path, *SIZE)
    assert proc.returncode == 0, proc.stderr
    return path


@pytest.mark.slow
def test_openimageio_reads_the_header_and_the_values(red_exr):
    oiio = imageio.oiio_module()
    spec = oiio.ImageInput.open(str(red_exr)).spec()
    assert sorted(spec.channelnames) == ["X", "Y", "Z", "x", "y"]  # EXR keeps them in its own order
    assert spec.getattribute("chromaticities") == pytest.approx((1, 0, 0, 1, 0, 0, 1 / 3, 1 / 3))
    assert spec.getattribute("whiteLuminance") == 1.0
    assert "Y: CIE 1931 2 deg Y = luminance in cd/m2" in spec.getattribute("lamp:units")
    assert spec.getattribute("lamp:ev100") == "15"  # the preset's camera
    channels, _attrs = photometric_images.read_photometric_exr(red_exr)
    XYZ = np.stack([channels[c] for c in "XYZ"], axis=-1)
    lit = XYZ[..., 1] > 0.5 * XYZ[..., 1].max()
    x, y = cie.xy(XYZ[lit].sum(axis=0))
    assert x > 0.65 and y < 0.34  # the lens's red (UN R48's red region lies beyond x 0.65)
    np.testing.assert_allclose(channels["x"][lit], cie.xy(XYZ[lit])[:, 0], atol=1e-6)


@pytest.mark.slow
def test_blender_reads_it_as_xyz_and_shows_it_red(lamp_addon, bl_scene, red_exr):
    import bpy

    image = bpy.data.images.load(str(red_exr), check_existing=False)
    assert image.colorspace_settings.name == "Linear CIE-XYZ E"
    linear = lamp_addon.image_view.image_to_array(image)  # Blender's scene-linear (Linear Rec.709)
    g, b, pixels = lit_lens_ratios(linear)
    assert pixels > 20 and g < 0.2 and b < 0.2, (g, b)  # red, green and blue near zero or below
    # as a designer shows it: at the file's EV100 (lamp:ev100) through the scene's view
    ev100 = float(imageio.read_attribute(red_exr, "lamp:ev100"))
    shown = display.view_transform(bl_scene.view_settings.view_transform).to_display(
        linear * np.float32(output.exposure_scale(ev100)))
    g, b, _pixels = lit_lens_ratios(shown)
    assert g < 0.5 and b < 0.5, (g, b)
    # what Blender read is the file's XYZ taken to Rec.709 (adapted from E's white to D65's:
    # Blender's own configuration), so a white of X = Y = Z shows neutral
    channels, _attrs = photometric_images.read_photometric_exr(red_exr)
    XYZ = np.stack([channels[c] for c in "XYZ"], axis=-1)
    lit = XYZ[..., 1] > 0.5 * XYZ[..., 1].max()
    ours = cie.xyz_to_linear_rec709(XYZ[lit].mean(axis=0))
    theirs = linear[lit].mean(axis=0)
    assert theirs[0] == pytest.approx(ours[0], rel=0.1)
    bpy.data.images.remove(image)


@pytest.mark.slow
def test_blender_took_xyz_for_rgb_without_the_chromaticities(lamp_addon, bl_scene, red_exr, tmp_path):
    """The fault the attribute removes (and why the references carry it too)."""
    import bpy

    channels, _attrs = photometric_images.read_photometric_exr(red_exr)
    XYZ = np.stack([channels[c] for c in "XYZ"], axis=-1)
    imageio.write_channels(tmp_path / "bare.exr", XYZ, ("X", "Y", "Z"))
    image = bpy.data.images.load(str(tmp_path / "bare.exr"), check_existing=False)
    assert image.colorspace_settings.name != "Linear CIE-XYZ E"
    g, _b, _n = lit_lens_ratios(lamp_addon.image_view.image_to_array(image))
    assert g > 0.3  # Y taken for green: an orange-gold lamp
    bpy.data.images.remove(image)

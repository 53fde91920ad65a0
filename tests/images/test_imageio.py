"""Image files: exact EXR round trip with the scene in the header, sRGB PNG, atomic writes."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import OpenImageIO as oiio
import pytest
from helpers import BASELINE

from core_tracer.images import display, imageio
from core_tracer.scene.reading import SceneError, read_json, scene_to_json
from core_tracer.scene.validate import load_scene, parse_scene


def _random_image(rng: np.random.Generator, h: int = 7, w: int = 11) -> np.ndarray:
    # Values a renderer gives: mostly in [0, 1], some far brighter (a bulb), some exactly 0.
    img = rng.random((h, w, 3), dtype=np.float32)
    img[0, 0] = [123.456, 7.0e3, 1.0e-7]
    img[-1, -1] = 0.0
    return img


def _leftovers(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


@pytest.mark.seed(1)
def test_exr_round_trip_is_exact(tmp_path, rng):
    img = _random_image(rng)
    path = tmp_path / "out.exr"
    imageio.write_image(path, img)
    back, sc = imageio.read_image(path)
    assert sc is None
    assert back.dtype == np.float32 and back.shape == img.shape
    assert np.array_equal(back, img)
    # top row first: the distinctive pixel stays in the top-left corner
    assert back[0, 0, 1] == np.float32(7.0e3)
    # stored as 32-bit float, linear
    spec = oiio.ImageInput.open(str(path)).spec()
    assert spec.format == oiio.FLOAT
    assert tuple(spec.channelnames) == ("R", "G", "B")


def test_exr_carries_the_normalised_scene(tmp_path):
    doc = read_json(BASELINE)
    expected = parse_scene(doc)
    path = tmp_path / "scene.exr"
    imageio.write_image(path, np.zeros((4, 5, 3), np.float32), expected)
    text = oiio.ImageInput.open(str(path)).spec().getattribute(imageio.SCENE_ATTRIBUTE)
    assert text == scene_to_json(expected)
    _, back = imageio.read_image(path)
    assert back == expected


def _srgb_formula(x: float) -> float:
    # IEC 61966-2-1, written out independently of the module under test
    x = min(max(x, 0.0), 1.0)
    return 12.92 * x if x <= 0.0031308 else 1.055 * x ** (1 / 2.4) - 0.055


def test_png_is_8_bit_srgb(tmp_path):
    values = np.array([0.0, 0.001, 0.0031308, 0.01, 0.05, 0.18, 0.2140, 0.5, 0.9, 1.0, 1.5, 40.0, -0.3],
                      dtype=np.float32)
    img = np.stack([values, values[::-1], np.full_like(values, 0.18)], axis=1)[None, :, :]
    sc = load_scene(BASELINE)
    path = tmp_path / "out.png"
    imageio.write_image(path, img, sc, view=display.view_transform("Standard"), exposure=0)

    inp = oiio.ImageInput.open(str(path))
    spec = inp.spec()
    assert spec.format == oiio.UINT8 and spec.nchannels == 3
    codes = inp.read_image(oiio.UINT8)
    inp.close()
    expected = np.array([[[round(_srgb_formula(float(c)) * 255) for c in px] for px in row] for row in img])
    assert np.array_equal(codes, expected)
    # 18 % grey is sRGB code 118; the linear midpoint 0.5 is 188
    assert codes[0, 5, 2] == 118 and codes[0, 7, 0] == 188
    assert spec.getattribute(imageio.SCENE_ATTRIBUTE) == scene_to_json(sc)

    back, back_scene = imageio.read_image(path)
    assert back_scene == sc
    # decoded back to linear within half an 8-bit step of the clipped input
    clipped = np.clip(img, 0, 1)
    assert np.allclose(display.srgb_encode(back), display.srgb_encode(clipped), atol=0.5 / 255 + 1e-6)


def test_srgb_matches_openimageio_colorconvert():
    x = np.linspace(0, 1, 3 * 256, dtype=np.float32).reshape(16, 16, 3)
    buf = oiio.ImageBuf(oiio.ImageSpec(16, 16, 3, oiio.FLOAT))
    buf.set_pixels(oiio.ROI(), x)
    conv = oiio.ImageBufAlgo.colorconvert(buf, "linear", "sRGB")
    assert not conv.has_error
    assert np.abs(conv.get_pixels(oiio.FLOAT) - display.srgb_encode(x)).max() < 1e-4
    assert np.allclose(display.srgb_decode(display.srgb_encode(x)), x, atol=1e-6)


@pytest.mark.parametrize("name", ["out.jpg", "out.tif", "out", "out.exr.txt"])
def test_unknown_suffix_is_refused_clearly(tmp_path, name):
    path = tmp_path / name
    with pytest.raises(SceneError) as err:
        imageio.write_image(path, np.zeros((2, 2, 3), np.float32))
    assert str(path) in str(err.value) and ".exr, .png" in str(err.value)
    assert _leftovers(tmp_path) == []


def test_bad_scene_is_refused_before_writing(tmp_path):
    sc = load_scene(BASELINE)
    sc["lamps"][0]["lens"]["ior"] = 0.5
    with pytest.raises(SceneError, match=r"lamps\[0\]\.lens\.ior"):
        imageio.write_image(tmp_path / "a.exr", np.zeros((2, 2, 3), np.float32), sc)
    assert _leftovers(tmp_path) == []


def test_no_partial_file_when_the_folder_is_missing(tmp_path):
    blocker = tmp_path / "not-a-folder"
    blocker.write_text("x")
    with pytest.raises(OSError):
        imageio.write_image(blocker / "out.exr", np.zeros((2, 2, 3), np.float32))
    assert _leftovers(tmp_path) == ["not-a-folder"]


def test_failed_final_rename_leaves_nothing_and_keeps_the_old_file(tmp_path):
    # The image is written completely to the temporary file; the rename onto a directory fails.
    target = tmp_path / "taken.exr"
    target.mkdir()
    (target / "keep").write_text("old")
    with pytest.raises(OSError):
        imageio.write_image(target, np.ones((3, 3, 3), np.float32))
    assert _leftovers(tmp_path) == ["taken.exr"]
    assert (target / "keep").read_text() == "old"


def test_failure_while_writing_keeps_the_previous_image(tmp_path):
    path = tmp_path / "out.exr"
    first = np.full((3, 4, 3), 0.25, np.float32)
    imageio.write_image(path, first)
    with pytest.raises(ValueError):
        imageio.write_image(path, np.zeros((9, 9, 4), np.float32))  # not an RGB image
    back, _ = imageio.read_image(path)
    assert np.array_equal(back, first)
    assert _leftovers(tmp_path) == ["out.exr"]


def test_read_errors_name_the_file(tmp_path):
    missing = tmp_path / "missing.exr"
    with pytest.raises(SceneError, match="missing.exr"):
        imageio.read_image(missing)
    garbage = tmp_path / "garbage.exr"
    garbage.write_bytes(b"not an exr")
    with pytest.raises(SceneError, match="garbage.exr"):
        imageio.read_image(garbage)


def test_header_with_a_broken_scene_is_reported(tmp_path):
    path = tmp_path / "odd.exr"
    spec = oiio.ImageSpec(2, 2, 3, oiio.FLOAT)
    spec.attribute(imageio.SCENE_ATTRIBUTE, '{"schema": "lamp-scene/3"}')
    out = oiio.ImageOutput.create(str(path))
    assert out.open(str(path), spec)
    out.write_image(np.zeros((2, 2, 3), np.float32))
    out.close()
    with pytest.raises(SceneError) as err:
        imageio.read_image(path)
    assert "odd.exr" in str(err.value) and "lamp-scene/3" in str(err.value)
    assert os.path.exists(path)


@pytest.mark.slow
@pytest.mark.parametrize("view", ["Standard", "AgX"])
def test_png_exposure_and_view_are_undone_on_reading(tmp_path, view):
    image = np.full((4, 6, 3), 4.0, dtype=np.float32)  # a bright lamp: clips at exposure 0 in Standard
    image[:, :3] = [8.0, 1.0, 0.25]
    transform = display.view_transform(view)
    plain, darker = tmp_path / "plain.png", tmp_path / "darker.png"
    imageio.write_image(plain, image, view=display.view_transform("Standard"), exposure=0)
    assert imageio.write_image(darker, image, view=transform, exposure=-3) == -3
    assert np.all(imageio.read_image(plain)[0] <= 1.0)  # clipped
    header = oiio.ImageInput.open(str(darker)).spec()
    assert header.getattribute(imageio.VIEW_ATTRIBUTE) == view and header.getattribute("lamp:exposure") == "-3"
    back, _ = imageio.read_image(darker)
    # 8-bit quantisation at 1/8 of the value, taken back through the view and scaled back up by 8
    np.testing.assert_allclose(back, image, rtol=0.04, atol=0.01)
    exr = tmp_path / "linear.exr"
    assert imageio.write_image(exr, image, exposure=-3) == 0.0
    np.testing.assert_array_equal(imageio.read_image(exr)[0], image)  # an EXR keeps the linear values


def test_exr_has_only_rgb_channels(tmp_path):
    path = tmp_path / "rgb.exr"
    imageio.write_image(path, np.ones((2, 3, 3), np.float32))
    assert tuple(oiio.ImageInput.open(str(path)).spec().channelnames) == ("R", "G", "B")

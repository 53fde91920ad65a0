"""The photometric mode's outputs from the CLI (issue 22 items 6 and 7): a .png at the camera's
EV100 through the view transform (the red lens reads red; the stop lamp brighter than the tail
lamp under the same EV100), an .exr of XYZ and xy with units, passes, a false-colour map."""

from __future__ import annotations

import re

import numpy as np
import pytest
from helpers import BASELINE, PRESETS, assert_bad_input, run_cli

from core_tracer import render_passes
from core_tracer.images import imageio
from core_tracer.images import photometric as photometric_images
from core_tracer.photometry import output
from core_tracer.raytrace import spectral_bands
from core_tracer.scene.validate import load_scene

pytestmark = pytest.mark.slow

STOP = PRESETS / "photometric-stop-lamp.json"
TAIL = PRESETS / "photometric-tail-lamp.json"
SIZE = ("--width", "64", "--height", "64", "--samples", "1")


def _png(path) -> np.ndarray:
    oiio = imageio.oiio_module()
    return np.asarray(oiio.ImageBuf(str(path)).get_pixels(oiio.UINT8))[..., :3].astype(np.float64)


def _render_png(scene, path, *extra) -> str:
    proc = run_cli("render", scene, "-o", path, *SIZE, *extra)
    assert proc.returncode == 0, proc.stderr
    return proc.stdout


def test_stop_and_tail_show_red_at_the_scenes_one_ev100(tmp_path):
    said = {name: _render_png(scene, tmp_path / f"{name}.png") for name, scene in (("stop", STOP), ("tail", TAIL))}
    for text in said.values():
        assert re.search(r"AgX at EV100 15\.0 on \d+ bands", text), text  # the scene's camera, not re-exposed
    stop, tail = _png(tmp_path / "stop.png"), _png(tmp_path / "tail.png")
    lens = stop.max(axis=-1) > 40  # the lit lens (the night around it is near black)
    assert lens.sum() > 50
    for image in (stop, tail):
        red, green, blue = (image[lens][:, c].mean() for c in range(3))
        assert red > 2.0 * green and red > 2.0 * blue, (red, green, blue)  # red, not orange or pink
    assert stop[lens][:, 0].mean() > tail[lens][:, 0].mean() + 20  # the stop filament shows brighter


def test_ev100_and_exposure_options(tmp_path):
    darker = _render_png(STOP, tmp_path / "a.png", "--ev100", "17")
    assert "EV100 17.0" in darker
    stops = _render_png(STOP, tmp_path / "b.png", "--ev100", "15", "--exposure", "-2")
    assert "EV100 15.0 -2.0 EV" in stops
    # EV100 17 is 2 stops less light than 15: the same picture as 15 with -2 stops
    assert np.abs(_png(tmp_path / "a.png") - _png(tmp_path / "b.png")).max() <= 1
    auto = _render_png(STOP, tmp_path / "c.png", "--ev100", "auto")
    assert re.search(r"EV100 -?\d+\.\d", auto)


def test_exr_holds_xyz_in_cd_m2_with_units_and_passes(tmp_path):
    out, passes = tmp_path / "stop.exr", tmp_path / "passes"
    proc = run_cli("render", STOP, "-o", out, *SIZE, "--passes", passes)
    assert proc.returncode == 0, proc.stderr
    assert "XYZ (Y in cd/m2)" in proc.stdout
    channels, attrs = photometric_images.read_photometric_exr(out)
    assert sorted(channels) == ["X", "Y", "Z", "x", "y"]  # EXR keeps its channels sorted
    assert "Y: CIE 1931 2 deg Y = luminance in cd/m2" in attrs[output.UNITS_ATTRIBUTE]
    assert attrs["lamp:ev100"] == "15"
    scene = load_scene(STOP)
    scene["image"].update(width=64, height=64, samples=1)
    expected = render_passes(scene, keep_passes=True)
    assert np.allclose(channels["Y"], expected.image[..., 1], rtol=1e-6, atol=1e-6)
    assert channels["Y"].max() > 1000.0  # a lit stop lamp: thousands of cd/m²
    lit = channels["Y"] > 0.1 * channels["Y"].max()
    assert channels["x"][lit].mean() > 0.6  # red chromaticity
    names = sorted(p.stem for p in passes.iterdir())
    assert names == sorted(expected.passes)
    bulb, attrs = photometric_images.read_photometric_exr(passes / "bulb.exr")
    assert sorted(bulb) == ["X", "Y", "Z"] and "cd/m2" in attrs[output.UNITS_ATTRIBUTE]


def test_false_colour_png_has_a_cd_m2_legend(tmp_path):
    said = _render_png(STOP, tmp_path / "fc.png", "--false-color", "--luminance-range", "10:100000")
    assert "false colour of luminance in cd/m2" in said
    image = _png(tmp_path / "fc.png")
    assert image.shape[0] == 64 and image.shape[1] > 64  # the legend beside the image
    assert imageio.read_attribute(tmp_path / "fc.png", "lamp:false_colour") == "log10 luminance 10 to 100000 cd/m2"


def test_photometric_options_refused_for_the_paper_mode(tmp_path):
    proc = run_cli("render", BASELINE, "-o", tmp_path / "x.png", *SIZE, "--ev100", "12")
    assert_bad_input(proc, "--ev100", "photometric")
    proc = run_cli("render", STOP, "-o", tmp_path / "x.png", *SIZE, "--luminance-range", "1:10")
    assert_bad_input(proc, "--luminance-range", "--false-color")
    proc = run_cli("render", STOP, "-o", tmp_path / "x.exr", *SIZE, "--false-color")
    assert_bad_input(proc, "--false-color", ".png")
    assert not (tmp_path / "x.exr").exists()
    proc = run_cli("render", STOP, "-o", tmp_path / "x.png", *SIZE, "--ev100", "40")
    assert proc.returncode == 2 and "[-20, 30]" in proc.stderr
    assert not (tmp_path / "x.png").exists()


def _cells(sheet_path) -> list[np.ndarray]:
    from core_tracer.study import sheet as study_sheet
    from core_tracer.study.definition import Study

    study = Study.load(str(sheet_path))
    image = _png(sheet_path)
    return [image[r.y:r.y + r.h, r.x:r.x + r.w] for r in study_sheet.layout(study).cells]


@pytest.mark.parametrize("exposure", [(), ("--ev100", "auto")], ids=["scene-ev100", "one-auto"])
def test_a_study_shows_the_brighter_filament_brighter(tmp_path, exposure):
    """One exposure for every cell (the scene's EV100, or one automatic one over all cells): the
    stop filament's cell is brighter than the tail filament's; with a worker process as in use."""
    out = tmp_path / "sheet.png"
    proc = run_cli("study", STOP, "--vary", "bulb.state=tail,stop", "--size", "64x64", "-o", out, "--workers", "1",
                   *exposure)
    assert proc.returncode == 0, proc.stderr
    assert re.search(r"Filmic at EV100 -?\d+\.\d for every cell", proc.stdout), proc.stdout  # the lamp view
    if not exposure:
        assert "EV100 15.0" in proc.stdout
    tail, stop = _cells(out)
    lit = stop.max(axis=-1) > 40
    assert stop[lit][:, 0].mean() > tail[lit][:, 0].mean() + 20
    assert stop[lit][:, 0].mean() > 2.0 * stop[lit][:, 1].mean()  # red


def test_a_photometric_study_sheet_exr_holds_xyz(tmp_path):
    out = tmp_path / "sheet.exr"
    proc = run_cli("study", STOP, "--vary", "bulb.state=tail,stop", "--size", "32x32", "-o", out, "--workers", "0")
    assert proc.returncode == 0, proc.stderr
    channels, attrs = photometric_images.read_photometric_exr(out)
    assert sorted(channels) == ["X", "Y", "Z"] and "cd/m2" in attrs[output.UNITS_ATTRIBUTE]
    assert channels["Y"].max() > 1000.0


def test_study_options_checked_before_any_render(tmp_path):
    proc = run_cli("study", BASELINE, "--vary", "lens.ior=1.4,1.5", "--size", "32x32", "-o", tmp_path / "s.png",
                   "--ev100", "12")
    assert_bad_input(proc, "--ev100", "photometric")
    proc = run_cli("study", STOP, "--vary", "light_model=paper,photometric", "--size", "32x32", "-o",
                   tmp_path / "s.exr")
    assert_bad_input(proc, "light_model", ".png")
    assert not any(tmp_path.iterdir())


def test_an_led_scene_says_its_own_bands_in_the_line_and_the_exr_header(tmp_path):
    """The LED stop lamp is traced on the bands it chooses (``raytrace.spectral_bands``): the printed line
    gives their number and widths, the EXR's ``lamp:bands`` their edges."""
    led = PRESETS / "led-stop-lamp.json"
    bands = spectral_bands.scene_bands(load_scene(led))
    proc = run_cli("render", led, "-o", tmp_path / "led.exr", "--width", "24", "--height", "24", "--samples", "1")
    assert proc.returncode == 0, proc.stderr
    assert f"on {bands.k} bands of 2.5 to 10 nm" in proc.stdout, proc.stdout
    header = photometric_images.read_photometric_exr(tmp_path / "led.exr")[1]
    assert np.allclose([float(e) for e in header[output.BANDS_ATTRIBUTE].split()], bands.edges_nm)
    assert bands.k > 40

"""A red photometric stop lamp shows red on every picture made for a person outside Blender (issue 31
item 1): the CLI's render and study sheet, a preset's thumbnail, the measure report's picture, and
``images.display.shown`` itself. Each goes through ``display.shown``; before it, a sheet that took
the XYZ in cd/m² for R, G, B showed the lamp gold (G/R about 0.7 on the lit lens).

The optimiser's sheet has its own test (tests/optimise/test_optimise_photometric.py), the Blender
paths theirs (tests/addon/test_addon_red_on_every_path.py). Metric: the medians of G/R and B/R over
the lit lens (``helpers.lit_lens_ratios``) below 0.5."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import STOP_LAMP, lit_lens_ratios, run_cli

from core_tracer import render
from core_tracer.images import display, imageio
from core_tracer.library import presets as P
from core_tracer.scene.validate import load_scene
from core_tracer.study import definition as st
from core_tracer.study import sheet as study_sheet

RED = 0.5  # G/R and B/R on a red lens stay below this; gold is about 0.7, white 1
SIZE = 48


def _png(path) -> np.ndarray:
    oiio = imageio.oiio_module()
    return np.asarray(oiio.ImageBuf(str(path)).get_pixels(oiio.FLOAT))[..., :3]


def _assert_red(shown: np.ndarray, where: str) -> None:
    g, b, pixels = lit_lens_ratios(shown)
    assert pixels > 20, where
    assert g < RED and b < RED, f"{where}: G/R {g:.2f}, B/R {b:.2f} on {pixels} lit pixels"


@pytest.fixture(scope="module")
def stop_lamp() -> dict:
    scene = load_scene(STOP_LAMP)
    scene["image"].update(width=SIZE, height=SIZE, samples=1)
    return scene


def test_the_one_function_shows_xyz_red_and_refuses_to_guess(stop_lamp):
    XYZ = render(stop_lamp, SIZE, SIZE)
    view = display.view_transform()
    _assert_red(display.shown(XYZ, stop_lamp, view=view).pixels[0], "display.shown")
    # the fault it removes: the same pixels taken for R, G, B
    g, _b, _n = lit_lens_ratios(view.to_display(XYZ, display.auto_exposure(XYZ)))
    assert g > 0.6
    with pytest.raises(ValueError, match="one scene per image"):
        display.shown([XYZ, XYZ], [stop_lamp], view=view)


def test_a_study_sheet_composed_from_the_variants_shows_red(stop_lamp):
    study = st.Study.build(stop_lamp, [{"parameter": "lens.ior", "values": [1.45, 1.6]}], (SIZE, SIZE), "")
    images = [render(v.scene, SIZE, SIZE) for v in study.variants]
    for view in (None, display.view_transform()):  # scene-linear (Blender's sheet) and display values (files)
        sheet, used = study_sheet.composed(study, images, exposure="auto", view=view, text="none")
        assert used.ev100 == stop_lamp["camera"]["ev100"] and used.paper_stops is None
        _assert_red(sheet, f"sheet through {view.view if view else 'Blender'}")


@pytest.mark.slow
def test_the_cli_render_and_study_sheet_show_red(tmp_path):
    size = ("--width", str(SIZE), "--height", str(SIZE), "--samples", "1")
    proc = run_cli("render", STOP_LAMP, "-o", tmp_path / "f.png", *size)
    assert proc.returncode == 0, proc.stderr
    _assert_red(_png(tmp_path / "f.png"), "render .png")
    proc = run_cli("study", STOP_LAMP, "--vary", "lens.ior=1.45,1.6", "--size", f"{SIZE}x{SIZE}", "-o",
                   tmp_path / "s.png", "--workers", "0")
    assert proc.returncode == 0, proc.stderr
    _assert_red(_png(tmp_path / "s.png"), "study sheet .png")


def test_a_thumbnail_shows_red(tmp_path, stop_lamp):
    lib = P.Library("mine", str(tmp_path / "lib"), writable=True)
    (tmp_path / "lib").mkdir()
    entry = P.save_preset(lib, "Stop", load_scene(STOP_LAMP))
    path = P.make_thumbnail(entry, tmp_path / "thumb.png", size=SIZE)
    _assert_red(_png(path), "thumbnail")
    assert imageio.read_attribute(path, "lamp:ev100") == f"{stop_lamp['camera']['ev100']:g}"


def test_the_measure_reports_picture_shows_red(stop_lamp):
    from core_tracer.measures import report

    _assert_red(report.lamp_picture(stop_lamp, width=SIZE), "report picture")

"""Measured curves beside the document (``filter_file``, ``spectrum_file``) from the command line:
``validate``, ``render``, ``states`` and ``study`` read them beside the design, whatever the working
directory, and refuse in one line a missing one or one its kind does not read (issue 32, item 4)."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest
from helpers import PRESETS, run_cli

from core_tracer.images import photometric as photometric_images
from core_tracer.images.imageio import read_attribute
from core_tracer.photometry import materials

pytestmark = pytest.mark.slow

STOP = PRESETS / "photometric-stop-lamp.json"


def red_curve(folder, name: str = "red.csv") -> None:
    """The project's red filter (at 3 mm) sampled at 1 nm: a measured curve of the same filter."""
    curve = materials.FILTERS["red"].spectrum()
    nm = np.arange(380.0, 781.0, 1.0)
    values = np.interp(nm, curve.wavelengths_nm, curve.values)
    (folder / name).write_text("nm,transmittance\n" + "".join(f"{a:g},{b:.8f}\n" for a, b in zip(nm, values,
                                                                                                 strict=True)))


def design(folder, **lens) -> str:
    doc = json.loads(STOP.read_text())
    doc["lamps"][0]["lens"].update(lens)
    path = folder / "stop.json"
    path.write_text(json.dumps(doc))
    return str(path)


def test_a_filter_file_beside_the_design_is_read_by_validate_render_and_states(tmp_path):
    folder = tmp_path / "design"
    folder.mkdir()
    red_curve(folder)
    measured = design(folder, filter="file", filter_file="red.csv")
    named = design(tmp_path, filter="red")
    done = run_cli("validate", measured)  # run from the repository's root: not the design's folder
    assert done.returncode == 0 and "valid" in done.stdout, done.stderr
    images = []
    for path, out in ((measured, tmp_path / "measured.exr"), (named, tmp_path / "named.exr")):
        done = run_cli("render", path, "-o", out, "--width", "40", "--height", "40", "--samples", "1")
        assert done.returncode == 0, done.stderr
        channels = photometric_images.read_photometric_exr(out)[0]
        images.append(np.stack([channels[c] for c in "XYZ"], axis=-1))
    lens = images[1][..., 1] > 0.05 * images[1][..., 1].max()
    assert lens.sum() > 50
    # the same filter: the measured curve's band means are the named filter's, sampled at 1 nm
    np.testing.assert_allclose(images[0][lens], images[1][lens], rtol=2e-3)
    recorded = json.loads(read_attribute(tmp_path / "measured.exr", "lamp:scene"))
    assert recorded["lamps"][0]["lens"]["filter_file"] == "red.csv"  # the file keeps the name, not a path
    done = run_cli("states", measured, "-o", tmp_path / "states.npz", "--width", "24", "--height", "24")
    assert done.returncode == 0 and "2 states" in done.stdout, done.stderr


def test_a_study_reads_the_curve_beside_its_base(tmp_path):
    folder = tmp_path / "design"
    folder.mkdir()
    red_curve(folder)
    measured = design(folder, filter="file", filter_file="red.csv")
    done = run_cli("study", measured, "--vary", "lens.filter_thickness=2,4", "--size", "24x24", "--workers", "0",
                   "-o", tmp_path / "sheet.exr")
    assert done.returncode == 0, done.stderr


@pytest.mark.parametrize("lens, field, words", [
    ({"filter": "file", "filter_file": "absent.csv"}, "lamps[0].lens.filter_file", '"absent.csv" is missing'),
    ({"filter": "red", "filter_file": "red.csv"}, "lamps[0].lens.filter_file", 'while filter is "red"'),
])
def test_a_curve_that_is_not_there_or_not_read_is_one_line_from_validate(tmp_path, lens, field, words):
    red_curve(tmp_path)
    done = run_cli("validate", design(tmp_path, **lens))
    assert done.returncode == 2
    line = done.stderr.strip()
    assert "\n" not in line and field in line and words in line, line


def test_a_spectrum_file_with_a_named_bulb_is_refused(tmp_path):
    doc = json.loads(STOP.read_text())
    doc["lamps"][0]["bulb"]["spectrum_file"] = "led.csv"  # a P21/5W's spectrum is its type's
    path = tmp_path / "stop.json"
    path.write_text(json.dumps(doc))
    done = run_cli("validate", path)
    assert done.returncode == 2 and "lamps[0].bulb.spectrum_file" in done.stderr and 'type is "P21/5W"' in done.stderr


def test_the_photometric_free_form_twin_renders_and_is_relit_from_the_command_line(tmp_path):
    for suffix in (".json", ".glb"):
        shutil.copy(PRESETS / f"freeform-sculpted-wrap-lamp{suffix}", tmp_path / f"freeform-sculpted-wrap-lamp{suffix}")
    twin = tmp_path / "twin.json"
    shutil.copy(PRESETS / "freeform-sculpted-wrap-lamp-photometric.json", twin)
    done = run_cli("render", twin, "-o", tmp_path / "twin.exr", "--width", "48", "--height", "40")
    assert done.returncode == 0 and "on 40 bands" in done.stdout, done.stderr
    channels = photometric_images.read_photometric_exr(tmp_path / "twin.exr")[0]
    lit = channels["Y"] > 0.1 * channels["Y"].max()
    assert lit.sum() > 20 and channels["x"][lit].mean() > 0.6  # a red lamp
    done = run_cli("states", twin, "-o", tmp_path / "twin.npz", "--width", "24", "--height", "20")
    assert done.returncode == 0 and "freeform.parts[0].tail" in done.stdout, done.stderr

"""The standalone CLI, run as users run it: ``python -m core_tracer`` in a subprocess."""

from __future__ import annotations

import copy
import json
import os
import signal

import numpy as np
import pytest
from helpers import BASELINE, assert_bad_input, baseline_doc, run_cli, signal_and_wait, start_cli_at

from core_tracer import PASS_NAMES, render
from core_tracer.images import imageio
from core_tracer.scene import reading
from core_tracer.scene.reading import SceneError
from core_tracer.scene.validate import load_scene

pytestmark = pytest.mark.slow

# ---------------------------------------------------------------------------------------------
# Bad scenes: every case gives exit 2, one line naming the field, the value and the range, and
# writes nothing.


def _lamp(center):
    lamp = copy.deepcopy(baseline_doc()["lamps"][0])
    lamp["center"] = center
    return lamp


def _edit(fn):
    def make():
        doc = baseline_doc()
        fn(doc)
        return json.dumps(doc)
    return make


BAD_SCENES = {
    "not-json": (lambda: '{"schema": "lamp-scene/1", "lamps": [', ("not valid JSON", "line 1")),
    "not-utf8": (lambda: b'{"name": "\xff\xfe"}', ("not UTF-8",)),
    "wrong-schema": (_edit(lambda d: d.update(schema="lamp-scene/3")),
                     ("schema", '"lamp-scene/3"', '"lamp-scene/2"', '"lamp-scene/1"')),
    "no-schema": (_edit(lambda d: d.pop("schema")), ("schema", '"lamp-scene/2"')),
    "unknown-key": (_edit(lambda d: d["lamps"][0]["lens"].update(colour=[1, 0, 0])),
                    ("lamps[0].lens.colour", "unknown key", "transmitted_color")),
    "nan": (lambda: BASELINE.read_text().replace('"ior": 1.49', '"ior": NaN'), ("lamps[0].lens.ior", "NaN", "[1, 3]")),
    "infinity": (lambda: BASELINE.read_text().replace('"ior": 1.49', '"ior": 1e999'),
                 ("lamps[0].lens.ior", "1e999 is out of range", "[1, 3]")),
    "negative-radius": (_edit(lambda d: d["lamps"][0]["lens"].update(radius=-3)),
                        ("lamps[0].lens.radius", "-3", "(0, 1000] mm")),
    "zero-body-size": (_edit(lambda d: d["body"].update(size=[0, 120])),
                       ("body.size[0]", "0 is out of range", "(0, 10000] mm")),
    "zero-thickness": (_edit(lambda d: d["lamps"][0]["lens"].update(thickness=0)),
                       ("lamps[0].lens.thickness", "0", "(0, 100] mm")),
    "negative-thickness": (_edit(lambda d: d["lamps"][0]["lens"].update(thickness=-2)),
                           ("lamps[0].lens.thickness", "-2 is out of range", "(0, 100] mm")),
    "ior-below-1": (_edit(lambda d: d["lamps"][0]["lens"].update(ior=0.9)),
                    ("lamps[0].lens.ior", "0.9", "[1, 3]")),
    "five-lamps": (_edit(lambda d: d.update(lamps=[_lamp([0, 0]) for _ in range(5)])),
                   ("lamps", "5 items", "1 to 4")),
    "overlapping-lenses": (_edit(lambda d: (d["body"].update(size=[300, 120]),
                                            d.update(lamps=[_lamp([-30, 0]), _lamp([30, 0])]))),
                           ("lamps[1].center", "overlaps the lens of lamps[0]", "at least 90 mm")),
    "lens-outside-body": (_edit(lambda d: d["lamps"][0].update(center=[80, 0])),
                          ("lamps[0].center", "[80.0, 0.0]", "outside the body", "[-65, 65]")),
    "cuts-larger-than-lens": (_edit(lambda d: d["lamps"][0]["cuts"].update(pitch=100)),
                              ("lamps[0].cuts.pitch", "100", "[0.09, 90] mm")),
    "bulb-too-big": (_edit(lambda d: d["lamps"][0]["bulb"].update(radius=30)),
                     ("lamps[0].bulb.radius", "30", "(0, 14.06] mm")),
    "bulb-off-axis-outside-reflector": (_edit(lambda d: d["lamps"][0]["bulb"].update(offset=[40, 0, 0])),
                                        ("lamps[0].bulb.offset", "outside the reflector", "up to 18.65 mm")),
    "image-100000-px": (_edit(lambda d: d["image"].update(width=100000)),
                        ("image.width", "100000", "[1, 8192] px")),
    "lamps-not-a-list": (_edit(lambda d: d.update(lamps={"center": [0, 0]})), ("lamps", "expected a list")),
    "light-direction-too-short": (_edit(lambda d: d["light"].update(direction=[1e-170, 0, 0])),
                                  ("light.direction", "too short", "length at least 1e-09")),
    "camera-up-too-short": (_edit(lambda d: d["camera"].update(up=[0, 0, 1e-300])),
                            ("camera.up", "too short", "length at least 1e-09")),
    "camera-on-its-target": (_edit(lambda d: d["camera"].update(position=[0, -1e-200, 0], target=[0, 0, 0])),
                             ("camera.target", "1e-200 mm from camera.position", "at least 1e-06 mm")),
    "cuts-too-fine": (_edit(lambda d: d["lamps"][0]["cuts"].update(pitch=1e-15)),
                      ("lamps[0].cuts.pitch", "1e-15 is too fine", "[0.09, 90] mm")),
    "prism-plate-focus-too-near": (_edit(lambda d: d["lamps"][0].update(collection="prism_plate",
                                                                        prism_plate={"focal_length": 20})),
                                   ("lamps[0].prism_plate.focal_length", "20 is too short", "[49.09, 1000] mm")),
    "prism-plate-housing-too-deep": (_edit(lambda d: d["lamps"][0].update(collection="prism_plate",
                                                                          prism_plate={"housing_depth": 90})),
                                     ("lamps[0].prism_plate.housing_depth", "90", "(0, 69.5] mm")),
    "unknown-collection": (_edit(lambda d: d["lamps"][0].update(collection="lightguide")),
                           ("lamps[0].collection", "lightguide", '"reflector", "prism_plate"')),
}


CASES = [(case, "render") for case in sorted(BAD_SCENES)]
CASES += [(case, "validate") for case in ("not-json", "unknown-key", "five-lamps", "bulb-too-big")]


@pytest.mark.parametrize("case,command", CASES)
def test_bad_scene_exits_2_with_one_line(tmp_path, case, command):
    make, needles = BAD_SCENES[case]
    content = make()
    src = tmp_path / "scene.json"
    src.write_bytes(content if isinstance(content, bytes) else content.encode())
    out = tmp_path / "out.exr"
    extra = ["-o", out, "--passes", tmp_path / "passes"] if command == "render" else []
    proc = run_cli(command, src, *extra)
    line = assert_bad_input(proc, "scene.json", *needles)
    assert line.startswith("error: ")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scene.json"]


def test_unreadable_file(tmp_path):
    missing = tmp_path / "missing.json"
    assert_bad_input(run_cli("render", missing, "-o", tmp_path / "o.exr"), "missing.json", "cannot read")
    assert list(tmp_path.iterdir()) == []


def test_a_folder_is_not_a_scene(tmp_path):
    (tmp_path / "dir.json").mkdir()
    assert_bad_input(run_cli("validate", tmp_path / "dir.json"), "dir.json", "not a regular file")


def test_a_pipe_is_refused_not_waited_on(tmp_path):
    os.mkfifo(tmp_path / "pipe.json")
    assert_bad_input(run_cli("validate", tmp_path / "pipe.json", timeout=20), "pipe.json", "not a regular file")


def test_integer_beyond_json_limits(tmp_path):
    src = tmp_path / "scene.json"
    src.write_text(BASELINE.read_text().replace('"ior": 1.49', '"ior": ' + "9" * 5000))
    assert_bad_input(run_cli("render", src, "-o", tmp_path / "o.exr"), "scene.json: lamps[0].lens.ior: ",
                     "a number of 5000 digits is out of range; allowed [1, 3]")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scene.json"]


def test_oversized_file_is_refused_before_reading(tmp_path, monkeypatch):
    big = tmp_path / "big.json"
    with open(big, "wb") as f:
        f.truncate(100 * 1024 * 1024)  # sparse: costs no disk
    assert_bad_input(run_cli("validate", big), "big.json", "104857600 bytes", "at most 1000000 bytes")
    opened = []
    monkeypatch.setattr(reading, "open", lambda *a, **kw: opened.append(a) or open(*a, **kw), raising=False)
    with pytest.raises(SceneError, match="104857600 bytes; allowed at most 1000000 bytes"):
        reading.read_json(big)
    assert opened == []  # refused by its size, never opened


@pytest.mark.parametrize("option,value", [("--width", "100000"), ("--height", "0"), ("--width", "-5")])
def test_absurd_image_size_option(tmp_path, option, value):
    out = tmp_path / "out.png"
    assert_bad_input(run_cli("render", BASELINE, "-o", out, option, value), option, value, "[1, 8192] px")
    assert list(tmp_path.iterdir()) == []


def test_image_size_option_not_a_number(tmp_path):
    assert_bad_input(run_cli("render", BASELINE, "-o", tmp_path / "o.png", "--width", "wide"),
                     "--width", "'wide'")


@pytest.mark.parametrize("name", ["out.jpg", "out"])
def test_unsupported_output_format(tmp_path, name):
    out = tmp_path / name
    assert_bad_input(run_cli("render", BASELINE, "-o", out), name, ".exr, .png")
    assert list(tmp_path.iterdir()) == []


def test_output_folder_missing(tmp_path):
    out = tmp_path / "nowhere" / "out.exr"
    assert_bad_input(run_cli("render", BASELINE, "-o", out), "out.exr", "does not exist")
    assert list(tmp_path.iterdir()) == []


def test_usage_errors_are_one_line():
    assert_bad_input(run_cli("render"), "required")
    assert_bad_input(run_cli("frobnicate"), "invalid choice")


# ---------------------------------------------------------------------------------------------
# Good input


def test_validate_ok():
    proc = run_cli("validate", BASELINE)
    assert proc.returncode == 0, proc.stderr
    assert "valid lamp-scene/2" in proc.stdout and "Round red tail lamp" in proc.stdout


def test_validate_reports_photometric_fields_a_paper_design_ignores(tmp_path):
    """Issue 31: reported in one line on stderr, not refused (exit 0)."""
    doc = baseline_doc()
    doc["lamps"][0]["bulb"]["flux_lm"] = 900
    path = tmp_path / "paper.json"
    path.write_text(json.dumps(doc))
    proc = run_cli("validate", path)
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr.splitlines() == [
        f"note: {path}: the paper light model ignores photometric fields: lamps[0].bulb.flux_lm = 900.0; "
        'they take effect with light_model "photometric"']
    assert run_cli("validate", BASELINE).stderr == ""


def test_render_exr_with_passes(tmp_path):
    out = tmp_path / "out.exr"
    passes = tmp_path / "passes"
    proc = run_cli("render", BASELINE, "-o", out, "--width", "40", "--height", "24", "--passes", passes)
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == ""
    summary = proc.stdout.strip()
    assert "40x24 px" in summary and " s" in summary and "segments" in summary
    image, sc = imageio.read_image(out)
    assert image.shape == (24, 40, 3)
    assert np.isfinite(image).all() and (image >= 0).all() and image.max() > 0
    assert sc["image"] == {"width": 40, "height": 24, "samples": 1, "edge_samples": 0}
    expected = load_scene(BASELINE)
    expected["image"] = {"width": 40, "height": 24}
    assert sc["lamps"] == expected["lamps"] and sc["body"] == expected["body"]
    assert sorted(p.name for p in passes.iterdir()) == sorted(f"{n}.exr" for n in PASS_NAMES)
    total = sum(imageio.read_image(passes / f"{n}.exr")[0] for n in PASS_NAMES)
    assert np.allclose(total, image, rtol=1e-5, atol=1e-6)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.exr", "passes"]


def test_render_png(tmp_path):
    out = tmp_path / "out.png"
    proc = run_cli("render", BASELINE, "-o", out, "--width", "32", "--height", "32")
    assert proc.returncode == 0, proc.stderr
    image, sc = imageio.read_image(out)
    assert image.shape == (32, 32, 3) and sc is not None


def test_ctrl_c_exits_130_without_a_file(tmp_path):
    out = tmp_path / "lamp.exr"
    # The signal lands after the first band of the image is traced, in the middle of the render.
    proc = start_cli_at("render:band", tmp_path.parent / f"{tmp_path.name}-band", "render", BASELINE, "-o", out,
                        "--width", "96", "--height", "400")
    _, err = signal_and_wait(proc, signal.SIGINT)
    assert proc.returncode == 130, err
    assert "Traceback" not in err and err.strip() == "interrupted"
    assert list(tmp_path.iterdir()) == []


def test_exposure_out_of_range_is_refused_before_rendering(tmp_path):
    out = tmp_path / "o.png"
    assert_bad_input(run_cli("render", BASELINE, "-o", out, "--exposure", "40"), "--exposure", "auto or [-16, 16]")
    assert not out.exists()


def test_exposure_darkens_the_png(tmp_path):
    normal, darker = tmp_path / "n.png", tmp_path / "d.png"
    size = ("--width", "32", "--height", "32", "--view", "Standard")
    assert run_cli("render", BASELINE, "-o", normal, *size, "--exposure", "0").returncode == 0
    assert run_cli("render", BASELINE, "-o", darker, *size, "--exposure", "-2").returncode == 0
    from core_tracer.images.imageio import read_image

    a, _ = read_image(normal)  # read_image undoes the exposure
    b, _ = read_image(darker)
    assert np.all(a <= 1.0) and b.max() > 1.0  # the darker PNG kept the highlights the plain one clipped


def test_render_samples_override_the_scene(tmp_path):
    out = tmp_path / "out.exr"
    proc = run_cli("render", BASELINE, "-o", out, "--width", "24", "--height", "16", "--samples", "4")
    assert proc.returncode == 0, proc.stderr
    assert "24x16 px at 4 samples" in proc.stdout
    image, sc = imageio.read_image(out)
    assert sc["image"] == {"width": 24, "height": 16, "samples": 4, "edge_samples": 0}
    scene = load_scene(BASELINE)
    scene["image"].update(width=24, height=16, samples=4)
    np.testing.assert_array_equal(image, render(scene))


@pytest.mark.parametrize("value", ["0", "257"])
def test_render_refuses_bad_samples(tmp_path, value):
    proc = run_cli("render", BASELINE, "-o", tmp_path / "out.exr", "--samples", value)
    assert_bad_input(proc, "--samples", "[1, 256]")
    assert not (tmp_path / "out.exr").exists()


def test_render_refuses_too_many_eye_rays(tmp_path):
    proc = run_cli("render", BASELINE, "-o", tmp_path / "out.exr", "--width", "4096", "--height", "4096",
                   "--samples", "256")
    assert_bad_input(proc, "image.samples", "1 to 64 samples")
    assert not (tmp_path / "out.exr").exists()

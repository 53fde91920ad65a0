"""Studies vary the choices of a design by name: lamp types side by side on one sheet (cut type,
outline, lens shape, collection, a lamp's function, the camera's projection, the surroundings)."""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest
from helpers import BASELINE, PRESETS, baseline_doc, run_cli

from core_tracer import parse_scene, render
from core_tracer.cli import main as cli
from core_tracer.scene import functions
from core_tracer.scene import spec as S
from core_tracer.scene.reading import SceneError
from core_tracer.study import definition as st
from core_tracer.study import run as study_run
from core_tracer.study import sheet as study_sheet
from core_tracer.study.parameters import resolve_parameter, study_parameters

WRAP = PRESETS / "wrap-around-combination.json"  # its third lamp has a cylindrical lens


def _types_by_collection(size=(64, 48)) -> st.Study:
    return st.Study.build(baseline_doc(), [st.parse_vary("cuts.type=fisheye, sawtooth, flutes"),
                                           st.parse_vary("collection=reflector,prism_plate")], size)


def test_every_choice_of_the_scene_is_a_study_parameter():
    choices = {info.path.removeprefix("lamps[].") for info in S.iter_fields()
               if isinstance(info.spec, S.Choice) and info.path != "schema"}
    # a free-form part's choices under its role (its role itself is the design's geometry)
    choices |= {info.path for info in S.iter_fields(S.FREEFORM_PART, "freeform.parts[].")
                if isinstance(info.spec, S.Choice) and info.path != "freeform.parts[].role"}
    offered = {name for name in study_parameters() if isinstance(resolve_parameter(name).spec, S.Choice)}
    assert offered == choices
    assert {"cuts.type", "lens.outline", "lens.shape", "lens.wrap_toward", "collection", "function",
            "environment.world", "camera.type"} <= offered
    assert "schema" not in study_parameters()


@pytest.mark.slow
def test_cut_type_by_collection_renders_six_different_lamps():
    s = _types_by_collection()
    assert (s.columns, s.rows) == (3, 2)
    kinds = [(v.scene["lamps"][0]["cuts"]["type"], v.scene["lamps"][0]["collection"]) for v in s.variants]
    assert kinds == [(c, k) for k in ("reflector", "prism_plate") for c in ("fisheye", "sawtooth", "flutes")]
    images = study_run.run_study(s, workers=2)
    assert np.array_equal(images[4], render(s.variants[4].scene, 64, 48))  # the type reaches the tracer
    # Every pair of cells differs: mean absolute difference at least 5 % of their mean (measured 13 to 87 %).
    for a, b in itertools.combinations(range(len(images)), 2):
        difference = np.abs(images[a] - images[b]).mean() / (0.5 * (images[a].mean() + images[b].mean()))
        assert difference > 0.05, (s.variants[a].label(s), s.variants[b].label(s), difference)
    # The sheet's labels show the names.
    lay = study_sheet.layout(s)
    assert [b.text for b in lay.texts if b.kind == "column"] == ["cuts.type=fisheye", "cuts.type=sawtooth",
                                                                  "cuts.type=flutes"]
    assert [b.text for b in lay.texts if b.kind == "row"] == ["collection=reflector", "collection=prism_plate"]
    assert s.variants[5].label(s) == "cuts.type=flutes  collection=prism_plate"


@pytest.mark.parametrize(("base", "axes", "needles"), [
    (WRAP, ["cuts.type=fisheye,sawtooth"],
     ("lamps[2].cuts.type", '"sawtooth" cuts are not made on a cylindrical lens', 'allowed "fisheye"',
      "cuts.type=sawtooth")),
    (BASELINE, ["collection=reflector,prism_plate", "lens.outline=round,rectangular"],
     ("lamps[0].lens.outline", "a prism plate sits behind a round lens", 'allowed "round"',
      "collection=prism_plate, lens.outline=rectangular")),
    (BASELINE, ["cuts.type=fisheye,pillow"], ("cuts.type", '"pillow" is not allowed', '"sawtooth", "flutes"')),
    (BASELINE, ["lens.outline=round:rectangular:2"], ("lens.outline", "is a name; give values", '"rectangular"')),
    (BASELINE, ["function=tail,stop", "lens.transmitted_color=0.9/0.1/0.1"],
     ("lens.transmitted_color", "sets what function sets")),
    (BASELINE, ["lamps[0].bulb.intensity=8/7/6", "function=tail,stop"], ("function", "sets what")),
])
def test_a_refused_combination_is_named_before_anything_renders(base, axes, needles):
    with pytest.raises(SceneError) as info:
        st.Study.build(parse_scene(json.loads(base.read_text())), [st.parse_vary(a) for a in axes], (32, 24))
    message = str(info.value)
    assert "\n" not in message
    for needle in needles:
        assert needle in message, (needle, message)


def test_cli_refuses_a_refused_combination_with_one_line_and_no_worker(tmp_path, capsys):
    started = study_run.workers_started
    args = ["study", str(WRAP), "--vary", "lamps[2].cuts.type=fisheye,flutes", "--size", "32x24",
            "-o", str(tmp_path / "sheet.png")]
    assert cli.main(args) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: lamps[2].cuts.type: ") and "\n" not in err
    assert "lamps[2].cuts.type=flutes" in err
    assert study_run.workers_started == started and list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_cli_studies_lamp_types_and_the_sheet_carries_them(tmp_path):
    sheet = tmp_path / "types.png"
    proc = run_cli("study", BASELINE, "--vary", "cuts.type=fisheye,sawtooth,flutes", "--vary",
                   "lens.outline=round,rectangular", "--size", "32x24", "--workers", "0", "-o", sheet)
    assert proc.returncode == 0, proc.stderr
    again = st.Study.load(sheet)
    assert [a.values for a in again.axes] == [("fisheye", "sawtooth", "flutes"), ("round", "rectangular")]
    assert again.variants[4].scene["lamps"][0]["lens"]["outline"] == "rectangular"
    listed = run_cli("study", "--list").stdout.split()
    assert {"cuts.type", "collection", "lens.outline", "lens.shape"} <= set(listed)


def test_a_lamp_function_sets_its_lens_colour_and_bulb_as_in_blender():
    s = st.Study.build(baseline_doc(), [st.parse_vary("lamps[0].function=tail,stop,turn")], (32, 24))
    for v, name in zip(s.variants, ("tail", "stop", "turn"), strict=True):
        lamp = v.scene["lamps"][0]
        look, intensity = functions.DEFAULTS[name]
        assert lamp["function"] == name and lamp["bulb"]["intensity"] == intensity
        assert lamp["lens"]["transmitted_color"] == look.fields["transmitted_color"]
        assert "absorption" not in lamp["lens"]
    assert s.variants[2].label(s) == "function=turn"


def test_choice_axes_round_trip_and_apply_to_one_lamp():
    doc = parse_scene(json.loads((PRESETS / "four-lamp-rear-combination.json").read_text()))
    s = st.Study.build(doc, [st.parse_vary("lamps[1].cuts.type=sawtooth,flutes"),
                             st.parse_vary("camera.type=perspective,orthographic")], (32, 24))
    assert [lamp["cuts"]["type"] for lamp in s.variants[1].scene["lamps"]] == \
        [doc["lamps"][0]["cuts"]["type"], "flutes", *(lamp["cuts"]["type"] for lamp in doc["lamps"][2:])]
    assert s.variants[3].scene["camera"]["type"] == "orthographic"
    again = st.Study.from_json(s.to_json())
    assert [v.scene for v in again.variants] == [v.scene for v in s.variants]
    assert resolve_parameter("lamps[1].cuts.type").short == "cuts.type"


@pytest.mark.parametrize("function_first", [True, False])
def test_a_function_goes_first_so_a_thicker_lens_still_looks_deeper(function_first):
    axes = [st.parse_vary("function=stop"), st.parse_vary("lens.thickness=3,6")]
    s = st.Study.build(baseline_doc(), axes if function_first else axes[::-1], (32, 24))
    lenses = [v.scene["lamps"][0]["lens"] for v in s.variants]
    assert {lens["reference_thickness"] for lens in lenses} == {baseline_doc()["lamps"][0]["lens"]["thickness"]}
    assert sorted(lens["thickness"] for lens in lenses) == [3, 6]

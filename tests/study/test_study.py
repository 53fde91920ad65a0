"""Design studies: definitions, parallel rendering, cancel, contact sheets, the CLI."""

from __future__ import annotations

import json
import os
import signal
import time
from pathlib import Path

import numpy as np
import OpenImageIO as oiio
import pytest
from helpers import BASELINE, FOUR_LAMPS, baseline_doc, child_pids, process_gone, run_cli, signal_and_wait, start_cli_at

from core_tracer import render
from core_tracer.cli import main as cli
from core_tracer.images import display
from core_tracer.scene.derived import lens_absorption
from core_tracer.scene.reading import SceneError, read_json
from core_tracer.scene.validate import load_scene, parse_scene
from core_tracer.study import definition as st
from core_tracer.study import run as study_run
from core_tracer.study import sheet as study_sheet
from core_tracer.study.parameters import study_parameters

SIZE = (32, 32)




def two_by_two(size=SIZE) -> st.Study:
    return st.Study.build(baseline_doc(), [{"parameter": "lens.ior", "values": [1.45, 1.6]},
                                       {"parameter": "cuts.height", "range": [0.5, 2.0], "steps": 2}], size)




def test_variants_are_row_major_with_the_edited_values():
    s = st.Study.build(baseline_doc(), [st.parse_vary("lens.ior=1.45:1.60:4"), st.parse_vary("cuts.height=0.5,1,2")])
    assert (s.columns, s.rows, len(s)) == (4, 3, 12)
    assert s.axes[0].values == (1.45, 1.5, 1.55, 1.6)  # tidy decimals, not 1.4999999999999998
    for v in s.variants:
        assert v.index == v.row * 4 + v.column
        assert v.values == (s.axes[0].values[v.column], s.axes[1].values[v.row])
        lamp = v.scene["lamps"][0]
        assert (lamp["lens"]["ior"], lamp["cuts"]["height"]) == v.values
    # The base is the design at the study's size, and everything else in a variant equals the base.
    assert s.base == parse_scene({**baseline_doc(), "image": {"width": 256, "height": 256}})
    other = s.variants[5].scene
    assert other["body"] == s.base["body"] and other["camera"] == s.base["camera"]


def test_lamp_index_edits_one_lamp_and_no_index_edits_all():
    base = read_json(FOUR_LAMPS)
    one = st.Study.build(base, [st.parse_vary("lamps[2].lens.ior=1.6")])
    every = st.Study.build(base, [st.parse_vary("lens.ior=1.6")])
    iors = [lamp["lens"]["ior"] for lamp in one.variants[0].scene["lamps"]]
    assert iors[2] == 1.6 and iors[:2] + iors[3:] == [lamp["lens"]["ior"] for i, lamp
                                                     in enumerate(one.base["lamps"]) if i != 2]
    assert all(lamp["lens"]["ior"] == 1.6 for lamp in every.variants[0].scene["lamps"])
    # lamps[] (no index) is the same as the lamp-relative name
    assert st.Study.build(base, [st.parse_vary("lamps[].lens.ior=1.6")]).variants[0].scene == every.variants[0].scene


def test_lens_colour_replaces_absorption():
    s = st.Study.build(baseline_doc(), [st.parse_vary("lens.transmitted_color=0.9/0.1/0.1,0.9/0.5/0.05")])
    lens = s.variants[1].scene["lamps"][0]["lens"]
    assert "absorption" not in lens
    assert lens["transmitted_color"] == [0.9, 0.5, 0.05]
    assert lens["reference_thickness"] == lens["thickness"]
    assert lens_absorption(lens) == pytest.approx([-np.log(c) / 3.0 for c in (0.9, 0.5, 0.05)])
    # One component: the others keep the colour the base's absorption gives through its thickness.
    s = st.Study.build(baseline_doc(), [st.parse_vary("lens.transmitted_color[1]=0.2,0.4")])
    base_a = s.base["lamps"][0]["lens"]["absorption"]
    lens = s.variants[0].scene["lamps"][0]["lens"]
    assert lens["transmitted_color"][1] == 0.2
    assert lens["transmitted_color"][0] == pytest.approx(np.exp(-base_a[0] * 3.0))
    # And back: varying absorption drops a transmitted colour.
    tc = st.Study.build(baseline_doc(), [st.parse_vary("lens.transmitted_color=0.9/0.1/0.1")]).variants[0].scene
    back = st.Study.build(tc, [st.parse_vary("lens.absorption=0.1/1/1")]).variants[0].scene["lamps"][0]["lens"]
    assert back["absorption"] == [0.1, 1.0, 1.0] and "transmitted_color" not in back


def test_a_default_camera_frames_the_body_at_the_study_size():
    doc = baseline_doc()
    del doc["camera"]
    wide = st.Study.build(doc, [st.parse_vary("lens.ior=1.5")], (96, 32))
    expected = parse_scene({**doc, "image": {"width": 96, "height": 32}})
    assert wide.base["camera"] == expected["camera"] != parse_scene(doc)["camera"]
    assert wide.variants[0].scene["image"] == {"width": 96, "height": 32, "samples": 1, "edge_samples": 0}


def test_two_axes_on_one_field_differ_by_lamp_or_component():
    base = read_json(FOUR_LAMPS)
    s = st.Study.build(base, [st.parse_vary("lamps[0].lens.ior=1.5,1.6"), st.parse_vary("lamps[1].lens.ior=1.4,1.7")])
    assert [[lamp["lens"]["ior"] for lamp in v.scene["lamps"][:2]] for v in s.variants] == [
        [1.5, 1.4], [1.6, 1.4], [1.5, 1.7], [1.6, 1.7]]
    s = st.Study.build(baseline_doc(), [st.parse_vary("body.color[0]=0.2,0.8"), st.parse_vary("body.color[2]=0.1,0.9")])
    assert s.variants[3].scene["body"]["color"] == [0.8, s.base["body"]["color"][1], 0.9]
    # A transmitted colour against its reference thickness is a real study (not one field twice).
    colour = st.Study.build(baseline_doc(), [st.parse_vary("lens.transmitted_color=0.9/0.1/0.1")]).variants[0].scene
    s = st.Study.build(colour, [st.parse_vary("lens.transmitted_color=0.9/0.1/0.1,0.9/0.5/0.05"),
                                st.parse_vary("lens.reference_thickness=1.5,3")])
    assert s.variants[3].scene["lamps"][0]["lens"]["reference_thickness"] == 3.0


def test_vector_range_and_flag_values():
    s = st.Study.build(baseline_doc(), [st.parse_vary("bulb.intensity=2/2/2:8/6/4:3"), st.parse_vary("bulb.on=on,off")])
    assert s.axes[0].values == ([2.0, 2.0, 2.0], [5.0, 4.0, 3.0], [8.0, 6.0, 4.0])
    assert [v.scene["lamps"][0]["bulb"]["on"] for v in s.variants] == [True] * 3 + [False] * 3


def test_study_json_round_trip(tmp_path):
    s = two_by_two()
    path = tmp_path / "study.json"
    s.save(path)
    doc = json.loads(path.read_text())
    assert doc["schema"] == "lamp-study/1" and doc["size"] == [32, 32]
    assert doc["axes"][1] == {"parameter": "cuts.height", "range": [0.5, 2.0], "steps": 2}
    assert doc["base"]["schema"] == "lamp-scene/2"  # embedded: the study travels alone
    again = st.Study.load(path)
    assert again.to_json() == s.to_json()
    assert [v.scene for v in again.variants] == [v.scene for v in s.variants]


def test_variants_saved_as_presets(tmp_path):
    s = two_by_two()
    paths = s.save_variants(tmp_path / "variants")
    assert [Path(p).name for p in paths] == [f"variant-0{i}.json" for i in range(4)]
    for v, path in zip(s.variants, paths, strict=True):
        loaded = load_scene(path)
        assert loaded["name"] == s.variant_name(v.index)
        assert "lens.ior=" in loaded["name"] and "cuts.height=" in loaded["name"]
        assert {**loaded, "name": v.scene["name"]} == v.scene
    assert sorted(p.name for p in (tmp_path / "variants").iterdir()) == [f"variant-0{i}.json" for i in range(4)]


BAD_STUDIES = {
    "unknown parameter": ([{"parameter": "lens.colour", "values": [1]}], ("lens.colour", "unknown parameter")),
    "not a study field": ([{"parameter": "image.width", "values": [64]}], ("image.width", "unknown parameter")),
    "value out of range": ([{"parameter": "lens.ior", "values": [1.5, 3.5]}], ("lens.ior", "3.5", "[1, 3]")),
    "range end out of range": ([{"parameter": "body.specular", "range": [0, 2], "steps": 3}],
                               ("body.specular", "2", "[0, 1]")),
    "colour out of range": ([{"parameter": "lens.transmitted_color", "values": [[0.9, 0, 0.1]]}],
                            ("lens.transmitted_color", "0", "(0, 1]")),
    "steps 1 of a range": ([{"parameter": "lens.ior", "range": [1.4, 1.6], "steps": 1}],
                           ("lens.ior", "steps 1", "2 to 64")),
    "steps 0": ([{"parameter": "lens.ior", "range": [1.4, 1.6], "steps": 0}], ("lens.ior", "steps 0", "1 to 64")),
    "more than 64 variants": ([{"parameter": "lens.ior", "range": [1.4, 1.6], "steps": 9},
                               {"parameter": "cuts.height", "range": [0.5, 2], "steps": 8}],
                              ("9 x 8 = 72 variants", "at most 64")),
    "65 values": ([{"parameter": "lens.ior", "values": [1.5] * 65}], ("lens.ior", "65 values", "at most 64")),
    "no such lamp": ([{"parameter": "lamps[1].lens.ior", "values": [1.5]}], ("lamps[1].lens.ior", "index 1")),
    "no such component": ([{"parameter": "bulb.offset[3]", "values": [1]}], ("bulb.offset[3]", "0 to 2")),
    "same parameter twice": ([{"parameter": "lens.ior", "values": [1.5]}, {"parameter": "lamps[0].lens.ior",
                                                                           "values": [1.6]}], ("same field",)),
    "absorption against colour": ([{"parameter": "lens.absorption", "values": [[0.1, 1, 1]]},
                                   {"parameter": "lens.transmitted_color", "values": [[0.9, 0.1, 0.1]]}],
                                  ("lens.transmitted_color", "lens colour")),
    "breaks the geometry": ([{"parameter": "cuts.height", "values": [1, 7]}],
                            ("lamps[0].cuts.height", "7", "pitch 9", "cuts.height=7")),
    "three axes": ([{"parameter": "lens.ior", "values": [1.5]}] * 3, ("axes", "1 or 2")),
}


@pytest.mark.parametrize("case", sorted(BAD_STUDIES))
def test_bad_study_is_refused_when_built(case):
    axes, needles = BAD_STUDIES[case]
    with pytest.raises(SceneError) as info:
        st.Study.build(baseline_doc(), axes, SIZE)
    for needle in needles:
        assert needle in str(info.value), (needle, str(info.value))
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("vary,needles", [
    (["lens.colour=1,2"], ("lens.colour", "unknown parameter")),
    (["lens.ior=1.45,3.5"], ("lens.ior", "3.5", "[1, 3]")),
    (["lens.ior=1.4:1.6:0"], ("steps 0",)),
    (["lens.ior=1.4:1.6:9", "cuts.height=0.5:2:8"], ("72 variants", "at most 64")),
    (["lens.ior=1.4:x:3"], ("lens.ior", "'x' is not a number")),
])
def test_cli_refuses_a_bad_study_before_any_worker_starts(tmp_path, capsys, vary, needles):
    started = study_run.workers_started
    out = tmp_path / "sheet.png"
    args = ["study", str(BASELINE), "-o", str(out), "--size", "32x32"]
    for v in vary:
        args += ["--vary", v]
    assert cli.main(args) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: ") and "\n" not in err
    for needle in needles:
        assert needle in err
    assert study_run.workers_started == started
    assert list(tmp_path.iterdir()) == []


# ---------------------------------------------------------------------------------------------
# Rendering


@pytest.mark.slow
def test_two_by_two_gives_the_images_of_four_separate_renders():
    s = two_by_two()
    seen = []
    images = study_run.run_study(s, workers=2, progress=lambda done, total: seen.append((done, total)))
    assert len(images) == 4
    for v, image in zip(s.variants, images, strict=True):
        expected = render(v.scene, *SIZE)
        assert image.dtype == np.float32 and image.shape == (32, 32, 3)
        assert np.array_equal(image, expected), v.index
    # variants differ from each other (the parameters reach the tracer)
    assert not np.array_equal(images[0], images[3])
    assert seen[-1] == (4, 4) and [d for d, _ in seen] == sorted(d for d, _ in seen)
    # the same in this process
    here = study_run.run_study(s, workers=0)
    assert all(np.array_equal(a, b) for a, b in zip(images, here, strict=True))


@pytest.mark.slow
def test_cancel_stops_the_workers_and_removes_the_temporary_files():
    s = st.Study.build(baseline_doc(), [st.parse_vary("lens.ior=1.4:1.6:4"), st.parse_vary("cuts.height=0.5:2:4")],
                       (48, 48))
    runs: list[study_run.StudyRun] = []
    state = {}

    def on_start(run):
        runs.append(run)
        state["pids"] = run.process_ids()
        state["folder"] = run._folder

    with pytest.raises(study_run.Cancelled):
        study_run.run_study(s, workers=2, on_start=on_start, should_stop=lambda: runs[0].done >= 1)
    run = runs[0]
    assert 1 <= run.done < len(s)  # stopped mid-study
    assert len(state["pids"]) == 2
    assert all(process_gone(pid) for pid in state["pids"])
    assert all(w.process.returncode is not None for w in run._pool)
    assert not os.path.exists(state["folder"])


def test_a_worker_that_dies_stops_the_study_with_an_error():
    s = st.Study.build(baseline_doc(), [st.parse_vary("lens.ior=1.4:1.6:8")], (48, 48))
    run = study_run.StudyRun(s, workers=2)
    run.start()
    folder = run._folder
    try:
        os.kill(run.process_ids()[0], signal.SIGKILL)
        with pytest.raises(study_run.StudyError, match="stopped unexpectedly"):
            deadline = time.monotonic() + 60
            while not run.poll(timeout=0.05):
                assert time.monotonic() < deadline
    finally:
        run.close()
    assert all(process_gone(pid) for pid in run.process_ids())
    assert not os.path.exists(folder)


# ---------------------------------------------------------------------------------------------
# The contact sheet


def _rects_overlap(a: study_sheet.Rect, b: study_sheet.Rect) -> bool:
    return a.x < b.x + b.w and b.x < a.x + a.w and a.y < b.y + b.h and b.y < a.y + a.h


@pytest.mark.parametrize("size", [(32, 32), (64, 40), (256, 256)])
def test_layout_follows_from_the_study(size):
    s = st.Study.build(baseline_doc(), [st.parse_vary("lens.ior=1.45:1.6:3"), st.parse_vary("cuts.height=0.5,2")], size)
    lay = study_sheet.layout(s)
    w, h = size
    scale = study_sheet.text_scale(size)
    adv, line, pad = 6 * scale, 10 * scale, 4 * scale
    # Column width: the image or the widest column label ("ior=1.525"), whichever is wider; each value
    # is said once, in its column's or row's header with its unit, so nothing goes under the cells.
    cell_w = max(w, len("ior=1.525") * adv)
    cell_h = h
    row_header = len("height=0.5 mm") * adv + pad
    assert lay.width == max(pad + row_header + 3 * cell_w + 2 * pad + pad, 2 * pad + 28 * adv)
    assert lay.height == pad + 2 * line + pad + line + 2 * cell_h + pad + pad
    assert len(lay.cells) == 6
    for v, rect in zip(s.variants, lay.cells, strict=True):
        assert (rect.w, rect.h) == (w, h)
        assert rect.x == pad + row_header + v.column * (cell_w + pad) + (cell_w - w) // 2
        assert rect.y == pad + 3 * line + pad + v.row * (cell_h + pad)
        assert 0 <= rect.x and rect.x + rect.w <= lay.width and rect.y + rect.h <= lay.height
    boxes = [b.rect for b in lay.texts] + list(lay.cells)
    for i, a in enumerate(boxes):
        assert a.x >= 0 and a.y >= 0 and a.x + a.w <= lay.width and a.y + a.h <= lay.height
        for b in boxes[i + 1:]:
            assert not _rects_overlap(a, b), (a, b)
    kinds = [b.kind for b in lay.texts]
    assert kinds.count("column") == 3 and kinds.count("row") == 2 and kinds.count("cell") == 0
    texts = [b.text for b in lay.texts]
    assert "columns: lens.ior   rows: cuts.height" in texts
    assert ["ior=1.45", "ior=1.525", "ior=1.6"] == [b.text for b in lay.texts if b.kind == "column"]
    assert ["height=0.5 mm", "height=2 mm"] == [b.text for b in lay.texts if b.kind == "row"]  # spec's unit
    assert len(texts) == len(set(texts))  # each label once


def test_one_axis_sheet_is_one_row_without_row_labels():
    s = st.Study.build(baseline_doc(), [st.parse_vary("lens.ior=1.45,1.5,1.55,1.6,1.65")], (64, 64))
    lay = study_sheet.layout(s)
    assert len({r.y for r in lay.cells}) == 1 and len({r.x for r in lay.cells}) == 5
    assert not [b for b in lay.texts if b.kind == "row"]
    assert all(r.x >= 4 for r in lay.cells)


@pytest.mark.parametrize("text", ["oiio", "bitmap"])
@pytest.mark.seed(5)
def test_sheet_pastes_each_image_in_its_cell_and_labels_it(text, rng):
    s = two_by_two()
    images = [rng.random((32, 32, 3), dtype=np.float32) for _ in range(4)]
    sheet = study_sheet.compose(s, images, text=text)
    lay = study_sheet.layout(s)
    assert sheet.shape == (lay.height, lay.width, 3) and sheet.dtype == np.float32
    for rect, image in zip(lay.cells, images, strict=True):
        assert np.array_equal(sheet[rect.y:rect.y + rect.h, rect.x:rect.x + rect.w], image)
    bg = np.asarray(study_sheet.BACKGROUND, dtype=np.float32)
    for box in lay.texts:
        r = box.rect
        region = sheet[r.y:r.y + r.h, r.x:r.x + r.w]
        assert (np.abs(region - bg).max(axis=2) > 0.2).any(), box  # something is written in every label
    plain = study_sheet.compose(s, images, text="none")
    outside = np.ones(sheet.shape[:2], dtype=bool)
    for rect in lay.cells:
        outside[rect.y:rect.y + rect.h, rect.x:rect.x + rect.w] = False
    assert np.all(plain[outside] == bg)


@pytest.mark.parametrize("suffix", [".exr", ".png"])
def test_sheet_file_carries_the_study(tmp_path, suffix):
    s = two_by_two()
    images = [np.full((32, 32, 3), 0.25 * (i + 1), dtype=np.float32) for i in range(4)]
    standard = display.view_transform("Standard")
    path = tmp_path / f"sheet{suffix}"
    used = study_sheet.write_sheet(path, s, images, view=standard, exposure=-1)
    assert (used.paper_stops, used.ev100) == ((-1 if suffix == ".png" else 0), None)
    assert sorted(p.name for p in tmp_path.iterdir()) == [path.name]
    inp = oiio.ImageInput.open(str(path))
    spec = inp.spec()
    pixels = inp.read_image(0, 0, 0, 3, oiio.FLOAT)
    inp.close()
    lay = study_sheet.layout(s)
    assert (spec.width, spec.height) == (lay.width, lay.height)
    if suffix == ".exr":  # linear, no exposure
        assert spec.format == oiio.FLOAT and np.array_equal(pixels, study_sheet.compose(s, images))
    else:  # the variants at -1 EV through the view, labels on the display side
        assert spec.format == oiio.UINT8
        shown = study_sheet.compose(s, images, exposure=-1, view=standard)
        assert np.array_equal(np.rint(pixels * 255).astype(np.uint8), np.rint(shown * 255).astype(np.uint8))
        for rect, image in zip(study_sheet.layout(s).cells, images, strict=True):
            cell = pixels[rect.y:rect.y + rect.h, rect.x:rect.x + rect.w]
            assert np.abs(cell - display.srgb_encode(image / 2)).max() <= 0.5 / 255 + 1e-6
    assert json.loads(spec.getattribute("lamp:study")) == s.to_doc()
    assert st.Study.load(path).to_json() == s.to_json()


def test_loading_a_study_from_an_image_without_one(tmp_path):
    from core_tracer.images.imageio import write_image

    path = tmp_path / "plain.png"
    write_image(path, np.zeros((4, 4, 3), dtype=np.float32))
    with pytest.raises(SceneError, match="carries no study"):
        st.Study.load(path)


# ---------------------------------------------------------------------------------------------
# The command line, as users run it


@pytest.mark.slow
def test_cli_study_writes_the_sheet_and_reruns_it(tmp_path):
    out = tmp_path / "sheet.png"
    proc = run_cli("study", BASELINE, "--vary", "lens.ior=1.45:1.6:2", "--vary", "cuts.height=0.5,2", "-o", out,
                   "--size", "32x32", "--workers", "2", "--save-study", tmp_path / "study.json",
                   "--save-variants", tmp_path / "variants")
    assert proc.returncode == 0, proc.stderr
    assert "2 x 2 variants of 32x32 px" in proc.stdout
    s = st.Study.load(out)
    assert len(s) == 4 and s.to_json() == (tmp_path / "study.json").read_text()
    assert len(list((tmp_path / "variants").glob("variant-*.json"))) == 4
    lay = study_sheet.layout(s)
    inp = oiio.ImageInput.open(str(out))
    assert (inp.spec().width, inp.spec().height) == (lay.width, lay.height)
    inp.close()
    # Re-run from the sheet's own header, as EXR this time, at another size.
    again = tmp_path / "again.exr"
    proc = run_cli("study", "--study", out, "-o", again, "--size", "24x16")
    assert proc.returncode == 0, proc.stderr
    assert st.Study.load(again).size == (24, 16)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["again.exr", "sheet.png", "study.json", "variants"]


@pytest.mark.slow
@pytest.mark.parametrize("args,needles", [
    (["--vary", "lens.ior=1.45,9", "-o", "{out}"], ("lens.ior", "9", "[1, 3]")),
    (["--vary", "lens.ior=1.45:1.6:0", "-o", "{out}"], ("steps 0",)),
    (["--vary", "lens.ior", "-o", "{out}"], ("--vary", "PARAMETER=")),
    (["--vary", "lens.ior=1.5", "-o", "{tmp}/sheet.tif"], ("sheet.tif", ".exr, .png")),
    (["--vary", "lens.ior=1.5", "-o", "{tmp}/no/sheet.png"], ("does not exist",)),
    (["--vary", "lens.ior=1.5", "-o", "{out}", "--size", "64"], ("--size", "WIDTHxHEIGHT")),
    (["-o", "{out}"], ("--vary", "is required")),
])
def test_cli_bad_input_exits_2_with_one_line(tmp_path, args, needles):
    out = tmp_path / "sheet.png"
    args = [a.format(out=out, tmp=tmp_path) for a in args]
    proc = run_cli("study", BASELINE, *args)
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in proc.stderr, proc.stderr
    for needle in needles:
        assert needle in lines[0]
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_cli_study_of_a_missing_sheet_exits_2(tmp_path):
    proc = run_cli("study", "--study", tmp_path / "nothing.exr", "-o", tmp_path / "x.png")
    assert proc.returncode == 2 and "nothing.exr" in proc.stderr and "Traceback" not in proc.stderr


@pytest.mark.slow
@pytest.mark.skipif(not os.path.isdir("/proc"), reason="finds the worker processes through /proc")
def test_cli_ctrl_c_exits_130_and_writes_nothing(tmp_path):
    out = tmp_path / "sheet.png"
    args = ["study", BASELINE, "--vary", "lens.ior=1.4:1.6:8", "--vary", "cuts.height=0.5:2:8", "-o", out,
            "--size", "128x128", "--workers", "2", "--engine", "processes"]
    # The signal lands once both workers have started, before the first variant is done.
    proc = start_cli_at("study:started", tmp_path.parent / f"{tmp_path.name}-started", *args)
    workers = child_pids(proc.pid)
    _, err = signal_and_wait(proc, signal.SIGINT)
    assert proc.returncode == 130, err
    assert "Traceback" not in err
    assert list(tmp_path.iterdir()) == []
    assert len(workers) == 2
    assert all(process_gone(pid) for pid in workers)


@pytest.mark.slow
def test_study_run_driven_by_polling_like_a_modal_operator():
    s = st.Study.build(baseline_doc(), [st.parse_vary("lens.ior=1.4:1.6:3")], (48, 48))
    run = study_run.StudyRun(s, workers=2)
    run.start()
    folder = run._folder
    fractions = []
    try:
        deadline = time.monotonic() + 60
        while not run.poll():  # never blocks, as a timer callback must not
            fractions.append(run.fraction)
            assert time.monotonic() < deadline
            time.sleep(0.01)
    finally:
        run.close()
    assert run.finished and run.done == 3 and run.fraction == 1.0
    assert fractions == sorted(fractions) and all(0 <= f <= 1 for f in fractions)
    for v, image in zip(s.variants, run.images, strict=True):
        assert np.array_equal(image, render(v.scene, 48, 48))
    assert all(process_gone(pid) for pid in run.process_ids())
    assert not os.path.exists(folder)


@pytest.mark.slow
def test_cli_lists_the_parameters():
    proc = run_cli("study", "--list")
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split() == study_parameters()


def test_one_lamps_centre_is_a_parameter():
    base = load_scene(FOUR_LAMPS)
    s = st.Study.build(base, [st.parse_vary("lamps[0].center=-185/0,-180/5")])
    assert [v.scene["lamps"][0]["center"] for v in s.variants] == [[-185.0, 0.0], [-180.0, 5.0]]


def test_the_axes_line_names_both_parameters_in_full():
    """Small variants make a narrow sheet: the line naming the columns' and rows' parameters still
    fits in full (it was cut to "rows: cut..." at 128 px cells)."""
    study = st.Study.build(baseline_doc(), [st.parse_vary("lens.ior=1.45,1.6"),
                                            st.parse_vary("cuts.height=0.5,2")], (128, 128))
    lay = study_sheet.layout(study)
    adv = study_sheet.bitmap_font.ADVANCE_W * study_sheet.text_scale(study.size)
    (axes,) = [box for box in lay.texts if box.kind == "axes"]
    assert axes.text == "columns: lens.ior   rows: cuts.height"
    assert len(axes.text) * adv <= axes.rect.w


def test_samples_vary_like_any_parameter_and_count_in_the_budget():
    assert "image.samples" in study_parameters()
    doc = {**baseline_doc(), "image": {"width": 9, "height": 9, "samples": 4}}
    s = st.Study.build(doc, [st.parse_vary("image.samples=1,16")], SIZE)
    # the design's, at the study's size
    assert s.base["image"] == {"width": SIZE[0], "height": SIZE[1], "samples": 4, "edge_samples": 0}
    one, many = (v.scene for v in s.variants)
    assert (one["image"]["samples"], many["image"]["samples"]) == (1, 16)
    assert not np.array_equal(render(one), render(many))
    # 64 variants of 512 x 512 px at 256 samples: refused before any work, naming samples.
    with pytest.raises(SceneError, match=r"image\.samples: .* eye rays; allowed at most"):
        st.Study.build({**doc, "image": {"width": 9, "height": 9, "samples": 256}},
                       [st.parse_vary("lens.ior=1.4:1.6:8"), st.parse_vary("cuts.height=0.5:2:8")], (512, 512))

"""Measures under a study's cells: the study fields, sorting and filtering, the sheet's layout."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from helpers import BASELINE, PRESETS, ROOT

from core_tracer.measures import by_name, report, table
from core_tracer.scene.reading import SceneError
from core_tracer.study import definition as st
from core_tracer.study import measured as sm
from core_tracer.study import sheet as study_sheet

STOP = PRESETS / "photometric-stop-lamp.json"
FOUR = ROOT / "docs" / "measures" / "four-lamp-night-lit-photometric" / "measures.json"
STOP_MEASURED = ROOT / "docs" / "measures" / "photometric-stop-lamp" / "measures.json"


def _study(measured: dict | None = None, base=STOP, values=(1.45, 1.5, 1.55, 1.6)) -> st.Study:
    doc = json.loads(base.read_text())
    return st.Study.build(doc, [{"parameter": "lens.ior", "values": list(values)}], (24, 16), "", measured)


def test_a_study_without_measures_writes_what_it_always_wrote():
    study = _study()
    assert not study.measured
    assert set(study.to_doc()) == {"schema", "base", "axes", "size"}
    again = st.Study.from_json(study.to_json())
    assert again.to_json() == study.to_json()
    assert study_sheet.layout(study) == study_sheet.layout(study, None)


def test_measure_fields_round_trip_through_the_study_json():
    fields = {"measures": ["homogeneity.lmin_lmax", "intensity.hv_cd@stop"], "sort": "-homogeneity.lmin_lmax",
              "filter": ["grid.pass==1"]}
    study = _study(fields)
    assert study.to_doc()["measures"] == fields["measures"] and study.to_doc()["filter"] == ["grid.pass==1"]
    again = st.Study.from_json(study.to_json())
    assert again.measured == study.measured
    assert again.measured.names == ("homogeneity.lmin_lmax", "intensity.hv_cd@stop", "grid.pass")


@pytest.mark.parametrize(("fields", "path", "words"), [
    ({"measures": ["homogeneity.evenness"]}, "measures[0]", "allowed colour.distance_outside"),
    ({"measures": ["intensity.hv_cd@fog"]}, "measures[0]", "@function (tail, stop, turn, reversing)"),
    ({"measures": "grid.pass"}, "measures", "expected a list"),
    ({"sort": "-grid.passes"}, "sort", "allowed colour.distance_outside"),
    ({"filter": ["grid.pass=1"]}, "filter[0]", "operators == != >= <= > <"),
    ({"filter": ["grid.pass==one"]}, "filter[0]", "MEASURE OPERATOR NUMBER"),
])
def test_bad_measure_fields_are_one_line_naming_the_field(fields, path, words):
    with pytest.raises(SceneError) as e:
        _study(fields)
    assert e.value.path == path and words in e.value.message and "\n" not in str(e.value)


def test_measures_need_a_photometric_design():
    with pytest.raises(SceneError) as e:
        _study({"measures": ["grid.pass"]}, base=BASELINE)
    assert e.value.path == "measures" and 'light_model "photometric"' in e.value.message


def test_sort_and_filter_order_the_variants_and_name_the_left_out():
    values = [{"a.b": 0.2, "grid.pass": 1.0}, {"a.b": math.nan, "grid.pass": 1.0},
              {"a.b": 0.9, "grid.pass": 0.0}, {"a.b": 0.5, "grid.pass": 1.0}]
    choice = sm.Choice(("a.b",), "-a.b", (sm.Filter("grid.pass", "==", 1.0),))
    assert sm.arrange(choice, values) == ([3, 0, 1], [2])  # highest first, n/a last; #3 fails the filter
    assert sm.arrange(sm.Choice(("a.b",), "a.b"), values) == ([0, 3, 2, 1], [])
    assert not sm.Filter("a.b", ">", 0.0).keeps(math.nan)


def test_a_sorted_filtered_sheet_places_cells_in_order_and_lists_the_rest():
    study = _study({"measures": ["homogeneity.lmin_lmax"], "sort": "-homogeneity.lmin_lmax",
                    "filter": ["grid.pass==1"]})
    values = [{"homogeneity.lmin_lmax": u, "grid.pass": p} for u, p in ((0.1, 1), (0.4, 1), (0.3, 0), (0.2, 1))]
    lay = study_sheet.layout(study, values)
    assert lay.cells[2] is None  # filtered out
    kept = [lay.cells[i] for i in (1, 3, 0)]  # 0.4, 0.2, 0.1: left to right
    assert [r.x for r in kept] == sorted(r.x for r in kept) and len({r.y for r in kept}) == 1
    texts = [t.text for t in lay.texts]
    assert "homogeneity.lmin_lmax=0.4" in texts and "sorted by -homogeneity.lmin_lmax   filter grid.pass==1" in texts
    footer = [t.text for t in lay.texts if t.kind == "footer"]
    assert footer[0] == "left out by the filter (1):" and footer[1].startswith("  #3 ior=1.55")
    assert "grid.pass=0" in footer[1]
    # The images land where the layout says; the left-out one is nowhere.
    images = [np.full((16, 24, 3), 0.1 * (k + 1), np.float32) for k in range(4)]
    sheet = study_sheet.compose(study, images, text="none", measured=values, as_values=True)  # placement only
    assert sheet.shape == (lay.height, lay.width, 3)
    for k, rect in enumerate(lay.cells):
        if rect is not None:
            assert np.allclose(sheet[rect.y:rect.y + rect.h, rect.x:rect.x + rect.w], 0.1 * (k + 1))
    assert not np.isclose(sheet, 0.3).all(axis=-1).any()


def test_measures_without_order_keep_the_grid_and_add_lines():
    study = _study({"measures": ["grid.min_margin"]})
    values = [{"grid.min_margin": m} for m in (0.5, -0.25, math.nan, 1.0)]
    plain, with_values = study_sheet.layout(study), study_sheet.layout(study, values)
    assert [r.x for r in plain.cells] == [r.x for r in with_values.cells] or plain.width < with_values.width
    cells = [t.text for t in with_values.texts if t.kind == "cell"]  # the values are in the column headers
    assert cells == ["grid.min_margin=0.5", "grid.min_margin=-0.25", "grid.min_margin=n/a", "grid.min_margin=1"]
    assert [t.text for t in with_values.texts if t.kind == "column"] == ["ior=1.45", "ior=1.5", "ior=1.55", "ior=1.6"]
    hv = {"intensity.hv_cd": 121.66}
    assert study_sheet.measure_lines(_study({"measures": ["intensity.hv_cd"]}), 0, [hv] * 4) == [
        "intensity.hv_cd=122 cd"]  # with its unit (measures.by_name)


def test_measures_by_name_read_the_committed_reports():
    assert by_name.FUNCTION_NAMES == tuple(report.FUNCTIONS)
    four = json.loads(FOUR.read_text())
    v = by_name.values(four, by_name.NAMES)
    assert v["grid.pass"] == 0.0 and v["grid.failed"] == sum(not r["passed"] for r in four["rows"])
    assert by_name.value(four, "grid.pass@stop") == 1.0 and by_name.value(four, "grid.pass@reversing") == 0.0
    assert v["homogeneity.lmin_lmax"] == min(h["lmin_over_lmax"] for h in four["homogeneity"].values())
    assert v["homogeneity.cv"] == max(h["cv"] for h in four["homogeneity"].values())
    hv = {name: next(cd for h, vv, cd, _ in rows if h == 0 and vv == 0)
          for name, rows in four["intensities_cd"].items()}
    assert v["intensity.hv_cd"] == min(hv.values()) and by_name.value(four, "intensity.hv_cd@stop") == hv["stop"]
    assert v["grid.min_margin"] == min(r["margin"] for r in four["rows"] if r["margin"] is not None
                                       and math.isfinite(r["margin"]))
    assert v["colour.distance_outside"] == 0.0  # every function's light inside its R48 region
    assert by_name.value(four, "homogeneity.cv@tail") == four["homogeneity"]["tail"]["cv"]


def test_the_summary_line_names_the_worst_failing_point():
    four = json.loads(FOUR.read_text())
    assert table.summary(four) == ("Tail: pass · Stop: pass · Turn: pass · Reversing: fails AR at H-V 773 cd > "
                                   "300 cd (+10 more)")
    assert table.summary(json.loads(STOP_MEASURED.read_text())) == "Stop: pass"
    lines = table.lines(four)
    assert len([line for line in lines if line.passed is False]) == 11
    assert [line.passed for line in lines if line.point == "Lmin/Lmax (lit lens)"] == [None] * 4
    assert "FMVSS backup group 1 min" in {line.point for line in lines}
    assert (lines[0].function, lines[0].point, lines[0].passed) == ("reversing", "AR H-V max", False)  # failed first


def test_measured_values_are_kept_in_the_cell_cache_by_content(tmp_path):
    from core_tracer.cluster.cache import CellCache

    study = _study({"measures": ["grid.pass"]})
    scenes = [v.scene for v in study.variants]
    cache = CellCache(tmp_path)
    names = ("grid.pass", "intensity.hv_cd")
    # Values kept under a variant's key are what a re-run gets, without measuring (which takes seconds).
    for k, scene in enumerate(scenes):
        cache.put_array(sm.measures_key(scene, names), np.array([1.0, 100.0 + k]))
    got = sm.measure_variants(scenes, names, cache=cache)
    assert got == [{"grid.pass": 1.0, "intensity.hv_cd": 100.0 + k} for k in range(len(scenes))]
    assert sm.measures_key(scenes[0], names) != sm.measures_key(scenes[1], names)
    assert sm.measures_key(scenes[0], names) != sm.measures_key(scenes[0], names[:1])

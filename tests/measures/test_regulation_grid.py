"""The regulation grid (core_tracer.measures.regulation_grid): the data file agrees, value by value,
with the tables of docs/measures.md (neither is edited silently), and synthetic intensity
distributions built to pass and to fail exactly one point get exactly those verdicts."""

from __future__ import annotations

import math
import re

import pytest

from core_tracer.measures import regulation_grid as R

# -- the two places agree -------------------------------------------------------------------


def _tables(text: str) -> dict[str, list[list[str]]]:
    """Markdown tables under each ### heading: heading -> rows of cells (the header row first)."""
    out: dict[str, list[list[str]]] = {}
    heading = None
    for line in text.splitlines():
        if line.startswith("### "):
            heading = line[4:].strip()
        elif line.startswith("## "):
            heading = None
        elif line.startswith("|") and heading is not None and not re.match(r"^\|[-| ]+\|$", line):
            out.setdefault(heading, []).append([c.strip() for c in line.strip("|").split("|")])
    return out


@pytest.fixture(scope="module")
def doc_tables(repo_root):
    return _tables((repo_root / "docs" / "measures.md").read_text(encoding="utf-8"))


def _angle(label: str) -> float:
    """'20L' -> -20, '5R' -> 5, '10U' -> 10, '5D' -> -5, 'V' or 'H' -> 0."""
    if label in ("V", "H"):
        return 0.0
    value, side = float(label[:-1]), label[-1]
    return -value if side in "LD" else value


def _figure(rows: list[list[str]]) -> dict[tuple[float, float], float]:
    header = [_angle(h) for h in rows[0][1:]]
    grid = {}
    for row in rows[1:]:
        v = _angle(row[0])
        for h, cell in zip(header, row[1:], strict=True):
            if cell:
                grid[(h, v)] = float(cell)
    return grid


@pytest.mark.parametrize("heading, grid", [
    ("UN R148 Annex 3, Figure A3-I (p. 40): per cent of the H-V minimum", "R148 Figure A3-I"),
    ("UN R148 Annex 3, Figure A3-III (p. 41): per cent of the H-V minimum", "R148 Figure A3-III"),
    ("UN R148 Annex 3, Figure A3-V (p. 42): reversing lamp, minimum cd", "R148 Figure A3-V"),
])
def test_r148_figures_match_docs(doc_tables, heading, grid):
    in_data = {(float(h), float(v)): float(value) for h, v, value in R.data()["grids"][grid]["points"]}
    assert in_data == _figure(doc_tables[heading])


def test_r148_limits_match_docs(doc_tables):
    rows = doc_tables["UN R148: minimum at H-V and maximum (cd)"][1:]
    assert {r[0] for r in rows} == {k for k in R.function_keys() if k.startswith("R148")}
    for key, table, minimum, maximum, night, grid in rows:
        f = R.function(key)
        assert f["min_hv"] == float(minimum), key
        assert f["grid"] == f"R148 {grid}", key
        assert table.split(" (")[0] in f["cite"], key
        if "max_zones" in f:
            assert [float(z["max"]) for z in f["max_zones"]] == [float(x) for x in re.findall(r"(\d+) ", maximum + " ")]
        else:
            assert f["max"] == float(maximum), key
        assert f.get("max_night") == (float(night) if night else None), key


def test_fmvss_grid_matches_docs(doc_tables):
    rows = doc_tables["FMVSS 108 Tables VII, VIII, IX (pp. 467–469): one lighted section, minimum cd"]
    body, groups = rows[1:-1], rows[-1]
    keys = {"FMVSS taillamp": 2, "FMVSS stop": 3, "FMVSS rear turn amber": 4}
    for key, column in keys.items():
        points = R.function(key)["points"]
        assert [p["id"] for p in points] == [r[0] for r in body]
        assert [p["group"] for p in points] == [int(r[1]) for r in body]
        assert [p["min"] for p in points] == [float(r[column]) for r in body], key
        assert R.function(key)["groups"] == [float(x) for x in groups[column].split(",")], key
    ratio = R.data()["ratios"]["FMVSS stop/taillamp"]["points"]
    assert [(name, factor) for name, _, _, factor in ratio] == [(r[0], float(r[5])) for r in body]
    tail = R.function("FMVSS taillamp")
    assert {p.get("max") for p in tail["points"]} == {18, None}
    assert all((p.get("max") == 18) == (p["v"] >= 0) for p in tail["points"])
    assert R.function("FMVSS stop")["max"] == 300 and R.function("FMVSS rear turn amber")["max"] == 750


def test_fmvss_backup_matches_docs(doc_tables):
    rows = doc_tables["FMVSS 108 Table XII (p. 472): backup lamp, single lamp system, minimum cd"]
    body, groups = rows[1:-1], rows[-1]
    printed = {}
    for r in body:
        printed[r[0]] = (int(r[1]), float(r[2]))
        printed[r[3]] = (int(r[4]), float(r[5]))
    f = R.function("FMVSS backup")
    assert {p["id"]: (p["group"], p["min"]) for p in f["points"]} == printed
    assert f["groups"] == [float(x) for x in groups[2].split(",")]
    assert all((p.get("max") == 600) == (p["v"] >= 0) for p in f["points"])


def test_every_function_cites_its_source():
    for key in R.function_keys():
        cite = R.citation(key)
        assert "Table" in cite and ("ECE/TRANS/WP.29/2022/92" in cite or "49 CFR 571.108" in cite), key
    for source in R.data()["sources"].values():
        assert "swiftugandan/cutline" in source["read_from"] and source["url"].startswith("https://")


# -- verdicts -------------------------------------------------------------------------------


def _scaled(key: str, factor: float, peak_factor: float | None = None):
    """A smooth distribution that is ``factor`` × each grid point's minimum at the grid points
    (H-V: max(minimum, …)), and below the maximum everywhere: I(H, V) = A exp(−(H/25)² − (V/12)²)."""
    f = R.function(key)
    hv = f.get("min_hv") or max(p["min"] for p in f.get("points", [])) or 1.0
    amplitude = factor * hv if peak_factor is None else peak_factor

    def at(h: float, v: float) -> tuple[float, float]:
        return amplitude * math.exp(-((h / 25.0) ** 2) - (v / 12.0) ** 2), 0.0
    return at


def _with_points(key: str, factor: float):
    """Every test point at ``factor`` × its minimum (elsewhere the lowest of them), the maximum's
    directions kept under every maximum."""
    points = {(h, v): minimum for _, h, v, minimum in R.test_points(key)}
    floor = min(points.values())

    def at(h: float, v: float) -> tuple[float, float]:
        return factor * points.get((h, v), floor), 0.0
    return at


PASSING = {  # a factor that clears every minimum and stays under every maximum
    "R148 R1": 2.0, "R148 R2": 2.0, "R148 S1": 2.0, "R148 S2": 2.0, "R148 S3": 1.5, "R148 S4": 1.5,
    "R148 2a": 2.0, "R148 2b": 2.0, "R148 AR": 2.0, "FMVSS taillamp": 1.5, "FMVSS stop": 2.0,
    "FMVSS rear turn amber": 2.0, "FMVSS backup": 1.5,
}


@pytest.mark.parametrize("key", list(PASSING))
def test_built_to_pass_passes(key):
    rows = R.check(key, _with_points(key, PASSING[key]))
    assert rows and R.verdict(rows), [r for r in rows if not r.passed]


@pytest.mark.parametrize("key", list(PASSING))
def test_built_to_fail_one_point_fails_that_point_only(key):
    """One test point (not H-V) at 0.5 × its minimum, the others as built to pass: UN R148 and
    FMVSS's 60 % floor fail that point alone. Where FMVSS lets a group's sum stand for its points
    (Tables VIII, XII), the group's other points are put at their minima, whose sum is the group's
    minimum: the point and its group fail, nothing else."""
    points = R.test_points(key)
    name, h0, v0, minimum0 = next(p for p in points if (p[1], p[2]) != (0.0, 0.0))
    base = _with_points(key, PASSING[key])
    f = R.function(key)
    alternative = f.get("rule") == "group-alternative"
    group = next((p["group"] for p in f.get("points", []) if p["id"] == name), None)
    same_group = {(float(p["h"]), float(p["v"])): float(p["min"]) for p in f.get("points", []) if p["group"] == group}

    def at(h: float, v: float) -> tuple[float, float]:
        if (h, v) == (h0, v0):
            return 0.5 * minimum0, 0.0
        if alternative and (h, v) in same_group:
            return same_group[(h, v)], 0.0
        return base(h, v)
    rows = R.check(key, at)
    failed = [(r.point, r.kind) for r in rows if not r.passed]
    expected = [(name, "min")] + ([(f"group {group}", "group min")] if alternative else [])
    assert failed == expected


def test_maximum_fails_where_exceeded():
    rows = R.check("R148 S1", _scaled("R148 S1", 1.0, peak_factor=300.0))
    failed = [r for r in rows if not r.passed]
    assert [(r.kind, r.required) for r in failed] == [("max", 260.0)]
    assert failed[0].simulated == pytest.approx(300.0)


def test_rounding_down_to_three_digits():
    """R148 Annex 3 §1.1 (Supplement 6): 60 cd × 35 % = 21 cd; 4 cd × 35 % = 1.4 cd; 25 × 32 % = 8 cd."""
    assert R.round_down_3(1.4) == pytest.approx(1.4)
    assert R.round_down_3(12.3456) == pytest.approx(12.3)
    assert R.round_down_3(0.99999) == pytest.approx(0.999)
    assert {p[0]: p[3] for p in R.test_points("R148 S1")}["H-10L"] == pytest.approx(21.0)


def test_stop_tail_ratio():
    """R148 §4.8.3.5: (stop + tail)/tail ≥ 5 inside ±10° H, ±5° V: a tail of 10 cd beside a stop of
    45 cd passes (5.5), beside 35 cd fails (4.5) at every point of the zone."""
    tail = {d: (10.0, 0.0) for d in R.FIELD_SWEEP}
    ok = R.check_ratio("R148 stop/position 5:1", {d: (45.0, 0.0) for d in R.FIELD_SWEEP}, tail)
    bad = R.check_ratio("R148 stop/position 5:1", {d: (35.0, 0.0) for d in R.FIELD_SWEEP}, tail)
    assert len(ok) == 15 and R.verdict(ok)
    assert len(bad) == 15 and not any(r.passed for r in bad)
    assert all(abs(r.h) <= 10 and abs(r.v) <= 5 for r in ok)

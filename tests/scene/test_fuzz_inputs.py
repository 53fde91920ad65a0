"""Property-based tests of the validator and the command line on hostile input.

Random JSON trees, every field of a real design replaced by a value of the wrong kind, numbers of
hundreds or thousands of digits, control characters and lone surrogates, keys given twice: the
answer is always a ``SceneError`` (exit status 2 on the command line) whose one printable line
names the field, never a traceback.

The default run is short. ``LAMP_FUZZ_EXAMPLES=N`` multiplies every test's number of examples by
N for a long run, e.g. ``LAMP_FUZZ_EXAMPLES=50 pytest tests/test_fuzz_inputs.py``.
"""

from __future__ import annotations

import copy
import json
import os
import re
import subprocess
import sys

import helpers
import pytest
from helpers import ROOT, fuzz
from hypothesis import assume, given
from hypothesis import strategies as st

from core_tracer.scene import spec as S
from core_tracer.scene.reading import SceneError, parse_json_text
from core_tracer.scene.safe_text import has_surrogate, printable
from core_tracer.scene.validate import parse_scene
from core_tracer.study import definition as study_mod

pytestmark = pytest.mark.slow

BUILTIN = ROOT / "presets"


DESIGNS = {stem: json.loads((BUILTIN / f"{stem}.json").read_text())
           for stem in ("paper-baseline", "four-lamp-rear-combination", "photometric-stop-lamp",
                        "four-lamp-night-lit-photometric")}


# ---------------------------------------------------------------------------------------------
# Where the fields of a design are, and what each one is


def field_paths(node, spec: S.Spec, path: str = "") -> list[tuple[str, S.Spec]]:
    """Every leaf field present in a document, with its spec: ``lamps[1].lens.ior``."""
    out = []
    if isinstance(spec, S.Section):
        for key, sub in spec.fields.items():
            if key in node:
                out += field_paths(node[key], sub, f"{path}.{key}" if path else key)
    elif isinstance(spec, S.ListOf):
        for i, item in enumerate(node):
            out += field_paths(item, spec.item, f"{path}[{i}]")
    else:
        out.append((path, spec))
    return out


_STEP = re.compile(r"([a-z_][a-z_0-9]*)|\[(\d+)\]")  # keys may hold digits after a letter: camera.ev100


def set_path(doc: dict, path: str, value) -> dict:
    doc = copy.deepcopy(doc)
    steps = [m.group(1) if m.group(1) else int(m.group(2)) for m in _STEP.finditer(path)]
    node = doc
    for step in steps[:-1]:
        node = node[step]
    node[steps[-1]] = value
    return doc


FIELDS = [(stem, path, spec) for stem, doc in DESIGNS.items() for path, spec in field_paths(doc, S.SCENE)]

# ---------------------------------------------------------------------------------------------
# Hostile values

SURROGATES = st.integers(0xD800, 0xDFFF).map(chr)
CONTROL = st.sampled_from([chr(c) for c in [*range(0, 32), 127, *range(0x80, 0xA0)]])
NASTY_CHAR = st.one_of(st.characters(), SURROGATES, CONTROL, st.sampled_from(["\u202e", "\ufeff", "\x9b"]))
NASTY_TEXT = st.text(NASTY_CHAR, max_size=30)
# 310 to 4300 digits: beyond a float, within what int() reads (the range the fuzzing review hit).
HUGE_INT = st.integers(310, 4300).flatmap(lambda n: st.sampled_from([10 ** n - 1, -(10 ** n) + 7, 10 ** (n - 1)]))
NON_FINITE = st.sampled_from([float("nan"), float("inf"), float("-inf")])
JSON_LEAF = st.one_of(st.none(), st.booleans(), st.integers(), st.floats(allow_nan=True), NASTY_TEXT, HUGE_INT)
JSON_TREE = st.recursive(JSON_LEAF, lambda kids: st.one_of(st.lists(kids, max_size=5),
                                                           st.dictionaries(NASTY_TEXT, kids, max_size=5)),
                         max_leaves=20)


def with_surrogate(text_strategy=NASTY_TEXT):
    """A string holding at least one lone surrogate, also once read back from JSON (which joins a
    high and a low surrogate written one after the other into one character)."""
    return st.tuples(text_strategy, SURROGATES, text_strategy).map(lambda t: t[0] + t[1] + t[2]).filter(
        lambda text: has_surrogate(json.loads(json.dumps(text))))


def not_a_number():
    return st.one_of(st.none(), st.booleans(), NASTY_TEXT,
                     st.floats(allow_nan=False).map(lambda x: f"{x}"),  # "1.5": a number in quotes
                     st.lists(st.integers(), max_size=3), st.dictionaries(NASTY_TEXT, st.integers(), max_size=2))


def bad_scalar(spec: S.Num):
    """A value that is not a number in ``spec``'s range."""
    out_of_range = []
    if spec.lo is not None:
        out_of_range.append(st.floats(max_value=spec.lo, exclude_max=not spec.lo_open, allow_nan=False,
                                      allow_infinity=False, min_value=-1e308))
    if spec.hi is not None:
        out_of_range.append(st.floats(min_value=spec.hi, exclude_min=not spec.hi_open, allow_nan=False,
                                      allow_infinity=False, max_value=1e308))
    return st.one_of(not_a_number(), NON_FINITE, HUGE_INT, *out_of_range)


def bad_value(spec: S.Spec):
    """A value that ``spec`` refuses, of the kinds a hostile or careless file holds."""
    if isinstance(spec, S.Num):
        if spec.size == 1:
            return bad_scalar(spec)
        good = [0.5] * spec.size
        wrong_length = st.lists(st.floats(0, 1), max_size=spec.size + 3).filter(lambda v: len(v) != spec.size)
        one_bad_item = st.tuples(st.integers(0, spec.size - 1), bad_scalar(spec)).map(
            lambda t: [t[1] if i == t[0] else x for i, x in enumerate(good)])
        return st.one_of(one_bad_item, wrong_length, st.none(), NASTY_TEXT, HUGE_INT)
    if isinstance(spec, S.Text):
        too_long = st.integers(spec.max_len + 1, spec.max_len + 50).map(lambda n: "x" * n)
        return st.one_of(with_surrogate(), too_long, st.integers(), st.none(), st.lists(st.text(), max_size=2))
    if isinstance(spec, S.Tags):
        return st.one_of(st.lists(with_surrogate(), min_size=1, max_size=3), NASTY_TEXT, st.integers(),
                         st.lists(st.one_of(st.integers(), st.none()), min_size=1, max_size=3))
    if isinstance(spec, S.Choice):
        return st.one_of(NASTY_TEXT.filter(lambda t: t not in spec.choices), st.integers(), st.none())
    if isinstance(spec, S.Flag):
        return st.one_of(st.integers(), NASTY_TEXT, st.none(), st.floats())
    raise AssertionError(spec)


def assert_clean(error: SceneError) -> None:
    """One line a terminal shows as it is: no control character, no surrogate, bounded."""
    text = str(error)
    assert printable(text, 10**6) == text, text
    assert len(text) < 2000


# ---------------------------------------------------------------------------------------------
# The validator, in this process


@fuzz(120)
@given(JSON_TREE)
def test_random_json_trees_are_refused_cleanly(tree):
    try:
        parse_scene(parse_json_text(json.dumps(tree)))
    except SceneError as e:
        assert_clean(e)


@fuzz(150)
@given(st.sampled_from(FIELDS).flatmap(lambda f: st.tuples(st.just(f), bad_value(f[2]))))
def test_a_wrong_value_in_any_field_names_that_field_and_what_is_allowed(case):
    (stem, path, spec), value = case
    doc = set_path(DESIGNS[stem], path, value)
    text = json.dumps(doc)  # through JSON text, as from a file: surrogates and huge numbers included
    with pytest.raises(SceneError) as info:
        parse_scene(parse_json_text(text))
    e = info.value
    assert e.path == path or e.path.startswith((path + "[", path + ".")), (path, str(e))
    assert "allowed" in e.message, str(e)
    assert_clean(e)


@fuzz(40)
@given(st.sampled_from([f for f in FIELDS if isinstance(f[2], S.Num) and f[2].size == 1]),
       st.integers(310, 6000), st.sampled_from(["", "-"]), st.sampled_from(["", ".5", "e3", "0e-5"]))
def test_numbers_of_hundreds_or_thousands_of_digits_name_their_field(field, digits, sign, tail):
    stem, path, spec = field
    marker = "123456.789e-3"  # a number found nowhere else in the designs
    text = json.dumps(set_path(DESIGNS[stem], path, float(marker)))
    assert text.count("123.456789") == 1
    text = text.replace("123.456789", sign + "9" * digits + tail)
    with pytest.raises(SceneError) as info:
        parse_scene(parse_json_text(text))
    assert info.value.path == path, str(info.value)
    assert "out of range" in info.value.message and "allowed" in info.value.message
    assert_clean(info.value)


def _objects(node, path=""):
    """Every JSON object of a document with its path."""
    if isinstance(node, dict):
        yield path, node
        for k, v in node.items():
            yield from _objects(v, f"{path}.{k}" if path else k)
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from _objects(v, f"{path}[{i}]")


def _dumps_repeating(node, target, key, value) -> str:
    """JSON text of ``node`` in which the object ``target`` has ``key`` a second time, first with ``value``."""
    if isinstance(node, dict):
        items = [f"{json.dumps(k)}: {_dumps_repeating(v, target, key, value)}" for k, v in node.items()]
        if node is target:
            items.insert(0, f"{json.dumps(key)}: {json.dumps(value)}")
        return "{" + ", ".join(items) + "}"
    if isinstance(node, list):
        return "[" + ", ".join(_dumps_repeating(v, target, key, value) for v in node) + "]"
    return json.dumps(node)


@fuzz(40)
@given(st.sampled_from(sorted(DESIGNS)), st.data())
def test_a_key_given_twice_is_refused_naming_it(stem, data):
    doc = copy.deepcopy(DESIGNS[stem])
    objects = [(p, o) for p, o in _objects(doc) if o]
    path, target = data.draw(st.sampled_from(objects))
    key = data.draw(st.sampled_from(sorted(target)))
    value = data.draw(JSON_LEAF)
    with pytest.raises(SceneError) as info:
        parse_scene(parse_json_text(_dumps_repeating(doc, target, key, value)))
    assert info.value.path == (f"{path}.{key}" if path else key), str(info.value)
    assert "twice" in info.value.message
    assert_clean(info.value)


@fuzz(40)
@given(st.sampled_from([p for stem, p, _ in FIELDS if stem == "paper-baseline" and "." in p]),
       st.text(NASTY_CHAR, min_size=1, max_size=3000))
def test_unknown_keys_are_echoed_escaped_and_short(path, key):
    stem = "paper-baseline"
    section = path.rsplit(".", 1)[0]
    doc = copy.deepcopy(DESIGNS[stem])
    node = doc
    for m in _STEP.finditer(section):
        node = node[m.group(1) if m.group(1) else int(m.group(2))]
    assume(key not in node and isinstance(node, dict))
    node[key] = 1
    with pytest.raises(SceneError) as info:
        parse_scene(parse_json_text(json.dumps(doc)))
    e = info.value
    if "unknown key" in e.message:
        assert e.path.startswith(section + "."), str(e)
        assert len(e.path) <= len(section) + 1 + 60
    assert_clean(e)


# ---------------------------------------------------------------------------------------------
# Studies: every check before any rendering


def _study_doc(axis: dict, title="") -> dict:
    doc = {"schema": "lamp-study/1", "base": DESIGNS["paper-baseline"], "axes": [axis], "size": [16, 16]}
    if title:
        doc["title"] = title
    return doc


@fuzz(60)
@given(st.one_of(
    st.builds(lambda v: {"parameter": "lens.ior", "values": [v]}, JSON_TREE),
    st.builds(lambda v: {"parameter": "lens.ior", "range": [1.4, v], "steps": 3}, st.one_of(HUGE_INT, JSON_LEAF)),
    st.builds(lambda n: {"parameter": "lens.ior", "range": [1.4, 1.5], "steps": n}, st.one_of(HUGE_INT, JSON_LEAF)),
    st.builds(lambda d: {"parameter": f"lamps[{d}].lens.ior", "values": [1.5]}, st.integers(1, 6000).map(
        lambda n: "9" * n)),
    st.builds(lambda p: {"parameter": p, "values": [1.5]}, NASTY_TEXT),
    st.builds(lambda k: {"parameter": "lens.ior", "values": [1.5], k: 1}, NASTY_TEXT),
))
def test_study_axes_are_checked_before_rendering(axis):
    try:
        study_mod.Study.from_json(json.dumps(_study_doc(axis)))
    except SceneError as e:
        assert_clean(e)


@fuzz(20)
@given(with_surrogate())
def test_a_study_title_with_a_surrogate_is_refused(title):
    with pytest.raises(SceneError, match="^title: "):
        study_mod.Study.from_json(json.dumps(_study_doc({"parameter": "lens.ior", "values": [1.5]}, title)))


# ---------------------------------------------------------------------------------------------
# The command line, in a subprocess (its real stdout and stderr encodings)


def run_cli(*args) -> subprocess.CompletedProcess:
    return helpers.run_cli(*args, text=False)  # bytes: the test decodes stderr strictly


def assert_refused(proc: subprocess.CompletedProcess, *needles: str) -> str:
    err = proc.stderr.decode("utf-8")  # strict: whatever the program printed is valid UTF-8
    assert proc.returncode == 2, err
    assert "Traceback" not in err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), err
    assert printable(lines[0], 10**6) == lines[0]
    for needle in needles:
        assert needle in lines[0], (needle, lines[0])
    return lines[0]


@fuzz(4)
@given(st.sampled_from(FIELDS).flatmap(lambda f: st.tuples(st.just(f), bad_value(f[2]))))
def test_cli_validate_and_render_refuse_a_wrong_field(tmp_path_factory, case):
    (stem, path, spec), value = case
    folder = tmp_path_factory.mktemp("cli")
    scene = folder / "scene.json"
    scene.write_text(json.dumps(set_path(DESIGNS[stem], path, value)))
    assert_refused(run_cli("validate", scene), f"{scene}: {path}")
    out = folder / "out.png"
    size = () if path.startswith("image.") else ("--width", "8", "--height", "8")  # (those would replace it)
    assert_refused(run_cli("render", scene, "-o", out, *size), f"{scene}: {path}")
    assert sorted(p.name for p in folder.iterdir()) == ["scene.json"]


@fuzz(3)
@given(st.sampled_from(["name", "description", "tags[0]", "author"]), with_surrogate(st.text(max_size=5)))
def test_cli_study_refuses_surrogates_before_rendering(tmp_path_factory, field, text):
    folder = tmp_path_factory.mktemp("study")
    doc = copy.deepcopy(DESIGNS["paper-baseline"])
    if field == "tags[0]":
        doc["tags"] = [text]
    else:
        doc[field] = text
    base = folder / "base.json"
    base.write_text(json.dumps(doc))
    out = folder / "sheet.png"
    assert_refused(run_cli("study", base, "--vary", "lens.ior=1.4,1.5", "--size", "8x8", "-o", out),
                   f"{base}: {field}: ", "lone surrogate")
    assert sorted(p.name for p in folder.iterdir()) == ["base.json"]


def test_cli_study_refuses_a_title_that_cannot_be_stored_before_rendering(tmp_path):
    base = tmp_path / "base.json"
    base.write_text(json.dumps(DESIGNS["paper-baseline"]))
    out = tmp_path / "sheet.png"
    # An undecodable byte in argv reaches Python as a lone surrogate, which no PNG or EXR header holds.
    proc = subprocess.run([sys.executable, "-m", "core_tracer", "study", str(base), "--vary", "lens.ior=1.4,1.5",
                           "--size", "8x8", "-o", str(out), "--title", os.fsdecode(b"Lamp \xff")],
                          cwd=ROOT, capture_output=True, timeout=120)
    assert_refused(proc, "title: expected a string of at most 200 Unicode characters")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["base.json"]


def test_cli_study_refuses_a_lamp_index_of_5000_digits_and_a_value_of_10_to_the_400(tmp_path):
    base = tmp_path / "base.json"
    base.write_text(json.dumps(DESIGNS["paper-baseline"]))
    out = tmp_path / "sheet.png"
    assert_refused(run_cli("study", base, "--vary", f"lamps[{'9' * 5000}].lens.ior=1.4,1.5", "-o", out),
                   "lamp index", "does not exist", "allowed 0 to 0")
    study = tmp_path / "study.json"
    study.write_text(json.dumps(_study_doc({"parameter": "lens.ior", "values": [1.5]})).replace(
        "1.5]", "1" + "0" * 400 + "]"))
    assert_refused(run_cli("study", "--study", study, "-o", out), "lens.ior", "a number of 401 digits is out of range",
                   "allowed [1, 3]")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["base.json", "study.json"]


@fuzz(2)
@given(st.lists(st.sampled_from(FIELDS).flatmap(lambda f: st.tuples(st.just(f), bad_value(f[2]))),
                min_size=10, max_size=30))
def test_cli_presets_list_a_folder_of_generated_hostile_files(tmp_path_factory, cases):
    """One `presets list` and one `presets validate` over a folder of generated bad files: each is a
    warning naming its field, the good one is listed."""
    folder = tmp_path_factory.mktemp("team")
    (folder / "good.json").write_text(json.dumps(DESIGNS["paper-baseline"]))
    expected = {}
    for k, ((stem, path, _), value) in enumerate(cases):
        name = f"bad-{k:03d}.json"
        (folder / name).write_text(json.dumps(set_path(DESIGNS[stem], path, value)))
        expected[name] = path
    proc = run_cli("presets", "list", folder)
    err = proc.stderr.decode("utf-8")
    assert proc.returncode == 0 and "Traceback" not in err, err
    assert [line.rsplit(": ", 1)[-1] for line in proc.stdout.decode().splitlines()] == ["good.json)"]
    warnings = err.strip().splitlines()
    assert len(warnings) == len(cases)
    for line in warnings:
        assert printable(line, 10**6) == line
        name = re.search(r"/(bad-\d+\.json): ", line).group(1)
        assert f"{name}: {expected[name]}" in line, line
    proc = run_cli("presets", "validate", folder)
    assert proc.returncode == 2 and f"1 valid, {len(cases)} not valid" in proc.stderr.decode()


def test_cli_echoes_a_hostile_key_escaped_and_short(tmp_path):
    scene = tmp_path / "scene.json"
    doc = copy.deepcopy(DESIGNS["paper-baseline"])
    doc["lamps"][0]["lens"]["\x1b[2J\rpwned" + "k" * 900_000] = 1
    scene.write_text(json.dumps(doc))
    line = assert_refused(run_cli("validate", scene), "lamps[0].lens.\\x1b[2J\\rpwnedkkk", "unknown key")
    assert len(line) < 600


def test_cli_lists_a_library_whose_folder_and_file_names_are_not_utf8(tmp_path):
    folder = os.path.join(os.fsencode(tmp_path), b"team \xff")
    os.mkdir(folder)
    with open(os.path.join(folder, b"red \xfe.json"), "w") as f:
        f.write(json.dumps(DESIGNS["paper-baseline"]))
    proc = subprocess.run([sys.executable.encode(), b"-m", b"core_tracer", b"presets", b"list", folder], cwd=ROOT,
                          capture_output=True, timeout=120, env=dict(os.environ, PYTHONIOENCODING="utf-8"))
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.decode("utf-8").rstrip().endswith("(team \\xff: red \\xfe.json)")

"""The docs name only files and modules that exist, the README gives the two commands, and the
scene-format reference holds the field table generated from core_tracer/scene/spec.py."""

import re

import pytest
from helpers import ROOT

from core_tracer.scene import fields_doc, spec

DOCS = sorted([ROOT / "README.md", ROOT / "CONTRIBUTING.md", ROOT / "benchmarks" / "RESULTS.md",
               *(ROOT / "docs").glob("*.md")])
CODE = re.compile(r"```[^\n]*\n(.*?)```|`([^`]+)`", re.S)  # fenced blocks, then inline code (may wrap)
PATH = re.compile(r"(?<![\w./-])((?:core_tracer|lamp_addon|tools|benchmarks|tests|docs|presets)/[\w./-]*)")
MODULE = re.compile(r"(?<![\w./-])((?:core_tracer|lamp_addon)(?:\.\w+)+)")
LINK = re.compile(r"\]\(([^)\s]+)\)")


def _code_spans(text: str) -> list[str]:
    return [fenced or inline for fenced, inline in CODE.findall(text)]


def _module_exists(dotted: str) -> bool:
    """A dotted name resolves to a module or package, and what follows it to names the module holds."""
    parts = dotted.split(".")
    where = ROOT
    for i, part in enumerate(parts):
        if (where / part / "__init__.py").is_file():
            where = where / part
            continue
        if (where / f"{part}.py").is_file():
            source, rest = (where / f"{part}.py").read_text(encoding="utf-8"), parts[i + 1:]
        else:
            source, rest = (where / "__init__.py").read_text(encoding="utf-8"), parts[i:]
        return i > 0 and all(re.search(rf"\b{re.escape(name)}\b", source) for name in rest[:1])
    return True


def missing_names(doc) -> list[str]:
    """The files, folders, modules and linked files a doc names that are not in the repository."""
    text = doc.read_text(encoding="utf-8")
    missing = []
    for span in _code_spans(text):
        for path in PATH.findall(span):
            if not (ROOT / path.rstrip("./")).exists():
                missing.append(path)
        missing += [name for name in MODULE.findall(span) if not _module_exists(name)]
    for target in LINK.findall(text):
        if "://" not in target and not (doc.parent / target.split("#")[0]).exists():
            missing.append(target)
    return missing


@pytest.mark.parametrize("doc", DOCS, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_file_and_module_a_doc_names_exists(doc):
    assert doc.is_file()
    assert missing_names(doc) == [], f"{doc.relative_to(ROOT)} names what does not exist"


def test_the_check_finds_a_missing_file_and_module(tmp_path):
    doc = tmp_path / "doc.md"
    doc.write_text("See `core_tracer/paths.py`, `core_tracer.scene.nothing`, `core_tracer.scene.spec`,\n"
                   "`core_tracer/raytrace/paths.py` and ![a picture](nowhere.png).\n"
                   "```sh\n.venv/bin/python tools/compare_preset.py presets/nothing.json\n```\n")
    assert missing_names(doc) == ["core_tracer/paths.py", "core_tracer.scene.nothing",
                                  "presets/nothing.json", "nowhere.png"]


def test_the_readme_is_short_and_points_at_the_docs():
    text = (ROOT / "README.md").read_text()
    assert len(text.splitlines()) < 200
    for doc in ("docs/user-guide.md", "docs/scene-format.md", "docs/model.md", "benchmarks/RESULTS.md",
                "CONTRIBUTING.md"):
        assert f"({doc})" in text


def test_readme_gives_the_two_commands_and_ci_runs_the_test_command():
    text = (ROOT / "README.md").read_text()
    test_command = ("tools/ensure-venv && tools/ensure-system-packages && "
                    "xvfb-run -a .venv/bin/python -m pytest tests")
    assert f"```sh\n{test_command}\n```" in text
    ci = (ROOT / ".ci" / "run").read_text()
    assert ci.rstrip().splitlines()[-1] == test_command
    assert "tools/ensure-venv && .venv/bin/python tools/compare_preset.py" in text


def test_scene_format_field_table_is_generated_from_the_spec():
    text = (ROOT / "docs" / "scene-format.md").read_text()
    table = text[text.index(fields_doc.BEGIN) + len(fields_doc.BEGIN):text.index(fields_doc.END)].strip()
    update = "python -m core_tracer.scene.fields_doc --update docs/scene-format.md"
    assert table == fields_doc.field_table(), f"run: {update}"
    for info in spec.iter_fields():
        assert f"`{info.path}`" in table

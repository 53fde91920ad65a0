"""The README documents every scene field, as declared in core_tracer/scene/spec.py."""


from helpers import ROOT

from core_tracer.scene import fields_doc, spec

README = ROOT / "README.md"


def test_readme_field_table_is_generated_from_the_spec():
    text = README.read_text()
    table = text[text.index(fields_doc.BEGIN) + len(fields_doc.BEGIN):text.index(fields_doc.END)].strip()
    assert table == fields_doc.field_table(), "run: python -m core_tracer.scene.fields_doc --update README.md"
    for info in spec.iter_fields():
        assert f"`{info.path}`" in table


def test_readme_gives_the_two_commands_and_ci_runs_the_test_command():
    text = README.read_text()
    test_command = ("tools/ensure-venv && tools/ensure-system-packages && "
                    "xvfb-run -a .venv/bin/python -m pytest tests")
    assert f"```sh\n{test_command}\n```" in text
    ci = (README.parent / ".ci" / "run").read_text()
    assert ci.rstrip().splitlines()[-1] == test_command
    assert "tools/ensure-venv && .venv/bin/python tools/compare_preset.py" in text

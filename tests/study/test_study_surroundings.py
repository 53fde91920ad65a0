"""Studies vary the surroundings like any parameter: the world by name, its strength and turn, the sun."""

from __future__ import annotations

import pytest
from helpers import BASELINE, baseline_doc, run_cli

from core_tracer.scene.reading import SceneError
from core_tracer.study import definition as st
from core_tracer.study.parameters import study_parameters

pytestmark = pytest.mark.slow


def test_the_world_varies_by_name_and_its_turn_over_a_range():
    s = st.Study.build(baseline_doc(), [st.parse_vary("environment.world=none, city,night"),
                                        st.parse_vary("environment.rotation_deg=0:90:3")])
    worlds = [v.scene["environment"]["world"] for v in s.variants]
    turns = [v.scene["environment"]["rotation_deg"] for v in s.variants]
    assert worlds == ["none", "city", "night"] * 3
    assert turns == [0.0] * 3 + [45.0] * 3 + [90.0] * 3
    assert s.variants[1].label(s) == "world=city  rotation_deg=0"


def test_study_lists_the_surroundings_and_the_sun():
    names = study_parameters()
    assert {"environment.world", "environment.strength", "environment.rotation_deg", "light.strength",
            "light.sun_color", "light.phantom", "light.follow_environment"} <= set(names)
    assert "environment.file" not in names


@pytest.mark.parametrize(("vary", "message"), [
    ("environment.world=city,moon", r'"moon" is not allowed; allowed one of "none", "city"'),
    ("environment.world=city:night:2", r"is a name; give values"),
    ("environment.strength=-1", r"out of range"),
])
def test_bad_surroundings_are_named(vary, message):
    with pytest.raises(SceneError, match=message):
        st.Study.build(baseline_doc(), [st.parse_vary(vary)])


def test_cli_study_over_the_worlds(tmp_path, world_images):
    proc = run_cli("study", BASELINE, "--vary", "environment.world=none,sunset",
                   "--size", "32x24", "--workers", "0", "-o", tmp_path / "sheet.png")
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "sheet.png").stat().st_size > 0

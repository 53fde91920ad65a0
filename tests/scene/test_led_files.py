"""An LED's files (its far field, its spectrum) are found beside the design and confined to its folder
like every file a design names (``scene.beside``): a plain name of the right suffix, a regular file,
no link out of the folder; refused in one line naming the field."""

from __future__ import annotations

import json
import os

import pytest
from helpers import PRESETS

from core_tracer.measures import export
from core_tracer.raytrace import spectral
from core_tracer.scene import beside
from core_tracer.scene.reading import SceneError
from core_tracer.scene.validate import parse_scene


def _doc(**led) -> dict:
    doc = json.loads((PRESETS / "led-stop-lamp.json").read_text())
    doc["lamps"][0]["led"].update(led)
    return doc


def _ies(path) -> None:
    import numpy as np

    c, gamma = np.arange(0.0, 360.0, 30.0), np.arange(0.0, 90.0 + 1e-9, 10.0)
    export.write_ies(export.Distribution(c, gamma, np.cos(np.radians(gamma))[None, :].repeat(len(c), 0) * 10, 30.0),
                     path)


def test_a_far_field_file_beside_the_design_is_found_by_its_full_path(tmp_path):
    _ies(tmp_path / "led.ies")
    design = tmp_path / "design.json"
    scene = beside.with_spectrum_files(design, parse_scene(_doc(distribution="file", far_field_file="led.ies")))
    assert scene["lamps"][0]["led"]["far_field_file"] == str(tmp_path / "led.ies")
    pattern = spectral.led_pattern(scene["lamps"][0], "lamps[0]")
    assert pattern.table.shape == (181, 361)


@pytest.mark.parametrize("name, message", [
    ("../led.ies", "not allowed"), ("sub/led.ies", "not allowed"), ("led.txt", "ending in .ies or .ldt"),
    ("missing.ies", "is missing"), (".hidden.ies", "not allowed"),
])
def test_far_field_names_outside_the_folder_or_of_another_kind_are_refused(tmp_path, name, message):
    with pytest.raises(SceneError, match=message) as info:
        beside.with_spectrum_files(tmp_path / "design.json",
                                   parse_scene(_doc(distribution="file", far_field_file=name))
                                   if not name.startswith(("../", "sub/", ".hidden", "led.txt")) else
                                   _unchecked(name))
    assert info.value.path == "lamps[0].led.far_field_file"


def _unchecked(name: str) -> dict:
    """The scene with a name validation refuses (as a hand-edited one would be), to show the loader refuses
    it too."""
    with pytest.raises(SceneError) as refused:
        parse_scene(_doc(distribution="file", far_field_file=name))
    assert refused.value.path == "lamps[0].led.far_field_file"
    scene = parse_scene(_doc())
    scene["lamps"][0]["led"].update(distribution="file", far_field_file=name)
    return scene


def test_a_link_out_of_the_folder_is_refused(tmp_path):
    outside = tmp_path / "outside"
    outside.mkdir()
    _ies(outside / "led.ies")
    folder = tmp_path / "design"
    folder.mkdir()
    os.symlink(outside / "led.ies", folder / "led.ies")
    with pytest.raises(SceneError, match="leads outside"):
        beside.with_spectrum_files(folder / "design.json",
                                   parse_scene(_doc(distribution="file", far_field_file="led.ies")))


def test_an_unresolved_name_is_refused_when_traced():
    scene = parse_scene(_doc(distribution="file", far_field_file="led.ies"))
    with pytest.raises(SceneError, match="not found beside the document") as info:
        spectral.led_pattern(scene["lamps"][0], "lamps[0]")
    assert info.value.path == "lamps[0].led.far_field_file"


def test_a_lambertian_led_names_no_file():
    scene = parse_scene(_doc())
    assert beside.spectrum_files("/nowhere/design.json", scene) == {}

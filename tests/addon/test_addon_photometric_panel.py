"""The photometric mode in the Lamp tab: its fields in a designer's words, shown only in that mode,
and a named bulb keeping a filament it has."""

from __future__ import annotations

import re

import pytest
from helpers import PRESETS
from test_addon_panels import draw

pytestmark = pytest.mark.blender

SNAKE = re.compile(r"\b[a-z0-9]+_[a-z0-9_]+\b")


def _photometric_rna(lamp_addon, addon_core):
    """(path, RNA property) of every photometric-only field and the light model."""
    S = addon_core.scene.spec
    light_models = addon_core.scene.light_models
    props = lamp_addon.design.properties
    groups = {"": props.LampDesign}
    out = []
    for path, section in S.iter_sections():
        if path not in groups:
            owner, _, key = path.replace("[]", "").rpartition(".")
            groups[path] = groups[owner.replace("lamps", "lamps[]") if owner else ""].bl_rna.properties[
                key].fixed_type
        for key, spec in section.fields.items():
            if isinstance(spec, (S.Section, S.ListOf)):
                continue
            if light_models.is_photometric_only(section, key) or key == "light_model":
                out.append((f"{path}.{key}".lstrip("."), groups[path].bl_rna.properties[props.property_id(key)]))
    return out


def test_photometric_fields_read_as_a_designer_says_them(lamp_addon, addon_core):
    fields = _photometric_rna(lamp_addon, addon_core)
    assert len(fields) >= 30
    for path, rna in fields:
        assert "_" not in rna.name and not rna.name.islower(), (path, rna.name)
        assert not SNAKE.search(rna.description), (path, rna.description)
        for item in getattr(rna, "enum_items", ()):
            assert "_" not in item.name and not SNAKE.search(item.description), (path, item.identifier)
    names = {path: rna.name for path, rna in fields}
    assert names["lamps[].bulb.flux_lm"] == "Flux (lm)"
    assert names["lamps[].bulb.state"] == "Filament"
    assert names["light.illuminance_lux"] == "Sun Illuminance (lx)"
    assert names["environment.luminance_cd_m2"] == "Mean Luminance (cd/m2)"
    bulb_types = {item.identifier: item.description for item in
                  lamp_addon.design.properties.LampDesign.bl_rna.properties["lamps"].fixed_type.bl_rna
                  .properties["bulb"].fixed_type.bl_rna.properties["type"].enum_items}
    assert "stop 440 lm" in bulb_types["P21/5W"] and "tail 35 lm" in bulb_types["P21/5W"]


def test_each_light_model_shows_its_own_bulb_fields(lamp_addon, addon_core, bl_scene):
    import bpy

    scene = addon_core.scene.load_scene(PRESETS / "photometric-stop-lamp.json")
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    design = bl_scene.lamp_design
    shown = draw(bpy.types.LAMP_PT_bulb, bl_scene).spec_paths()
    assert {"lamps[].bulb.type", "lamps[].bulb.state"} <= shown
    assert "lamps[].bulb.intensity" not in shown and "lamps[].bulb.flux_lm" not in shown  # the P21/5W's own
    lens = draw(bpy.types.LAMP_PT_lens, bl_scene).spec_paths()
    assert {"lamps[].lens.material", "lamps[].lens.filter", "lamps[].lens.filter_thickness"} <= lens
    assert not {"lamps[].lens.ior", "lamps[].lens.absorption", "lamps[].lens.color_mode"} & lens
    design.lamps[0].lens.material = "custom"
    assert {"lamps[].lens.ior", "lamps[].lens.abbe"} <= draw(bpy.types.LAMP_PT_lens, bl_scene).spec_paths()
    design.light_model = "paper"
    shown = draw(bpy.types.LAMP_PT_bulb, bl_scene).spec_paths()
    assert "lamps[].bulb.intensity" in shown and "lamps[].bulb.type" not in shown
    assert "lamps[].lens.filter" not in draw(bpy.types.LAMP_PT_lens, bl_scene).spec_paths()


def test_a_paper_design_says_which_photometric_values_it_ignores(lamp_addon, addon_core, bl_scene):
    """Issue 31: the panel said only "Design is valid" for a paper design with a photometric bulb."""
    import bpy

    scene = addon_core.scene.load_scene(PRESETS / "photometric-stop-lamp.json")
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    design = bl_scene.lamp_design
    assert draw(bpy.types.LAMP_PT_design, bl_scene).labels() == ["Design is valid"]  # used there
    design.light_model = "paper"
    labels = draw(bpy.types.LAMP_PT_design, bl_scene).labels()
    assert labels[0] == "Design is valid"
    note = " ".join(labels[1:])
    assert note.startswith("The paper light model ignores photometric fields:")
    assert 'Camera & Image › Exposure = "ev100"' in note and " and 2 more;" in note
    assert note.endswith('they take effect with Light Model "photometric"')
    assert not SNAKE.search(note), note  # the panel's words, no JSON keys
    lamp_addon.design.properties.scene_to_design(bl_scene, addon_core.scene.load_scene(PRESETS / "paper-baseline.json"))
    assert draw(bpy.types.LAMP_PT_design, bl_scene).labels() == ["Design is valid"]


def test_a_named_bulb_keeps_a_filament_it_has(lamp_addon, addon_core, bl_scene):
    scene = addon_core.scene.load_scene(PRESETS / "photometric-stop-lamp.json")
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    bulb = bl_scene.lamp_design.lamps[0].bulb
    assert (bulb.type, bulb.state) == ("P21/5W", "stop")
    bulb.type = "R5W"
    assert bulb.state == "on"
    bulb.type = "PY21/5W"
    assert bulb.state == "stop"
    lamp_addon.design.properties.design_to_scene(bl_scene)  # valid as it stands


def test_a_wrong_filament_is_named_in_panel_words(lamp_addon, addon_core, bl_scene):
    scene = addon_core.scene.load_scene(PRESETS / "photometric-stop-lamp.json")
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    bulb = bl_scene.lamp_design.lamps[0].bulb
    lamp_addon.design.properties.write_section(bulb, addon_core.scene.spec.BULB, {"type": "R5W"})  # as a script
    problem = lamp_addon.design.validity.status(bl_scene).problem
    assert problem is not None and problem.path == "lamps[0].bulb.state"
    # The field just changed is the one to change back (issue 24: the highlighted field fixes it); the
    # rule's own field, the filament, is named in the message as the second way out.
    assert problem.label() == "Lamp 1 › Bulb › Bulb Type"
    assert "Lamp 1 › Bulb › Filament" in problem.text()
    assert "R5W" in problem.message and '"on"' in problem.message


def test_the_study_panel_offers_bulb_type_and_lens_material(lamp_addon):
    items = {path: label for path, label, _tooltip in lamp_addon.study.settings.PARAMETER_ITEMS}
    assert items["bulb.type"] == "Bulb: Bulb Type"
    assert items["lens.material"] == "Lens: Material"
    assert items["bulb.flux_lm"] == "Bulb: Flux (lm)"
    assert items["light.illuminance_lux"] == "Light: Sun Illuminance (lx)"


@pytest.mark.parametrize("fields, path", [
    ({"type": "custom", "spectrum": "led", "led_peak_nm": 830.0, "led_width_nm": 1.0}, "lamps[0].bulb.led_peak_nm"),
    ({"type": "custom", "spectrum": "led", "led_peak_nm": 360.0, "led_width_nm": 1.0}, "lamps[0].bulb.led_peak_nm"),
])  # a bulb radius of 1e-320 cannot reach Blender: its float32 property holds 0 (clamped to its minimum)
def test_the_panel_says_what_the_render_would_refuse_in_a_spectrum(lamp_addon, addon_core, bl_scene, fields, path):
    """Issue 33: a spectrum that passed the panel crashed F12 (an LED without visible light)."""
    scene = addon_core.scene.load_scene(PRESETS / "photometric-stop-lamp.json")
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    bulb = bl_scene.lamp_design.lamps[0].bulb
    lamp_addon.design.properties.write_section(bulb, addon_core.scene.spec.BULB, fields)
    problem = lamp_addon.design.validity.status(bl_scene).problem
    assert problem is not None and problem.path == path, problem

"""The sidebar's draw code, run against a recording layout (headless Blender has no UI to draw into).

``RecordingLayout`` is a plain class with the ``UILayout`` methods the panels use; it checks each call
against Blender's real data (the property exists on the struct, the operator and the UI list are
registered) and records it. A panel calling anything else fails the test with an AttributeError.
"""

from __future__ import annotations

import re
from types import SimpleNamespace

import pytest
from helpers import PRESETS

pytestmark = pytest.mark.blender



class RecordingLayout:
    def __init__(self, log: list | None = None):
        self.log = [] if log is None else log
        self.use_property_split = False
        self.use_property_decorate = True
        self.enabled = True
        self.active = True
        self.alert = False

    def _child(self) -> RecordingLayout:
        return RecordingLayout(self.log)

    def row(self, **_kw):
        return self._child()

    def column(self, **_kw):
        return self._child()

    def box(self):
        return self._child()

    def split(self, **_kw):
        return self._child()

    def separator(self, **_kw):
        self.log.append(("separator",))

    def label(self, *, text="", icon="NONE", **_kw):
        self.log.append(("label", text, icon))

    def prop(self, data, prop, **kw):
        assert prop in data.bl_rna.properties.keys(), f"{data} has no property {prop!r}"
        self.log.append(("prop", data, prop, kw))

    def operator(self, idname, **kw):
        import bpy

        module, name = idname.split(".")
        getattr(getattr(bpy.ops, module), name).get_rna_type()  # raises KeyError when not registered
        self.log.append(("operator", idname, kw))
        return SimpleNamespace()

    def template_list(self, listtype_name, list_id, dataptr, propname, active_dataptr, active_propname, **kw):
        import bpy

        assert issubclass(getattr(bpy.types, listtype_name), bpy.types.UIList)
        assert propname in dataptr.bl_rna.properties.keys()
        assert active_propname in active_dataptr.bl_rna.properties.keys()
        self.log.append(("template_list", listtype_name, propname, active_propname))

    # What was drawn

    def props(self) -> list[tuple]:
        return [entry for entry in self.log if entry[0] == "prop"]

    def spec_paths(self) -> set[str]:
        """Drawn design properties as spec paths: ``lamp_design.lamps[2].lens.ior`` -> ``lamps[].lens.ior``."""
        out = set()
        for _, data, prop, _kw in self.props():
            path = data.path_from_id(prop)
            if path.startswith("lamp_design."):
                out.add(re.sub(r"\[\d+\]", "[]", path[len("lamp_design."):]))
        return out

    def operators(self) -> list[str]:
        return [entry[1] for entry in self.log if entry[0] == "operator"]


class PanelProxy:
    """Stands in for the panel instance: ``layout`` plus the class's own attributes."""

    def __init__(self, cls, layout):
        self._cls = cls
        self.layout = layout

    def __getattr__(self, name):
        return getattr(self._cls, name)


def draw(cls, bl_scene) -> RecordingLayout:
    layout = RecordingLayout()
    context = SimpleNamespace(scene=bl_scene)
    if hasattr(cls, "poll"):
        assert cls.poll(context)
    cls.draw(PanelProxy(cls, layout), context)
    return layout


@pytest.fixture
def S(addon_core):
    return addon_core.scene.spec


@pytest.fixture
def design(lamp_addon, addon_core, bl_scene):
    scene = addon_core.scene.load_scene(PRESETS / "four-lamp-rear-combination.json")
    lamp_addon.design_properties.scene_to_design(bl_scene, scene)
    bl_scene.lamp_design.active_lamps_index = 2
    return bl_scene.lamp_design


def _panels(lamp_addon):
    import bpy

    return [cls for cls in lamp_addon.design_panels.classes if issubclass(cls, bpy.types.Panel)]


def test_panels_are_in_the_lamp_tab(lamp_addon):
    import bpy

    panels = _panels(lamp_addon)
    assert len(panels) >= 10
    for cls in panels:
        assert getattr(bpy.types, cls.__name__) is cls  # registered
        assert (cls.bl_space_type, cls.bl_region_type, cls.bl_category) == ("VIEW_3D", "UI", "Lamp")
    roots = [cls for cls in panels if not getattr(cls, "bl_parent_id", "")]
    assert [cls.__name__ for cls in roots] == ["LAMP_PT_design"]


def test_every_parameter_is_reachable(lamp_addon, S, bl_scene, design):
    shown = set()
    for mode in ("transmitted_color", "absorption"):
        design.lamps[2].lens.color_mode = mode
        for cls in _panels(lamp_addon):
            shown |= draw(cls, bl_scene).spec_paths()
    wanted = {info.path for info in S.iter_fields() if not lamp_addon.design_properties.is_constant(info.spec)}
    assert wanted - shown == set()
    assert shown - wanted == {"lamps[].lens.color_mode"}  # the only property that is not a scene field


def test_each_sub_panel_shows_its_section(lamp_addon, S, bl_scene, design):
    import bpy

    sections = {
        "LAMP_PT_body": ("body.", S.BODY),
        "LAMP_PT_light": ("light.", S.LIGHT),
        "LAMP_PT_camera": ("camera.", S.CAMERA),
        "LAMP_PT_cuts": ("lamps[].cuts.", S.CUTS),
        "LAMP_PT_reflector": ("lamps[].reflector.", S.REFLECTOR),
        "LAMP_PT_bulb": ("lamps[].bulb.", S.BULB),
        "LAMP_PT_socket": ("lamps[].socket.", S.SOCKET),
    }
    for name, (prefix, section) in sections.items():
        shown = draw(getattr(bpy.types, name), bl_scene).spec_paths()
        assert {prefix + key for key in section.fields} <= shown, name
    assert {"image.width", "image.height"} <= draw(bpy.types.LAMP_PT_camera, bl_scene).spec_paths()
    assert "background" in draw(bpy.types.LAMP_PT_light, bl_scene).spec_paths()
    assert {"name", "author", "description", "tags"} <= draw(bpy.types.LAMP_PT_info, bl_scene).spec_paths()
    assert "lamps[].center" in draw(bpy.types.LAMP_PT_lamps, bl_scene).spec_paths()


def test_part_panels_show_the_active_lamp(lamp_addon, bl_scene, design):
    import bpy

    for index in range(len(design.lamps)):
        design.active_lamps_index = index
        for cls in (bpy.types.LAMP_PT_lens, bpy.types.LAMP_PT_cuts, bpy.types.LAMP_PT_bulb):
            for _, data, prop, _kw in draw(cls, bl_scene).props():
                assert data.path_from_id(prop).startswith(f"lamp_design.lamps[{index}].")


def test_lens_colour_mode(lamp_addon, bl_scene, design):
    import bpy

    lens = design.lamps[2].lens
    lens.color_mode = "transmitted_color"
    layout = draw(bpy.types.LAMP_PT_lens, bl_scene)
    drawn = [prop for _, _, prop, _ in layout.props()]
    assert "color_mode" in drawn
    assert {"transmitted_color", "reference_thickness"} <= set(drawn) and "absorption" not in drawn
    lens.color_mode = "absorption"
    drawn = [prop for _, _, prop, _ in draw(bpy.types.LAMP_PT_lens, bl_scene).props()]
    assert "absorption" in drawn and "transmitted_color" not in drawn


def test_lengths_are_labelled_in_mm(lamp_addon, S, bl_scene, design):
    for cls in _panels(lamp_addon):
        for _, data, prop, kw in draw(cls, bl_scene).props():
            rna = [p for p in data.bl_rna.properties if p.identifier == prop][-1]
            path = re.sub(r"\[\d+\]", "[]", data.path_from_id(prop)).removeprefix("lamp_design.")
            try:
                spec = S.lookup(path)
            except KeyError:
                continue  # not a scene field (the colour mode)
            assert "text" not in kw, path  # the property's own name (with its unit) is shown
            if getattr(spec, "unit", "") == "mm":
                assert rna.name.endswith("(mm)"), (path, rna.name)


def test_lamp_list_and_actions(lamp_addon, bl_scene, design):
    import bpy

    layout = draw(bpy.types.LAMP_PT_lamps, bl_scene)
    assert ("template_list", "LAMP_UL_lamps", "lamps", "active_lamps_index") in layout.log
    assert {"lamp.lamp_add", "lamp.lamp_remove"} <= set(layout.operators())

    row = RecordingLayout()
    lamp_ul = bpy.types.LAMP_UL_lamps
    lamp_ul.draw_item(None, SimpleNamespace(scene=bl_scene), row, design, design.lamps[1], 0, design,
                      "active_lamps_index", 1)
    assert ("label", "Lamp 2", "LIGHT_POINT") in row.log
    assert [p[2] for p in row.props()] == ["on"]

    panels = lamp_addon.design_panels
    ops = draw(bpy.types.LAMP_PT_design, bl_scene).operators()
    assert ops[0] == "lamp.build"
    assert ops == [idname for idname, _, _ in panels.ACTION_OPERATORS]
    panels.add_action("lamp.lamp_add", "Another Action", "ADD")
    try:
        assert draw(bpy.types.LAMP_PT_design, bl_scene).operators()[-1] == "lamp.lamp_add"
    finally:
        panels.remove_action("lamp.lamp_add")
    assert "lamp.lamp_add" not in draw(bpy.types.LAMP_PT_design, bl_scene).operators()


def test_empty_design(lamp_addon, bl_scene):
    """A fresh scene has no lamp: the lamp panels hide, the rest draws."""
    import bpy

    context = SimpleNamespace(scene=bl_scene)
    assert len(bl_scene.lamp_design.lamps) == 0
    for cls in _panels(lamp_addon):
        if getattr(cls, "bl_parent_id", "") == "LAMP_PT_lamps":
            assert not cls.poll(context)
        else:
            draw(cls, bl_scene)
    assert bpy.ops.lamp.lamp_add.poll() and not bpy.ops.lamp.lamp_remove.poll()
    hints = [e for e in draw(lamp_addon.design_panels.LAMP_PT_lamps, bl_scene).log if e[0] == "label"]
    assert any("Add a lamp" in e[1] for e in hints)  # the empty list says how to start

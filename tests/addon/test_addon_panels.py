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



SPEC_KEYS = {"design_name": "name"}


class RecordingLayout:
    def __init__(self, log: list | None = None):
        self.log = [] if log is None else log
        self.use_property_split = False
        self.use_property_decorate = True
        self.enabled = True
        self.active = True
        self.alert = False
        self.alignment = "EXPAND"

    def _child(self) -> RecordingLayout:
        child = RecordingLayout(self.log)
        child.alert = self.alert  # as in Blender, a sub-layout starts with its parent's alert state
        return child

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
        if self.alert:
            self.log.append(("alert label", text))

    def prop(self, data, prop, **kw):
        assert prop in data.bl_rna.properties.keys(), f"{data} has no property {prop!r}"
        if "index" in kw:
            assert 0 <= kw["index"] < data.bl_rna.properties[prop].array_length
        self.log.append(("prop", data, prop, kw))
        if self.alert:
            self.log.append(("alert prop", data, prop))

    def template_icon(self, *, icon_value, scale=1.0):
        self.log.append(("template_icon", icon_value))

    def operator(self, idname, **kw):
        import bpy

        module, name = idname.split(".")
        getattr(getattr(bpy.ops, module), name).get_rna_type()  # raises KeyError when not registered
        self.log.append(("operator", idname, kw))
        return SimpleNamespace()

    def operator_menu_enum(self, idname, property, **kw):
        import bpy

        module, name = idname.split(".")
        rna = getattr(getattr(bpy.ops, module), name).get_rna_type()  # raises KeyError when not registered
        assert property in rna.properties.keys(), f"{idname} has no property {property!r}"
        self.log.append(("operator", idname, kw))
        self.log.append(("menu", idname, property))

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
                owner, _, ident = re.sub(r"\[\d+\]", "[]", path[len("lamp_design."):]).rpartition(".")
                key = SPEC_KEYS.get(ident, ident)  # a property named apart from its field ("design_name")
                out.add(f"{owner}.{key}" if owner else key)
        return out

    def operators(self) -> list[str]:
        return [entry[1] for entry in self.log if entry[0] == "operator"]

    def alerts(self) -> tuple[list[str], list[str]]:
        """The highlighted properties (paths below ``lamp_design``) and the highlighted label texts."""
        props = [e[1].path_from_id(e[2]).removeprefix("lamp_design.") for e in self.log if e[0] == "alert prop"]
        return props, [entry[1] for entry in self.log if entry[0] == "alert label"]

    def labels(self) -> list[str]:
        return [entry[1] for entry in self.log if entry[0] == "label"]


class PanelProxy:
    """Stands in for the panel instance: ``layout`` plus the class's own attributes."""

    def __init__(self, cls, layout):
        self._cls = cls
        self.layout = layout

    def __getattr__(self, name):
        return getattr(self._cls, name)


def draw(cls, bl_scene) -> RecordingLayout:
    import bpy

    layout = RecordingLayout()
    context = SimpleNamespace(scene=bl_scene, window_manager=bpy.context.window_manager,
                              engine=bl_scene.render.engine, view_layer=bl_scene.view_layers[0])
    if hasattr(cls, "poll"):
        assert cls.poll(context)
    if hasattr(cls, "draw_header"):  # a switch in the header (Glare's), as Blender's own effects have
        cls.draw_header(PanelProxy(cls, layout), context)
    cls.draw(PanelProxy(cls, layout), context)
    return layout


@pytest.fixture
def S(addon_core):
    return addon_core.scene.spec


@pytest.fixture
def design(lamp_addon, addon_core, bl_scene):
    scene = addon_core.scene.load_scene(PRESETS / "four-lamp-rear-combination.json")
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    bl_scene.lamp_design.active_lamps_index = 2
    return bl_scene.lamp_design


def _panels(lamp_addon):
    import bpy

    return [cls for cls in lamp_addon.design.panels.classes if issubclass(cls, bpy.types.Panel)]


def test_panels_are_in_the_lamp_tab(lamp_addon):
    import bpy

    panels = _panels(lamp_addon)
    assert len(panels) >= 10
    for cls in panels:
        assert getattr(bpy.types, cls.__name__) is cls  # registered
        assert (cls.bl_space_type, cls.bl_region_type, cls.bl_category) == ("VIEW_3D", "UI", "Lamp")
    roots = [cls for cls in panels if not getattr(cls, "bl_parent_id", "")]
    assert [cls.__name__ for cls in roots] == ["LAMP_PT_design"]


def _shown_panels(lamp_addon, bl_scene) -> list:
    import bpy

    context = SimpleNamespace(scene=bl_scene, window_manager=bpy.context.window_manager,
                              engine=bl_scene.render.engine, view_layer=bl_scene.view_layers[0])
    return [cls for cls in _panels(lamp_addon) if not hasattr(cls, "poll") or cls.poll(context)]


# The photometric mode's choices that show further fields: (light model, bulb type, spectrum,
# material, filter, environment brightness by), each value of each choice at least once.
PHOTOMETRIC_CHOICES = (("paper", "custom", "incandescent", "pmma", "red", "illuminance"),
                       ("photometric", "custom", "led", "custom", "custom", "illuminance"),
                       ("photometric", "custom", "file", "pmma", "file", "luminance"),
                       ("photometric", "P21/5W", "incandescent", "polycarbonate", "clear", "illuminance"))


@pytest.mark.slow
def test_every_parameter_is_reachable(lamp_addon, S, bl_scene, design):
    shown = set()
    lamp = design.lamps[2]
    for model, bulb_type, spectrum, material, filter_kind, scale_by in PHOTOMETRIC_CHOICES:
        design.light_model = model
        lamp.bulb.type, lamp.bulb.spectrum = bulb_type, spectrum
        for part in (lamp.lens, lamp.prism_plate, lamp.light_guide):
            part.material, part.filter = material, filter_kind
        design.environment.scale_by = scale_by
        for collection, mode, outline, shape in (("reflector", "transmitted_color", "round", "flat"),
                                                 ("reflector", "absorption", "rectangular", "cylindrical"),
                                                 ("prism_plate", "absorption", "round", "flat")):
            lamp.collection = collection
            lamp.lens.color_mode = mode
            lamp.lens.outline = outline
            lamp.lens.shape = shape
            lamp.light_guide.section = "round" if outline == "round" else "rectangular"  # each its own sizes
            lamp.light_guide.path = "straight" if outline == "round" else "arc"  # an arc's radius and sweep
            design.environment.world = "none" if outline == "round" else "file"  # the file row shows only then
            for cut_type in S.CUT_TYPES:  # each type shows its own fields
                lamp.cuts.type = cut_type
                # the lamp's source: the bulb's sections or the LEDs' (their spectrum and far field as the bulb's)
                lamp.source = "led" if cut_type == "sawtooth" else "bulb"
                lamp.led.spectrum = spectrum if spectrum in S.LED_SPECTRA else "red_led"
                lamp.led.distribution = "file" if filter_kind == "file" else "lambertian"
                for cls in _shown_panels(lamp_addon, bl_scene):
                    shown |= draw(cls, bl_scene).spec_paths()
    wanted = {info.path for info in S.iter_fields() if not lamp_addon.design.properties.is_constant(info.spec)}
    assert wanted - shown == set()
    assert shown - wanted == {"lamps[].lens.color_mode"}  # the only property that is not a scene field


def test_each_sub_panel_shows_its_section(lamp_addon, addon_core, S, bl_scene, design):
    import bpy

    sections = {
        "LAMP_PT_body": ("body.", S.BODY),
        "LAMP_PT_light": ("light.", S.LIGHT),
        "LAMP_PT_camera": ("camera.", S.CAMERA),
        "LAMP_PT_reflector": ("lamps[].reflector.", S.REFLECTOR),
        "LAMP_PT_bulb": ("lamps[].bulb.", S.BULB),
        "LAMP_PT_socket": ("lamps[].socket.", S.SOCKET),
    }
    light_models = addon_core.scene.light_models
    for model in ("paper", "photometric"):  # each shows the fields its light model uses, and only those
        design.light_model = model
        ignored = light_models.is_paper_only if model == "photometric" else light_models.is_photometric_only
        for name, (prefix, section) in sections.items():
            shown = draw(getattr(bpy.types, name), bl_scene).spec_paths()
            conditional = {key for key, _choice, _values in section.shown_when}  # shown for some choices
            assert {prefix + key for key in section.fields
                    if key not in conditional and not ignored(section, key)} <= shown, (model, name)
            assert not {prefix + key for key in section.fields if ignored(section, key)} & shown, (model, name)
        assert "light_model" in draw(bpy.types.LAMP_PT_light, bl_scene).spec_paths()
    design.light_model = "paper"
    cuts = set()
    for cut_type in S.CUT_TYPES:  # the cut type, then only the fields that type uses
        design.lamps[2].cuts.type = cut_type
        shown = draw(bpy.types.LAMP_PT_cuts, bl_scene).spec_paths()
        assert shown == {f"lamps[].cuts.{key}" for key in ("type", *S.CUT_TYPE_FIELDS[cut_type])}, cut_type
        cuts |= shown
    assert cuts == {f"lamps[].cuts.{key}" for key in S.CUTS.fields}
    assert {"image.width", "image.height"} <= draw(bpy.types.LAMP_PT_camera, bl_scene).spec_paths()
    assert "background" in draw(bpy.types.LAMP_PT_light, bl_scene).spec_paths()
    assert {"name", "author", "description", "tags"} <= draw(bpy.types.LAMP_PT_info, bl_scene).spec_paths()
    assert "lamps[].center" in draw(bpy.types.LAMP_PT_lamps, bl_scene).spec_paths()


def test_the_collection_shows_the_reflector_or_the_prism_plate_panel(lamp_addon, bl_scene, design):
    import bpy

    assert bpy.types.LAMP_PT_reflector in _shown_panels(lamp_addon, bl_scene)
    assert bpy.types.LAMP_PT_prism_plate not in _shown_panels(lamp_addon, bl_scene)
    design.lamps[2].collection = "prism_plate"
    shown = _shown_panels(lamp_addon, bl_scene)
    assert bpy.types.LAMP_PT_prism_plate in shown and bpy.types.LAMP_PT_reflector not in shown
    paths = draw(bpy.types.LAMP_PT_prism_plate, bl_scene).spec_paths()
    assert {f"lamps[].prism_plate.{key}" for key in ("gap", "thickness", "focal_length", "pitch", "ior",
                                                      "absorption", "housing_depth", "housing_color")} <= paths
    assert "lamps[].collection" in draw(bpy.types.LAMP_PT_lamps, bl_scene).spec_paths()


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


def test_lens_outline_rows(lamp_addon, bl_scene, design):
    # the outline choice, then the radius of a round lens or the width, height and corner radius of a
    # rectangular one, never both
    import bpy

    lens = design.lamps[2].lens
    design.active_lamps_index = 2
    lens.outline = "round"
    drawn = [prop for _, _, prop, _ in draw(bpy.types.LAMP_PT_lens, bl_scene).props()]
    assert "outline" in drawn and "radius" in drawn
    assert not {"width", "height", "corner_radius"} & set(drawn)
    lens.outline = "rectangular"
    drawn = [prop for _, _, prop, _ in draw(bpy.types.LAMP_PT_lens, bl_scene).props()]
    assert {"outline", "width", "height", "corner_radius"} <= set(drawn) and "radius" not in drawn
    assert drawn.index("outline") < drawn.index("width")


def test_the_light_panel_leaves_out_what_the_environment_gives(lamp_addon, bl_scene, design):
    # Following the environment's sun, its direction (or colour) comes from the image: the field
    # that would be ignored is not drawn, the other stays.
    import bpy

    def drawn() -> set[str]:
        return draw(bpy.types.LAMP_PT_light, bl_scene).spec_paths()

    assert {"light.direction", "light.sun_color"} <= drawn()
    design.light.follow_environment = True
    assert "light.direction" not in drawn() and "light.sun_color" in drawn()
    design.light.follow_environment_color = True
    assert not {"light.direction", "light.sun_color"} & drawn()
    design.light.follow_environment = False
    assert "light.direction" in drawn() and "light.sun_color" not in drawn()
    assert {"light.strength", "light.follow_environment", "light.follow_environment_color"} <= drawn()


def test_lens_shape_rows(lamp_addon, bl_scene, design):
    # the shape choice, then the cylinder's radius and side only for a cylindrical lens
    import bpy

    lens = design.lamps[2].lens
    design.active_lamps_index = 2
    lens.shape = "flat"
    drawn = [prop for _, _, prop, _ in draw(bpy.types.LAMP_PT_lens, bl_scene).props()]
    assert "shape" in drawn and not {"wrap_radius", "wrap_toward"} & set(drawn)
    lens.shape = "cylindrical"
    drawn = [prop for _, _, prop, _ in draw(bpy.types.LAMP_PT_lens, bl_scene).props()]
    assert drawn.index("shape") < drawn.index("wrap_radius") < drawn.index("wrap_toward")


@pytest.mark.parametrize("mode", ["transmitted_color", "absorption"])
@pytest.mark.parametrize("collection", ["reflector", "prism_plate"])
def test_lengths_are_labelled_in_mm(lamp_addon, S, bl_scene, design, mode, collection):
    design.lamps[2].lens.color_mode = mode
    design.lamps[2].collection = collection
    for cls in _shown_panels(lamp_addon, bl_scene):
        for _, data, prop, kw in draw(cls, bl_scene).props():
            rna = [p for p in data.bl_rna.properties if p.identifier == prop][-1]
            path = re.sub(r"\[\d+\]", "[]", data.path_from_id(prop)).removeprefix("lamp_design.")
            try:
                spec = S.lookup(path)
            except KeyError:
                continue  # not a scene field (the colour mode)
            if "index" in kw:  # one channel of absorption: "Absorption (1/mm) R", "G", "B"
                assert kw["text"] in (f"{rna.name} R", "G", "B"), (path, kw["text"])
            else:
                header_switch = hasattr(cls, "draw_header") and rna.type == "BOOLEAN" and kw.get("text") == ""
                assert "text" not in kw or header_switch, path  # the property's own name (with its unit) is shown,
                # or a switch in the panel's header, named by the panel's title (Glare)
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

    actions = lamp_addon.actions
    ops = draw(bpy.types.LAMP_PT_design, bl_scene).operators()
    assert ops[0] == "lamp.build"
    assert ops == [idname for idname, _, _ in actions.ACTION_OPERATORS]
    actions.add_action("lamp.lamp_add", "Another Action", "ADD")
    try:
        assert draw(bpy.types.LAMP_PT_design, bl_scene).operators()[-1] == "lamp.lamp_add"
    finally:
        actions.remove_action("lamp.lamp_add")
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
    hints = [e for e in draw(lamp_addon.design.panels.LAMP_PT_lamps, bl_scene).log if e[0] == "label"]
    assert any("Add a lamp" in e[1] for e in hints)  # the empty list says how to start


def test_absorption_is_labelled_rgb(lamp_addon, bl_scene, design):
    import bpy

    design.lamps[2].lens.color_mode = "absorption"
    drawn = [kw for _, _, prop, kw in draw(bpy.types.LAMP_PT_lens, bl_scene).props() if prop == "absorption"]
    assert [kw["index"] for kw in drawn] == [0, 1, 2]
    assert [kw["text"] for kw in drawn] == ["Absorption (1/mm) R", "G", "B"]


# ---------------------------------------------------------------------------------------------
# Every panel of the add-on


def _addon_panels(addon) -> list[type]:
    """Every registered Panel class that comes from the add-on, found through Blender's class tree."""
    import bpy

    def subclasses(cls):
        for sub in cls.__subclasses__():
            yield sub
            yield from subclasses(sub)

    return sorted({cls for cls in subclasses(bpy.types.Panel) if cls.__module__.startswith(addon + ".")
                   and getattr(bpy.types, cls.__name__, None) is cls}, key=lambda c: c.__name__)


@pytest.mark.slow
def test_every_panel_of_the_addon_is_drawn(addon, lamp_addon, bl_scene, design):
    import bpy

    assert bpy.ops.lamp.preset_refresh() == {"FINISHED"}  # the preset browser lists (no listing: one line)
    bl_scene.render.engine = lamp_addon.render.engine.ENGINE_ID  # the passes panel shows for this engine
    wm = bpy.context.window_manager
    wm.lamp_presets_index = 0
    panels = _addon_panels(addon)
    names = {cls.__name__ for cls in panels}
    assert {"LAMP_PT_design", "LAMP_PT_presets", "LAMP_PT_study", "LAMP_PT_lens"} <= names
    drawn = set()
    context = SimpleNamespace(scene=bl_scene, window_manager=wm, engine=bl_scene.render.engine,
                              view_layer=bl_scene.view_layers[0])
    for collection, source, model in (("reflector", "bulb", "paper"), ("prism_plate", "led", "photometric")):
        design.lamps[2].collection = collection  # each shows its own sub-panel
        design.lamps[2].source = source
        design.light_model = model  # the light guide's panel shows in the photometric mode
        for cls in panels:
            if hasattr(cls, "poll") and not cls.poll(context):
                continue
            layout = draw(cls, bl_scene)
            assert layout.log, f"{cls.__name__} drew nothing"
            drawn.add(cls.__name__)
    assert drawn == names
    presets = draw(bpy.types.LAMP_PT_presets, bl_scene)
    assert ("template_list", "LAMP_UL_presets", "lamp_presets", "lamp_presets_index") in presets.log
    assert "lamp.preset_apply" in presets.operators()
    study = draw(bpy.types.LAMP_PT_study, bl_scene)
    assert "lamp.study_run" in study.operators()
    assert {p for _, _, p, _ in study.props()} >= {"parameter", "use_axis_2", "width", "height", "workers"}


def test_preferences_draw(addon, lamp_addon):
    import bpy

    prefs = bpy.context.preferences.addons[addon].preferences
    layout = RecordingLayout()
    type(prefs).draw(PanelProxy(type(prefs), layout), bpy.context)
    assert ("template_list", "LAMP_UL_library_folders", "library_folders", "active_library_folder_index") in layout.log


# ---------------------------------------------------------------------------------------------
# The design's validity, as the panel shows it


def _status(bl_scene):
    import bpy

    return draw(bpy.types.LAMP_PT_design, bl_scene)


def test_a_valid_design_says_so(lamp_addon, bl_scene, design):
    layout = _status(bl_scene)
    assert ("label", "Design is valid", "CHECKMARK") in layout.log
    assert layout.alerts() == ([], [])


def _baseline(lamp_addon, addon_core, bl_scene):
    scene = addon_core.scene.load_scene(PRESETS / "paper-baseline.json")
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    return bl_scene.lamp_design


NUMBER = r"-?[0-9.]+(?:e[-+]?[0-9]+)?"

# Invalid edits a designer makes in the panel: (edit, the property the panel must highlight, words of the message).
INVALID_EDITS = {
    "shrunk body": (lambda d: setattr(d.body, "size", (80.0, 30.0)), "body.size", "cannot hold the lens"),
    "bulb moved back": (lambda d: setattr(d.lamps[0].bulb, "offset", (0.0, 30.0, 0.0)), "lamps[0].bulb.offset",
                        "outside the reflector"),
    "bulb moved sideways": (lambda d: setattr(d.lamps[0].bulb, "offset", (40.0, 0.0, 0.0)),
                            "lamps[0].bulb.offset", "up to"),
    "bulb too big": (lambda d: setattr(d.lamps[0].bulb, "radius", 30.0), "lamps[0].bulb.radius", "does not fit"),
    "cut height 100": (lambda d: setattr(d.lamps[0].cuts, "height", 100.0), "lamps[0].cuts.height",
                       "for pitch 9"),
    "lens outside the body": (lambda d: setattr(d.lamps[0], "center", (80.0, 0.0)), "lamps[0].center",
                              "outside the body"),
    "reflector deeper than the body": (lambda d: setattr(d.lamps[0].reflector, "focal_length", 5.0),
                                       "lamps[0].reflector.focal_length", "deeper than the body"),
    "negative lens thickness": (lambda d: setattr(d.lamps[0].lens, "thickness", -2.0), "lamps[0].lens.thickness",
                                "-2.0 is out of range"),
    "prism plate focus too near": (lambda d: (setattr(d.lamps[0], "collection", "prism_plate"),
                                              setattr(d.lamps[0].prism_plate, "focal_length", 30.0)),
                                   "lamps[0].prism_plate.focal_length", "cannot bend it parallel"),
    "prism plate housing deeper than the body": (lambda d: (setattr(d.lamps[0], "collection", "prism_plate"),
                                                            setattr(d.lamps[0].prism_plate, "housing_depth", 75.0)),
                                                 "lamps[0].prism_plate.housing_depth", "deeper than the body"),
}


@pytest.mark.parametrize("case", sorted(INVALID_EDITS))
def test_an_invalid_edit_names_the_field_with_a_range_that_is_not_empty(lamp_addon, addon_core, bl_scene, case):
    import bpy

    edit, field, words = INVALID_EDITS[case]
    design = _baseline(lamp_addon, addon_core, bl_scene)
    edit(design)
    props, labels = _status(bl_scene).alerts()
    assert props == [field]  # the field to change, drawn highlighted under the message
    message = " ".join(labels[1:])
    assert words in message
    allowed = message[message.index("allowed"):]
    ranges = re.findall(rf"[\[(]({NUMBER}), ({NUMBER})[\])]", allowed) + re.findall(rf"up to ({NUMBER})()", allowed)
    assert ranges, message
    for lo, hi in ranges:
        assert not hi or float(lo) <= float(hi), message
    # The same field is highlighted where the lamp's or the body's panel draws it.
    design.active_lamps_index = 0
    panel = {"body": "LAMP_PT_body", "center": "LAMP_PT_lamps"}.get(field.split(".")[-1] if "center" in field
                                                                   else field.split(".")[0], None)
    if panel is None:
        panel = f"LAMP_PT_{field.split('.')[1]}"
    sub_props, sub_labels = draw(getattr(bpy.types, panel), bl_scene).alerts()
    assert sub_props == [field] and " ".join(sub_labels) == message


def test_the_cut_height_panel_states_the_limit_of_the_pitch(lamp_addon, addon_core, bl_scene):
    import bpy

    design = _baseline(lamp_addon, addon_core, bl_scene)
    height = design.lamps[0].cuts.bl_rna.properties["height"]
    assert height.soft_max == 100.0  # a property's range is fixed: the panel states the real limit
    labels = draw(bpy.types.LAMP_PT_cuts, bl_scene).labels()
    assert "At most 6.363 mm for pitch 9 mm (pitch / sqrt 2)" in labels
    design.lamps[0].cuts.pitch = 4.0
    assert "At most 2.828 mm for pitch 4 mm (pitch / sqrt 2)" in draw(bpy.types.LAMP_PT_cuts, bl_scene).labels()
    assert "at most pitch / sqrt 2" in height.description


def test_validity_is_checked_once_per_design(lamp_addon, addon_core, bl_scene, monkeypatch):
    validity = lamp_addon.design.validity
    design = _baseline(lamp_addon, addon_core, bl_scene)
    calls = []
    real = validity._check
    monkeypatch.setattr(validity, "_check", lambda *args: calls.append(1) or real(*args))
    validity._memo.update(key=None, status=None)
    for _ in range(5):
        _status(bl_scene)
    assert len(calls) == 1
    design.lamps[0].cuts.height = 2.0
    _status(bl_scene)
    assert len(calls) == 2


def test_add_lamp_is_not_greyed_out_by_another_error(lamp_addon, addon_core, bl_scene):
    import bpy

    design = _baseline(lamp_addon, addon_core, bl_scene)
    design.lamps[0].cuts.height = 100.0  # invalid, but nothing to do with adding a lamp
    assert bpy.ops.lamp.lamp_add.poll()
    assert bpy.ops.lamp.lamp_add() == {"FINISHED"}
    assert len(design.lamps) == 2
    props, _ = _status(bl_scene).alerts()
    assert props == ["lamps[0].cuts.height"]  # the design's own error is still the one shown
    for _ in range(2):
        assert bpy.ops.lamp.lamp_add() == {"FINISHED"}
    assert not bpy.ops.lamp.lamp_add.poll()
    with pytest.raises(RuntimeError, match="at most 4 lamps"):
        bpy.ops.lamp.lamp_add()


def test_add_lamp_says_when_the_body_cannot_grow(lamp_addon, addon_core, bl_scene):
    import bpy

    design = _baseline(lamp_addon, addon_core, bl_scene)
    design.lamps[0].cuts.height = 100.0  # another error as well
    design.body.size = (9990.0, 120.0)
    assert not bpy.ops.lamp.lamp_add.poll()
    with pytest.raises(RuntimeError, match=r"the body would need 10085 mm; body\.size allows up to 10000"):
        bpy.ops.lamp.lamp_add()


# ---------------------------------------------------------------------------------------------
# The lamp's function


def test_choosing_a_function_sets_its_defaults_and_names(lamp_addon, addon_core, bl_scene):
    import bpy

    design = _baseline(lamp_addon, addon_core, bl_scene)
    lamp = design.lamps[0]
    assert lamp.function == "custom" and lamp.lens.color_mode == "absorption"  # the old preset, unchanged
    assert "function" in {p for _, _, p, _ in draw(bpy.types.LAMP_PT_lamps, bl_scene).props()}
    items = {item.identifier: item.description for item in lamp.bl_rna.properties["function"].enum_items}
    assert items["stop"] == "Red lens, bulb intensity 20/17.5/15"  # each choice says what it sets
    lamp.function = "stop"
    assert lamp.lens.color_mode == "transmitted_color"
    red = tuple(lamp.lens.transmitted_color)
    assert red[0] > 0.9 and max(red[1:]) < 0.02
    assert lamp.lens.reference_thickness == pytest.approx(lamp.lens.thickness)
    stop = tuple(lamp.bulb.intensity)
    lamp.function = "tail"
    assert sum(lamp.bulb.intensity) < sum(stop)  # a stop lamp is brighter than a tail lamp
    lamp.function = "turn"
    r, g, b = lamp.lens.transmitted_color
    assert r > g > b  # amber
    lamp.function = "reversing"
    assert min(lamp.lens.transmitted_color) > 0.9  # clear
    lamp.function = "stop"
    row = RecordingLayout()
    bpy.types.LAMP_UL_lamps.draw_item(None, SimpleNamespace(scene=bl_scene), row, design, lamp, 0, design,
                                      "active_lamps_index", 0)
    assert ("label", "Stop", "LIGHT_POINT") in row.log  # the list names the lamp as its parts are named
    assert bpy.ops.lamp.build() == {"FINISHED"}
    assert "Stop Lens" in bpy.data.objects and "Stop Bulb" in bpy.data.objects
    lamp.bulb.intensity = (1.0, 2.0, 3.0)
    lamp.function = "custom"  # custom keeps what is there
    assert tuple(lamp.bulb.intensity) == (1.0, 2.0, 3.0)


def test_a_preset_with_a_function_keeps_its_own_values(lamp_addon, addon_core, bl_scene):
    scene = addon_core.scene.load_scene(PRESETS / "paper-baseline.json")
    scene["lamps"][0]["function"] = "stop"
    scene["lamps"][0]["bulb"]["intensity"] = [1.0, 2.0, 3.0]
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    lamp = bl_scene.lamp_design.lamps[0]
    assert lamp.function == "stop" and tuple(lamp.bulb.intensity) == (1.0, 2.0, 3.0)
    assert lamp.lens.color_mode == "absorption"
    assert lamp_addon.design.properties.design_to_scene(bl_scene) == addon_core.scene.normalize(scene)


def test_a_new_design_starts_with_the_colour_picker(lamp_addon, bl_scene):
    import bpy

    assert bpy.ops.lamp.lamp_add() == {"FINISHED"}
    assert bl_scene.lamp_design.lamps[0].lens.color_mode == "transmitted_color"


def test_tooltips_say_what_a_field_does_first(lamp_addon, bl_scene):

    assert lamp_addon.design.properties.RESERVED_KEYS == {v: k for k, v in SPEC_KEYS.items()}
    design = bl_scene.lamp_design.bl_rna.properties
    assert design["design_name"].description.startswith("The design's name")  # not Blender's generic text
    info = draw(lamp_addon.design.panels.LAMP_PT_info, bl_scene)
    assert "design_name" in [p for _, _, p, _ in info.props()]
    bl_scene.lamp_design["name"] = "Saved before"  # where a file of an earlier version keeps the name
    assert bl_scene.lamp_design.design_name == "Saved before"
    assert lamp_addon.design.properties.design_document(bl_scene)["name"] == "Saved before"
    body = bl_scene.lamp_design.body.bl_rna.properties
    assert body["specular"].description == ("How strongly the body reflects the light as a highlight. Allowed: "
                                            "from 0 to 1. Paper: w in eq. 1")  # the paper's symbol last


def test_the_bulb_panel_states_where_the_bulb_fits(lamp_addon, addon_core, bl_scene):
    import bpy

    design = _baseline(lamp_addon, addon_core, bl_scene)
    labels = draw(bpy.types.LAMP_PT_bulb, bl_scene).labels()
    radius = next(t for t in labels if t.startswith("At most") and "where the bulb sits" in t)
    depth = next(t for t in labels if t.startswith("Y in ["))
    lo, hi = (float(v) for v in re.search(rf"\[({NUMBER}), ({NUMBER})\]", depth).groups())
    assert lo < 0 < hi  # the focus, where the bulb sits, is inside the range
    design.lamps[0].bulb.offset = (0.0, hi, 0.0)  # the stated limit is allowed ...
    assert ("label", "Design is valid", "CHECKMARK") in _status(bl_scene).log
    design.lamps[0].bulb.offset = (0.0, hi + 0.01, 0.0)  # ... and just past it is not
    assert _status(bl_scene).alerts()[0] == ["lamps[0].bulb.offset"]
    design.lamps[0].bulb.offset = (0.0, 0.0, 0.0)
    r = float(re.search(rf"At most ({NUMBER}) mm", radius)[1])
    design.lamps[0].bulb.radius = r
    assert ("label", "Design is valid", "CHECKMARK") in _status(bl_scene).log

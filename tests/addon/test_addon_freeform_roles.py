"""Lamp roles on mesh objects: properties generated from the spec's role sections, the operators that
assign and clear them, the part documents they make, and the Free-form Parts panel's draw code."""

from __future__ import annotations

import pytest
from test_addon_panels import PanelProxy, RecordingLayout

pytestmark = pytest.mark.blender


def _mesh(name: str, location=(0.0, 0.0, 0.0)):
    import bpy

    bpy.ops.mesh.primitive_cube_add(size=0.02, location=location)
    obj = bpy.context.active_object
    obj.name = name
    return obj


def _select_only(*objects) -> None:
    import bpy

    for obj in bpy.context.scene.objects:
        obj.select_set(obj in objects)
    bpy.context.view_layer.objects.active = objects[0] if objects else None


def test_every_role_field_is_a_property_with_the_spec_default(lamp_addon, addon_core):
    import bpy

    S = addon_core.scene.spec
    group = bpy.types.Object.bl_rna.properties["lamp_role"].fixed_type
    assert [item.identifier for item in group.properties["role"].enum_items] == ["NONE", *S.FREEFORM_ROLES]
    for role, section in S.FREEFORM_ROLE_SECTIONS.items():
        values = group.properties[role].fixed_type.properties
        for key, spec in section.fields.items():
            prop = values[key]
            if isinstance(spec, S.Num) and spec.size == 1:
                assert prop.default == pytest.approx(spec.default), (role, key)
                lo, hi = lamp_addon.design.properties.blender_range(spec)
                assert (prop.soft_min, prop.soft_max) == pytest.approx((lo, hi)), (role, key)
            elif isinstance(spec, S.Num):
                assert tuple(prop.default_array) == pytest.approx(spec.default), (role, key)
            elif isinstance(spec, S.Flag):
                assert prop.default == spec.default
        for rule in section.one_of:
            assert values[f"{rule.name}_mode"].default == rule.preferred


def test_assign_and_clear(lamp_addon, bl_scene):
    import bpy

    a, b, c = _mesh("Lens A"), _mesh("Reflector B"), _mesh("Other C")
    _select_only(a)
    assert bpy.ops.lamp.role_assign(role="lens") == {"FINISHED"}
    _select_only(b)
    assert bpy.ops.lamp.role_assign(role="reflector", material=False) == {"FINISHED"}
    assert [o.name for o in lamp_addon.freeform.properties.role_objects(bl_scene)] == ["Lens A", "Reflector B"]
    assert c.lamp_role.role == "NONE"
    # The lens got its Cycles material, the reflector kept what it had (nothing).
    mat = lamp_addon.freeform.materials.role_material(a)
    assert mat is not None and mat.node_tree.nodes["Lens BSDF"].inputs["IOR"].default_value == pytest.approx(1.49)
    assert len(b.material_slots) == 0
    doc = lamp_addon.freeform.properties.part_document(a)
    assert doc["object"] == "Lens A" and doc["role"] == "lens"
    photometric = {"material", "abbe", "filter", "filter_edge_nm", "filter_slope_nm", "filter_range", "filter_file",
                   "filter_thickness"}  # the lens's plastic and filter (docs/photometric.md, "Free-form parts")
    assert set(doc["lens"]) == {"ior", "transmitted_color", "reference_thickness", "diffuse_color", "specular",
                                "shininess"} | photometric  # the preferred colour form, the picker
    a.lamp_role.lens.ior = 1.6
    assert lamp_addon.freeform.properties.part_document(a)["lens"]["ior"] == 1.6
    assert bpy.ops.lamp.role_clear(object_name="Lens A") == {"FINISHED"}
    assert a.lamp_role.role == "NONE"
    assert a.lamp_role.lens.ior == pytest.approx(1.6)  # values stay for when the role comes back
    assert {"REGISTER", "UNDO"} <= bpy.types.LAMP_OT_role_assign.bl_options
    assert {"REGISTER", "UNDO"} <= bpy.types.LAMP_OT_role_clear.bl_options


def test_built_parts_and_non_meshes_are_refused(lamp_addon, addon_core, bl_scene):
    import bpy
    from helpers import BASELINE

    lamp_addon.design.properties.scene_to_design(bl_scene, addon_core.scene.load_scene(BASELINE))
    assert bpy.ops.lamp.build() == {"FINISHED"}
    lens = next(o for o in bl_scene.objects if o.get("lamp_part") == "lamps[0].lens")
    _select_only(lens)
    with pytest.raises(RuntimeError, match="Convert to Free-form"):
        bpy.ops.lamp.role_assign(role="lens")
    assert lens.lamp_role.role == "NONE"
    bpy.ops.object.empty_add()
    _select_only(bpy.context.active_object)
    assert not bpy.ops.lamp.role_assign.poll()


def test_role_value_out_of_range_is_named_with_the_object(lamp_addon, addon_core, bl_scene):
    from helpers import BASELINE

    lamp_addon.design.properties.scene_to_design(bl_scene, addon_core.scene.load_scene(BASELINE))
    obj = _mesh("My Lens")
    lamp_addon.freeform.properties.set_role(obj, "lens")
    assert lamp_addon.freeform.status.part_problem(bl_scene) is None
    obj.lamp_role.lens["ior"] = 0.5  # below the spec's 1, as an old file or a script may store it
    problem = lamp_addon.freeform.status.part_problem(bl_scene)
    assert problem.startswith('"My Lens" lens.ior: 0.5') and "allowed [1, 3]" in problem


def _draw_panel(bl_scene):
    from types import SimpleNamespace

    import bpy

    layout = RecordingLayout()
    context = SimpleNamespace(scene=bl_scene, window_manager=bpy.context.window_manager)
    cls = bpy.types.LAMP_PT_freeform
    cls.draw(PanelProxy(cls, layout), context)
    return layout


def test_panel_lists_parts_and_shows_the_selected_role(lamp_addon, addon_core, bl_scene):
    S = addon_core.scene.spec
    empty = _draw_panel(bl_scene)
    assert ("template_list", "LAMP_UL_role_objects", "objects", "lamp_role_index") in empty.log
    assert "Select mesh objects and give them a role with +" in empty.labels()
    assert {"lamp.role_assign", "lamp.role_clear", "lamp.freeform_convert", "lamp.freeform_export"} <= set(
        empty.operators())
    obj = _mesh("Lens")
    lamp_addon.freeform.properties.set_role(obj, "lens")
    bl_scene.lamp_role_index = list(bl_scene.objects).index(obj)
    for mode in ("transmitted_color", "absorption"):
        obj.lamp_role.lens.color_mode = mode
        shown = {prop for _, data, prop, _kw in _draw_panel(bl_scene).props() if data == obj.lamp_role.lens}
        lens = S.FREEFORM_ROLE_SECTIONS["lens"]
        form = lens.one_of[0].alternative(mode).keys
        # the paper model's fields (a new scene's light model) and those the role's choices call for
        def value_of(key):
            return getattr(obj.lamp_role.lens, key)

        always = {k for k in lens.fields if lens.rule_of(k) is None and lens.shown(k, value_of)
                  and addon_core.scene.light_models.used(lens, k, "paper", value_of)}
        assert shown == always | set(form) | {"color_mode"}
        assert "ior" in shown and "filter" not in shown  # the photometric fields are the other model's
    bl_scene.lamp_design.light_model = "photometric"
    shown = {prop for _, data, prop, _kw in _draw_panel(bl_scene).props() if data == obj.lamp_role.lens}
    assert {"material", "filter", "filter_thickness"} <= shown and not {"ior", "absorption", "abbe"} & shown


def test_editing_a_role_value_tells_no_design_listener(lamp_addon, bl_scene):
    """A role's values belong to its object, not to the scene's design: an edit of them is not a design
    edit (the listeners take a scene; an object made them fail in every role edit's update)."""
    obj = _mesh("Lens")
    lamp_addon.freeform.properties.set_role(obj, "lens")
    heard = []
    lamp_addon.design.properties.EDIT_LISTENERS.append(heard.append)
    try:
        lamp_addon.design.properties._edited(obj.lamp_role.lens, None)
        lamp_addon.design.properties._edited(bl_scene.lamp_design, None)
    finally:
        lamp_addon.design.properties.EDIT_LISTENERS.remove(heard.append)
    assert heard == [bl_scene]


def test_role_list_filters_to_parts(lamp_addon, bl_scene):
    import bpy

    a = _mesh("Zed")
    _mesh("Alpha")
    lamp_addon.freeform.properties.set_role(a, "body")
    ui_list = bpy.types.LAMP_UL_role_objects
    flags, _order = ui_list.filter_items(ui_list, bpy.context, bl_scene, "objects")
    shown = [obj.name for obj, flag in zip(bl_scene.objects, flags, strict=True) if flag]
    assert shown == ["Zed"]


@pytest.mark.slow
def test_registration_is_symmetric_and_keeps_the_roles(lamp_addon, bl_scene):
    import bpy

    obj = _mesh("Kept")
    lamp_addon.freeform.properties.set_role(obj, "reflector")
    obj.lamp_role.reflector.scatter = 0.3
    handler = lamp_addon.freeform.geometry._on_depsgraph_update

    def registered():
        return (hasattr(bpy.types.Object, "lamp_role"), hasattr(bpy.types, "LAMP_PT_freeform"),
                hasattr(bpy.types, "LAMP_OT_role_assign"), handler in bpy.app.handlers.depsgraph_update_post)

    assert registered() == (True, True, True, True)
    for _ in range(2):
        lamp_addon.unregister()
        try:
            assert registered() == (False, False, False, False)
        finally:
            lamp_addon.register()
        assert registered() == (True, True, True, True)
        assert obj.lamp_role.role == "reflector" and obj.lamp_role.reflector.scatter == pytest.approx(0.3)


def test_a_preset_of_a_design_with_parts_says_it_leaves_them_out(lamp_addon, addon_core, bl_scene, tmp_path, capfd):
    import bpy
    from helpers import BASELINE

    lamp_addon.design.properties.scene_to_design(bl_scene, addon_core.scene.load_scene(BASELINE))
    capfd.readouterr()
    assert bpy.ops.lamp.preset_export(filepath=str(tmp_path / "a.json")) == {"FINISHED"}
    assert "free-form parts" not in capfd.readouterr().out
    lamp_addon.freeform.properties.set_role(_mesh("Glass"), "lens")
    assert bpy.ops.lamp.preset_export(filepath=str(tmp_path / "b.json")) == {"FINISHED"}
    assert "the 1 free-form parts are not in it; Export Free-form Design writes them" in capfd.readouterr().out

"""The shipped free-form example (``presets/freeform-sculpted-wrap-lamp.json`` and its ``.glb``, made by
``tools/make_freeform_example.py``): the preset browser lists it, it renders from the command line, and
applied in Blender its F12 equals the command line's image pixel for pixel: the parts Apply Preset makes
hand the tracer the file's very positions and normals (``freeform.loading``, ``freeform.meshes
.normals_exporting_as``), which the test compares array by array before the images."""

from __future__ import annotations

import json

import numpy as np
import pytest
from helpers import PRESETS, applied_preset, run_cli

pytestmark = pytest.mark.blender

EXAMPLE = PRESETS / "freeform-sculpted-wrap-lamp.json"


def _exr(path) -> np.ndarray:
    import OpenImageIO as oiio

    buf = oiio.ImageBuf(str(path))
    return np.asarray(buf.get_pixels(oiio.FLOAT)).reshape(buf.spec().height, buf.spec().width, -1)[:, :, :3]


def _f12(bl_scene, path) -> np.ndarray:
    """F12 of ``bl_scene`` saved as a 32-bit EXR at ``path``, read back."""
    import bpy

    settings = bl_scene.render.image_settings
    settings.file_format, settings.color_depth = "OPEN_EXR", "32"
    assert bpy.ops.render.render() == {"FINISHED"}
    bpy.data.images["Render Result"].save_render(str(path), scene=bl_scene)
    return _exr(path)


def test_the_example_ships_with_its_mesh_file():
    import json

    doc = json.loads(EXAMPLE.read_text(encoding="utf-8"))
    assert (PRESETS / doc["freeform"]["mesh_file"]).is_file()
    roles = sorted(part["role"] for part in doc["freeform"]["parts"])
    assert roles == ["body", "bulb", "lens", "reflector", "side_wall", "socket"]


@pytest.mark.slow
def test_the_browser_lists_it_and_f12_equals_the_command_line(lamp_addon, startup_scene, tmp_path):
    import bpy

    bl_scene = startup_scene
    bpy.ops.lamp.preset_refresh()
    wm = bpy.context.window_manager
    listed = [item.file for item in wm.lamp_presets]
    assert any(f.endswith(EXAMPLE.name) for f in listed)  # the browser lists it
    wm.lamp_presets_index = next(i for i, f in enumerate(listed) if f.endswith(EXAMPLE.name))
    assert bpy.ops.lamp.preset_apply() == {"FINISHED"}
    parts = lamp_addon.freeform.properties.role_objects(bl_scene)
    assert sorted(o.lamp_role.role for o in parts) == ["body", "bulb", "lens", "reflector", "side_wall", "socket"]
    assert bl_scene.render.engine == "LAMP_TRACER"
    # Its parametric lamp is built and hidden: Auto Build's next build does not bring it back into renders.
    built = lamp_addon.freeform.parametric.used_parts(bl_scene, None)
    assert built == [] and any(ob.get("lamp_part") == "lamps[0].lens" and ob.hide_render for ob in bl_scene.objects)
    lamp_addon.design.builder.build_lamp(bl_scene, lamp_addon.design.properties.design_to_scene(bl_scene))
    assert lamp_addon.freeform.parametric.used_parts(bl_scene, None) == []

    # What F12 hands the tracer (the scene's kept geometry, as the render reads it) against what the
    # command line reads from the files: the same arrays, bit for bit.
    from core_tracer.freeform.loading import load

    _, from_files = load(EXAMPLE)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    in_blender = lamp_addon.freeform.geometry.geometry(
        bl_scene, depsgraph, lamp_addon.freeform.geometry.parts_in(depsgraph)).meshes
    assert sorted(in_blender) == sorted(from_files)
    for name, mesh in from_files.items():
        for field in ("vertices", "triangles", "corner_normals"):
            assert np.array_equal(getattr(in_blender[name], field), getattr(mesh, field)), (name, field)

    f12 = _f12(bl_scene, tmp_path / "f12.exr")

    done = run_cli("render", EXAMPLE, "-o", tmp_path / "cli.exr")
    assert done.returncode == 0, done.stderr
    cli = _exr(tmp_path / "cli.exr")
    assert cli.shape == f12.shape == (256, 320, 3)
    equal = (f12 == cli).all(axis=2)
    print(f"F12 vs CLI: {equal.mean():.1%} of the pixels equal, largest |difference| {np.abs(f12 - cli).max():.3g}")
    assert equal.all()  # pixel for pixel
    lens = cli[..., 0] > 4.0 * np.maximum(cli[..., 1], 1e-6)
    assert lens.mean() > 0.15 and cli[lens].max() > 1.0  # the lit red lens fills a good part of the frame


@pytest.mark.slow
def test_applied_over_a_built_parametric_lamp_nothing_is_traced_twice(lamp_addon, addon):
    """The quick start's order: a parametric preset built, then the free-form example applied, then F12."""
    import bpy

    bpy.ops.wm.read_homefile(use_factory_startup=True)
    bpy.ops.lamp.preset_refresh()
    wm = bpy.context.window_manager
    listed = [item.file for item in wm.lamp_presets]
    wm.lamp_presets_index = next(i for i, f in enumerate(listed) if f.endswith("four-lamp-rear-combination.json"))
    assert bpy.ops.lamp.preset_apply() == {"FINISHED"} and bpy.ops.lamp.build() == {"FINISHED"}
    wm.lamp_presets_index = next(i for i, f in enumerate(listed) if f.endswith(EXAMPLE.name))
    assert bpy.ops.lamp.preset_apply() == {"FINISHED"}
    bl_scene = bpy.context.scene
    bl_scene.render.resolution_percentage = 25
    assert lamp_addon.freeform.parametric.used_parts(bl_scene, None) == []
    assert bpy.ops.render.render() == {"FINISHED"}  # no "overlaps lens ... (Parametric)"


TWIN = PRESETS / "freeform-sculpted-wrap-lamp-photometric.json"


@pytest.mark.slow
def test_the_photometric_twin_renders_in_blender_as_on_the_command_line(lamp_addon, addon, tmp_path):
    """The example's photometric twin (the same .glb, a P21/5W tail filament, a red PMMA lens, night at
    3 lx): applied from the browser, F12 shows the command line's XYZ (cd/m²) as scene-linear Rec.709
    at the preset's EV100 15, the one display path of photometric images (``display.display_linear``)."""
    from core_tracer.images import display
    from core_tracer.images import photometric as photometric_images

    bl_scene = applied_preset(TWIN)
    parts = lamp_addon.freeform.properties.role_objects(bl_scene)
    bulb = next(o for o in parts if o.lamp_role.role == "bulb")
    assert bulb.lamp_role.bulb.type == "P21/5W" and bulb.lamp_role.bulb.state == "tail"
    f12 = _f12(bl_scene, tmp_path / "f12.exr")

    done = run_cli("render", TWIN, "-o", tmp_path / "cli.exr")
    assert done.returncode == 0, done.stderr
    channels = photometric_images.read_photometric_exr(tmp_path / "cli.exr")[0]
    xyz = np.stack([channels[c] for c in "XYZ"], axis=-1)
    shown = display.display_linear(xyz, 15.0)
    assert f12.shape == shown.shape == (256, 320, 3)
    lit = channels["Y"] > 0.05 * channels["Y"].max()
    print(f"F12 vs CLI at EV100 15: largest |difference| {np.abs(f12 - shown).max():.3g} of {shown.max():.3g}")
    assert lit.sum() > 1000 and channels["x"][lit].mean() > 0.6  # a red tail lamp
    np.testing.assert_allclose(f12, shown, rtol=1e-4, atol=1e-6 * shown.max())


@pytest.mark.slow
def test_the_light_and_optimise_panels_refuse_free_form_parts_in_one_line(lamp_addon, addon, tmp_path):
    """In Blender the Light Panel and Optimise operators work on the parametric lamp, which a free-form
    design's parts stand in for: they say so in one line rather than relight or optimise the hidden
    lamp (the command line does both on the exported pair; the Study and Measures panels work on the
    parts: tests/addon/test_addon_study_freeform.py, test_addon_install.py)."""
    import bpy

    bl_scene = applied_preset(TWIN)
    optimisation = tmp_path / "liked.optimise.json"  # no base: it would start from the scene's design
    optimisation.write_text(json.dumps({"schema": "lamp-optimise/1", "parameters": [
        {"parameter": "freeform.parts[].lens.filter_thickness", "range": [2, 4]}],
        "objectives": [{"measure": "lens_luminance", "goal": "maximise"}]}))
    bl_scene.lamp_optimise.file = str(optimisation)
    for operator, what in ((bpy.ops.lamp.light_states_render, "measured"), (bpy.ops.lamp.optimise_run, "optimised")):
        with pytest.raises(RuntimeError, match=f"Free-form Parts: are not {what} here yet") as err:
            operator()
        assert "Export Free-form Design" in str(err.value) and "\n" not in str(err.value).strip()

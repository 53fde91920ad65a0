"""Convert to Free-form, and the issue's "parametric ≡ free-form" test: every built-in preset rendered
by the parametric tracer and, after conversion, by the free-form tracer on the converted meshes.

Tolerance. Convert's meshes lie within the chord tolerance ε = 0.0125 mm of the analytic surfaces
(``convert.meshes.builder.FREEFORM_CHORD_TOLERANCE_MM``, measured per mesh; Build's within 0.05 mm). A
hit point is thus off by at most ε (at Build's 0.05 mm: 2 % of the 2.3 mm a pixel covers on the lamp
at 96², the design camera spanning 225 mm, and 1.7 % of the 3 mm plate a ray crosses, absorption eq. 2).
So a pixel agrees within τ = 2 % of its
value (its largest channel; at least 0.1 % of the image's brightest pixel, so that near-black pixels
are not held to a relative bound). Silhouettes and creases (the rim, the cut cells' edges) are where
an ε shift moves a whole pixel from one surface to another: pixels whose value differs from a
neighbour's by more than 10 % in the parametric image are excepted, and those of them outside τ
(the pixels the exception excuses) counted. A textured world seen around the lamp has such contrast
everywhere, yet both tracers look it up alike: only the excused pixels are bounded. The figures are
printed (``pytest -s``); measured: 99.5-100 % of the other pixels within τ, 13-45 % excepted, of
which at most 7 % of the image excused.
"""

from __future__ import annotations

import numpy as np
import pytest
from helpers import BASELINE, PRESETS, creases

pytestmark = pytest.mark.blender

SIZE = 96
# The parametric presets of the paper's model (the free-form example is its meshes already: nothing to
# convert); the photometric mode's agreement is test_photometric_stop_lamp_equals_its_freeform_meshes.
PARAMETRIC = sorted(p for p in PRESETS.glob("*.json")
                    if '"freeform"' not in (text := p.read_text(encoding="utf-8")) and '"photometric"' not in text)
TAU = 0.02
EDGE_CONTRAST = 0.10
MIN_SHARE_WITHIN = 0.99
MAX_SHARE_EXCEPTED = 0.10  # of the whole image: excepted and outside TAU


def _design(lamp_addon, addon_core, bl_scene, path) -> dict:
    scene = addon_core.scene.load_scene(path)
    scene["image"] = {"width": SIZE, "height": SIZE, "samples": 1}
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    return lamp_addon.design.properties.design_to_scene(bl_scene)


def _freeform_image(lamp_addon, bl_scene, design: dict) -> np.ndarray:
    import bpy

    prepared = lamp_addon.freeform.render.prepare(bl_scene, bpy.context.evaluated_depsgraph_get(), design)
    assert prepared.geometry is not None
    return lamp_addon.freeform.render.render_passes(prepared, SIZE, SIZE).image


def agreement(parametric: np.ndarray, freeform: np.ndarray, mask: np.ndarray | None = None) -> tuple[float, float]:
    """(share of the pixels away from silhouettes and creases within ``TAU``, share excused: at
    silhouettes and creases and outside ``TAU``, of the image), of the pixels ``mask`` (all when None)."""
    value = np.maximum(parametric.max(axis=2), 1e-3 * parametric.max())
    error = np.abs(freeform - parametric).max(axis=2) / value
    edge = creases(parametric, EDGE_CONTRAST)
    if mask is None:
        mask = np.ones(edge.shape, bool)
    return float((error[~edge & mask] <= TAU).mean()), float((edge & (error > TAU) & mask).mean())


@pytest.mark.seed(0)
def test_agreement_measure_fails_on_a_different_lamp(rng):
    image = np.ones((32, 32, 3)) + 0.001 * rng.random((32, 32, 3))
    assert agreement(image, image) == (1.0, 0.0)
    assert agreement(image, image * 1.03)[0] == 0.0  # 3 % brighter everywhere is not the same lamp


@pytest.mark.slow
@pytest.mark.parametrize("path", PARAMETRIC, ids=lambda p: p.stem)
def test_parametric_equals_freeform(lamp_addon, addon_core, bl_scene, path):
    design = _design(lamp_addon, addon_core, bl_scene, path)
    parametric = addon_core.render_passes(design, SIZE, SIZE).image
    lamp_addon.freeform.conversion.convert_to_freeform(bl_scene)
    freeform = _freeform_image(lamp_addon, bl_scene, design)
    within, excepted = agreement(parametric, freeform)
    print(f"\n{path.stem}: {within:.2%} of the pixels within {TAU:.0%} (at silhouettes and creases, "
          f"excused: {excepted:.1%} of the image)")
    assert within >= MIN_SHARE_WITHIN and excepted <= MAX_SHARE_EXCEPTED


@pytest.mark.slow
def test_convert_makes_closed_lenses_with_roles_and_hides_the_parametric_parts(lamp_addon, addon_core, bl_scene):
    import bpy

    design = _design(lamp_addon, addon_core, bl_scene, BASELINE)
    mine = bpy.data.objects.new("My Empty", None)
    bl_scene.collection.objects.link(mine)
    assert bpy.ops.lamp.freeform_convert() == {"FINISHED"}
    parts = lamp_addon.freeform.properties.role_objects(bl_scene)
    roles = sorted(o.lamp_role.role for o in parts)
    assert roles == ["body", "bulb", "lens", "reflector", "side_wall", "socket"]
    built = [o for o in bl_scene.objects if o.get("lamp_part") not in (None, "root", "sun")]
    assert built and all(o.hide_render and o.hide_get() for o in built)
    assert not mine.hide_render and mine.lamp_role.role == "NONE"  # the designer's objects are left alone
    root = lamp_addon.design.root.find_root(bl_scene)
    assert all(o.parent == root and o.get("lamp_part") is None for o in parts)
    meshes = lamp_addon.freeform.meshes.scene_meshes(bl_scene, bpy.context.evaluated_depsgraph_get(), parts)
    core_meshes = addon_core.freeform.meshes
    lens = next(o for o in parts if o.lamp_role.role == "lens")
    lamp = design["lamps"][0]
    assert core_meshes.check_lens_volume(meshes[lens.name]) > np.pi * lamp["lens"]["radius"] ** 2 * 0.9 * \
        lamp["lens"]["thickness"]
    assert lamp_addon.freeform.properties.part_document(lens)["lens"]["ior"] == lamp["lens"]["ior"]
    # Every part has its role material, so Cycles renders what the tracer traces.
    assert all(lamp_addon.freeform.materials.role_material(o) is not None for o in parts)
    assert {"REGISTER", "UNDO"} <= bpy.types.LAMP_OT_freeform_convert.bl_options
    # The parametric lamp is hidden now: the copies are traced alone, and the panel says so.
    status = lamp_addon.freeform.status
    assert status.rendered_text(bl_scene) == status.PARTS_ONLY_TEXT
    assert lamp_addon.freeform.parametric.built_parts(bl_scene, bpy.context.evaluated_depsgraph_get()) == []


def test_convert_makes_finer_meshes_and_leaves_the_built_parts_at_builds_tolerance(lamp_addon, addon_core, bl_scene):
    """Convert makes its meshes to ``FREEFORM_CHORD_TOLERANCE_MM`` / ``FREEFORM_CUT_TOLERANCE_MM`` (issue 32),
    the parametric parts stay as Build makes them, and the finer tolerances hold in their context only:
    another thread (Auto Build's worker) makes Build's meshes meanwhile."""
    import importlib
    import threading

    import bpy

    mesh_builder = importlib.import_module(f"{lamp_addon.__name__}.convert.meshes.builder")
    _design(lamp_addon, addon_core, bl_scene, BASELINE)
    lamp_addon.design.builder.build_lamp(bl_scene, lamp_addon.design.properties.design_to_scene(bl_scene))
    lens = next(o for o in bl_scene.objects if o.get(lamp_addon.design.root.PART_KEY) == "lamps[0].lens")
    built = len(lens.data.polygons)
    assert bpy.ops.lamp.freeform_convert() == {"FINISHED"}
    assert len(lens.data.polygons) == built and lamp_addon.design.builder.is_up_to_date(bl_scene)
    glass = next(o for o in lamp_addon.freeform.properties.role_objects(bl_scene) if o.lamp_role.role == "lens")
    assert len(glass.data.polygons) > 1.5 * built  # measured 2.2x on the stop lamp

    seen = []
    with mesh_builder.tolerances(0.01, 0.002):
        worker = threading.Thread(target=lambda: seen.append((mesh_builder.chord_tolerance(),
                                                              mesh_builder.cut_tolerance())))
        worker.start()
        worker.join()
        assert (mesh_builder.chord_tolerance(), mesh_builder.cut_tolerance()) == (0.01, 0.002)
    assert seen == [(mesh_builder.CHORD_TOLERANCE_MM, mesh_builder.CUT_TOLERANCE_MM)]
    assert mesh_builder.chord_tolerance() == mesh_builder.CHORD_TOLERANCE_MM


@pytest.mark.slow
def test_converting_again_says_the_earlier_parts_are_traced_too(lamp_addon, addon_core, bl_scene, capfd):
    import bpy

    _design(lamp_addon, addon_core, bl_scene, BASELINE)
    assert bpy.ops.lamp.freeform_convert() == {"FINISHED"}
    capfd.readouterr()
    assert bpy.ops.lamp.freeform_convert() == {"FINISHED"}
    assert "the 6 parts the scene had already are traced too" in capfd.readouterr().out
    assert len(lamp_addon.freeform.properties.role_objects(bl_scene)) == 12  # nothing of the first was changed


def _lens_volumes(lamp_addon, addon_core, bl_scene, parts) -> dict[str, float]:
    """Volume (mm³) of each lens-role part, which ``check_lens_volume`` finds closed and outward."""
    import bpy

    meshes = lamp_addon.freeform.meshes.scene_meshes(bl_scene, bpy.context.evaluated_depsgraph_get(), parts)
    return {o.name: addon_core.freeform.meshes.check_lens_volume(meshes[o.name]) for o in parts
            if o.lamp_role.role == "lens"}


@pytest.mark.slow
def test_convert_makes_the_prism_plate_a_closed_lens_and_its_housing_a_wall(lamp_addon, addon_core, bl_scene):
    import bpy

    design = _design(lamp_addon, addon_core, bl_scene, PRESETS / "prism-plate-stop-lamp.json")
    lamp_addon.design.builder.build_lamp(bl_scene, design)
    built_lens = next(o for o in bl_scene.objects if o.get("lamp_part") == "lamps[0].lens")
    mine = bpy.data.objects.new("My Bracket", bpy.data.meshes.new("My Bracket"))
    mine.data.from_pydata([(0, 0, 0), (0.01, 0, 0), (0, 0.01, 0)], [], [(0, 1, 2)])
    bl_scene.collection.objects.link(mine)
    mine.parent = built_lens
    where = mine.matrix_world.copy()
    assert bpy.ops.lamp.freeform_convert() == {"FINISHED"}
    parts = lamp_addon.freeform.properties.role_objects(bl_scene)
    by_name = {o.name: o for o in parts}
    plate = by_name["Lamp 1 Prism Plate (Free-form)"]
    housing = by_name["Lamp 1 Housing (Free-form)"]
    lamp = design["lamps"][0]
    values = lamp_addon.freeform.properties.part_document(plate)["lens"]
    assert plate.lamp_role.role == "lens" and values["ior"] == lamp["prism_plate"]["ior"]
    assert values["absorption"] == pytest.approx(lamp["prism_plate"]["absorption"])
    assert values["specular"] == 0 and values["diffuse_color"] == [0, 0, 0]  # the plate has no eq. (1) shading
    assert housing.lamp_role.role == "side_wall"
    assert lamp_addon.freeform.properties.part_document(housing)["side_wall"]["color"] == pytest.approx(
        lamp["prism_plate"]["housing_color"])
    volumes = _lens_volumes(lamp_addon, addon_core, bl_scene, parts)  # the plate is closed at its rim now
    assert volumes[plate.name] > np.pi * lamp["lens"]["radius"] ** 2 * lamp["prism_plate"]["thickness"]
    # the designer's object, though it hangs on the hidden lens, is as it was
    assert mine.parent == built_lens and mine.matrix_world == where and len(mine.data.vertices) == 3
    assert not mine.hide_render and not mine.hide_get() and mine.lamp_role.role == "NONE"


@pytest.mark.slow
def test_convert_closes_the_glass_of_a_wrap_around_lens(lamp_addon, addon_core, bl_scene):
    import bpy

    design = _design(lamp_addon, addon_core, bl_scene, PRESETS / "wrap-around-combination.json")
    assert bpy.ops.lamp.freeform_convert() == {"FINISHED"}
    parts = lamp_addon.freeform.properties.role_objects(bl_scene)
    volumes = _lens_volumes(lamp_addon, addon_core, bl_scene, parts)
    lens = design["lamps"][2]["lens"]  # rectangular on a cylinder: its side wall's collar is left to the wall
    outline = addon_core.scene.outline.Outline.of_lens(lens)
    assert volumes["Lamp 3 Lens (Free-form)"] > outline.area * lens["thickness"] * 0.9
    walls = [o for o in parts if o.lamp_role.role == "side_wall"]
    assert sorted(o.name for o in walls) == [f"Lamp {i} Side Wall (Free-form)" for i in (1, 2, 3)]


@pytest.mark.slow
def test_a_mixed_design_renders_the_parametric_lamp_as_the_parametric_tracer(lamp_addon, addon_core, bl_scene):
    """The built paper lamp, not converted, with the designer's own slab and bulb beside it: its lens
    pixels as the parametric tracer renders the lamp alone, within the chord tolerance."""
    from test_addon_freeform_render import _add_my_lamp

    design = _design(lamp_addon, addon_core, bl_scene, BASELINE)
    lamp_addon.design.builder.build_lamp(bl_scene, design)
    parametric = addon_core.render_passes(design, SIZE, SIZE).image
    _add_my_lamp(lamp_addon, bl_scene)
    mixed = _freeform_image(lamp_addon, bl_scene, design)
    lens = parametric[:, :, 0] > 2 * parametric[:, :, 1]  # the red lens; the body is grey
    within, excepted = agreement(parametric, mixed, lens)
    print(f"\nmixed design, parametric lens pixels ({lens.sum()}): {within:.2%} within {TAU:.0%} (at "
          f"silhouettes and creases, excused: {excepted:.1%} of the image)")
    assert lens.mean() > 0.1 and within >= MIN_SHARE_WITHIN and excepted <= MAX_SHARE_EXCEPTED
    # The designer's slab is there too, with their bulb seen through it, where the parametric lamp
    # shows the body.
    beside = np.arange(SIZE) > np.nonzero(lens.any(axis=0))[0].max()  # the columns right of the lens
    mine = (np.abs(mixed - parametric).max(axis=2) > TAU * parametric.max(axis=2)) & beside
    print(f"the slab: {mine.sum()} pixels, brightest {mixed[mine].max():.2f} (the body there: "
          f"{parametric[mine].max():.2f})")
    assert mine.sum() >= 50 and mixed[mine].max() > 1.0 and parametric[mine].max() < 1.0


@pytest.mark.slow
@pytest.mark.parametrize("path", PARAMETRIC, ids=lambda p: p.stem)
def test_parametric_equals_mixed(lamp_addon, addon_core, bl_scene, path):
    """Every preset built, not converted, traced by the free-form tracer beside a part of the
    designer's (a small body-role block hidden behind the body): the meshes made of the parametric
    lamps without Convert agree with the parametric tracer as Convert's do."""
    import bmesh
    import bpy
    from mathutils import Matrix

    design = _design(lamp_addon, addon_core, bl_scene, path)
    lamp_addon.design.builder.build_lamp(bl_scene, design)
    parametric = addon_core.render_passes(design, SIZE, SIZE).image
    block = bpy.data.objects.new("My Block", bpy.data.meshes.new("My Block"))
    bm = bmesh.new()
    bmesh.ops.create_cube(bm, size=0.01)
    bm.to_mesh(block.data)
    bm.free()
    bl_scene.collection.objects.link(block)
    behind = design["body"]["depth"] + 50.0 if design.get("body") else 500.0
    block.matrix_world = lamp_addon.design.root.world_from_design(bl_scene) @ Matrix.Translation((0, behind / 1000, 0))
    lamp_addon.freeform.properties.set_role(block, "body")
    bpy.context.view_layer.update()
    mixed = _freeform_image(lamp_addon, bl_scene, design)
    within, excepted = agreement(parametric, mixed)
    print(f"\n{path.stem}, mixed: {within:.2%} of the pixels within {TAU:.0%} (at silhouettes and creases, "
          f"excused: {excepted:.1%} of the image)")
    assert within >= MIN_SHARE_WITHIN and excepted <= MAX_SHARE_EXCEPTED


# The figure (issue 32): the photometric stop lamp converted to meshes gives the lit lens's
# luminance within 0.5 % and the R148 grid within 1 % of the parametric render. Convert makes its meshes
# to chord 0.0125 mm and cut surfaces 0.0025 mm for this (``mesh_builder.tolerances``): measured, the lit
# lens +0.39 %, of which +0.03 % on the pixels whose every branch meets the same surfaces in both (the
# physics: the same engine, the bulb of the same luminance) and the rest on the 1 % of its pixels where a
# ray reflected at grazing incidence meets the bulb in one and the socket or reflector in the other
# (Build's 0.05 / 0.0075 mm: +0.52 %; benchmarks/RESULTS.md, "The photometric stop lamp as free-form meshes").
LIT_LENS_TOLERANCE = 0.005
SAME_SURFACES_TOLERANCE = 0.001
GRID_TOLERANCE = 0.01
FRONT_PIXEL_MM = 0.5  # the measures' front view (``report.measure``'s homogeneity view)
# The grid's rendered views: the same randomly shifted pixel grids for both tracers (seeds), fine
# enough that a cut cell's edge moved by the chord tolerance moves the sum by far less than 1 %.
GRID_PIXEL_MM = 0.5
GRID_REPLICATES = 3
# Measured (3 replicates at 0.5 mm, paired: the difference's standard error 0.02-0.2 %): H = ±20°, V = ±10°,
# the worst, -0.45 % (-1.15 to -1.37 % at Build's tolerances).


@pytest.mark.slow
def test_photometric_stop_lamp_equals_its_freeform_meshes(lamp_addon, addon_core, bl_scene):
    """The same lamp traced on the same engine, its surfaces found on the parametric parts or on the
    meshes Convert makes of them: the lit lens's mean luminance in the measures' front view (the
    pixels whose ray crosses the lens's outer face), and the intensity at every point of the R148
    stop lamp grid (rendered views, the same shifted pixel grids for both)."""
    import importlib

    import bpy

    def core(name: str):
        return importlib.import_module(f"{addon_core.__name__}.{name}")

    path = PRESETS / "photometric-stop-lamp.json"
    design = _design(lamp_addon, addon_core, bl_scene, path)
    lamp_addon.freeform.conversion.convert_to_freeform(bl_scene)
    prepared = lamp_addon.freeform.render.prepare(bl_scene, bpy.context.evaluated_depsgraph_get(), design)
    assert prepared.geometry is not None and "freeform" in prepared.scene
    freeform = prepared.scene
    assert freeform["light_model"] == "photometric"
    meshes = core("freeform.design").DesignMeshes(prepared.geometry.meshes)
    intensity, grid = core("measures.intensity"), core("measures.regulation_grid")
    direction = core("measures.directions").direction

    view = intensity.view_along(design, direction(0.0, 0.0), FRONT_PIXEL_MM)
    parametric = intensity.render_view(intensity.measurement_scene(design), view)[..., 1]
    meshed = intensity.render_view(intensity.measurement_scene(freeform), view, meshes=meshes)[..., 1]
    lens = (intensity.lamp_of_pixels(design, view) == 0) & (parametric > 0)
    # the measures' lit-lens luminance: the mean over the lit lens as an eye at 10 m resolves it
    # (``homogeneity``, as ``report.measure`` takes it)
    homogeneity = core("measures.homogeneity").homogeneity
    l_parametric = homogeneity(parametric, lens, FRONT_PIXEL_MM).l_mean
    l_meshed = homogeneity(meshed, lens, FRONT_PIXEL_MM).l_mean
    lit = l_meshed / l_parametric - 1.0
    print(f"\nlit lens ({lens.sum()} px at {FRONT_PIXEL_MM} mm): {l_parametric:.1f} cd/m² parametric, "
          f"{l_meshed:.1f} free-form ({lit:+.3%})")
    assert abs(lit) <= LIT_LENS_TOLERANCE
    both = lens & (parametric > 0) & (meshed > 0)
    ratio = meshed[both] / parametric[both]
    agreeing = np.abs(ratio - 1.0) < 0.02  # the same surfaces met (a different one: a factor of 2 to 100)
    same = ratio[agreeing].mean() - 1.0
    print(f"pixels meeting the same surfaces ({agreeing.mean():.1%} of the lit lens): {same:+.3%}")
    assert abs(same) <= SAME_SURFACES_TOLERANCE and agreeing.mean() > 0.95

    worst = 0.0
    for k, (h, v) in enumerate(grid.directions_for("R148 S1")):
        a, = intensity.rendered_intensities(design, h, v, pixel_mm=GRID_PIXEL_MM, replicates=GRID_REPLICATES,
                                            seed=k)
        b, = intensity.rendered_intensities(freeform, h, v, pixel_mm=GRID_PIXEL_MM, replicates=GRID_REPLICATES,
                                            seed=k, meshes=meshes)
        error = b.cd / a.cd - 1.0
        worst = max(worst, abs(error))
        print(f"  H {h:+5.1f} V {v:+5.1f}: {a.cd:8.2f} ± {a.stderr:.2f} cd parametric, {b.cd:8.2f} ± {b.stderr:.2f} "
              f"free-form ({error:+.3%})")
        assert abs(error) <= GRID_TOLERANCE, (h, v)
    print(f"R148 S1 grid: worst {worst:.3%}")

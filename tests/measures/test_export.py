"""The beam as a file (core_tracer.measures.export): EULUMDAT read back by an independent parser
(pyldt, the eulumdat-py package), IES LM-63-2002 read by Blender's Cycles (its IES texture), which
lights a floor 3 m away with I cos θ / d² within 3 %."""

from __future__ import annotations

import math

import numpy as np
import pytest
from needs import require

from core_tracer.measures import export as E

# Cycles turns candela into its light units with the luminous efficacy of D65, 177.83 lm/W
# (intern/cycles/util/ies.cpp, "factor *= 0.0706650768394" = 4π / 177.83, for a point light of 1 W
# radiating 1/(4π) W/sr per unit of strength): a point light of 177.83 W makes a white Lambertian
# surface's radiance π L numerically its illuminance in lx.
CYCLES_LM_PER_W = 177.83


def synthetic() -> E.Distribution:
    """Not symmetric in C, peaked at γ = 0, one value on the axis: I = (100 + 300 cos² γ)(1 + 0.3 sin C sin γ) cd."""
    c = np.arange(0.0, 360.0, 15.0)
    gamma = np.arange(0.0, 90.0 + 1e-9, 5.0)
    g, ci = np.radians(gamma)[None, :], np.radians(c)[:, None]
    cd = (100 + 300 * np.cos(g) ** 2) * (1 + 0.3 * np.sin(ci) * np.sin(g))
    return E.Distribution(c, gamma, cd, 440.0, "synthetic")


def test_ies_text_follows_lm63_2002():
    text = E.ies_text(synthetic())
    lines = text.split("\r\n")
    assert lines[0] == "IESNA:LM-63-2002" and "TILT=NONE" in lines
    assert max(len(line) for line in lines) <= 256
    numbers = " ".join(lines[lines.index("TILT=NONE") + 1:]).split()
    n_v, n_h = int(numbers[3]), int(numbers[4])
    assert (numbers[1], numbers[5], numbers[6]) == ("-1", "1", "2")  # absolute photometry, type C, metres
    assert len(numbers) == 13 + n_v + n_h + n_v * n_h
    assert float(numbers[13 + n_v - 1]) == 180.0 and float(numbers[13 + n_v + n_h - 1]) == 360.0


def test_ldt_reads_back_in_an_independent_parser(tmp_path):
    """pyldt (PyPI eulumdat-py 1.0.0, MIT) reads the angles and cd/klm back; × flux/1000 = cd."""
    pyldt = require("pyldt", "eulumdat-py")
    dist = synthetic()
    E.write_ldt(dist, tmp_path / "lamp.ldt")
    ldt = pyldt.LdtReader.read(tmp_path / "lamp.ldt")
    assert ldt.header.mc == len(dist.c_deg) and ldt.header.isym == 0
    assert ldt.header.lamp_flux[0] == pytest.approx(440.0)
    np.testing.assert_allclose(ldt.header.c_angles, dist.c_deg)
    np.testing.assert_allclose(ldt.header.g_angles[:len(dist.gamma_deg)], dist.gamma_deg)
    got = np.array(ldt.intensities)[:, :len(dist.gamma_deg)] * 440.0 / 1000.0
    np.testing.assert_allclose(got, dist.cd, rtol=1e-5)
    assert np.all(np.array(ldt.intensities)[:, len(dist.gamma_deg):] == 0.0)


def _cycles_floor(bpy, ies_path, tmp_path, size_m=12.0, pixels=241):
    """Cycles' render of a white Lambertian floor 3 m under a point light whose strength is the IES
    texture of ``ies_path``, seen from above by an orthographic camera: π × radiance per pixel."""
    import OpenImageIO as oiio

    bpy.ops.wm.read_homefile(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = 64
    scene.cycles.use_denoising = False
    scene.cycles.max_bounces = 0  # direct light only: the floor under the light
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    world = bpy.data.worlds.new("black")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs[1].default_value = 0.0
    scene.world = world
    bpy.ops.mesh.primitive_plane_add(size=4 * size_m, location=(0.0, 0.0, 0.0))
    floor = bpy.context.object
    material = bpy.data.materials.new("white")
    material.use_nodes = True
    nodes = material.node_tree.nodes
    nodes.clear()
    diffuse = nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    diffuse.inputs["Roughness"].default_value = 0.0
    material.node_tree.links.new(diffuse.outputs[0], nodes.new("ShaderNodeOutputMaterial").inputs[0])
    floor.data.materials.append(material)
    light = bpy.data.lights.new("ies", "POINT")
    light.energy = CYCLES_LM_PER_W
    light.shadow_soft_size = 0.0
    light.use_nodes = True
    ies = light.node_tree.nodes.new("ShaderNodeTexIES")
    ies.mode = "EXTERNAL"
    ies.filepath = str(ies_path)
    light.node_tree.links.new(ies.outputs[0], light.node_tree.nodes["Emission"].inputs["Strength"])
    holder = bpy.data.objects.new("ies", light)
    holder.location = (0.0, 0.0, 3.0)  # the light's −Z, the file's nadir, looks down at the floor
    scene.collection.objects.link(holder)
    camera = bpy.data.cameras.new("camera")
    camera.type = "ORTHO"
    camera.ortho_scale = size_m
    eye = bpy.data.objects.new("camera", camera)
    eye.location = (0.0, 0.0, 2.0)
    scene.collection.objects.link(eye)
    scene.camera = eye
    scene.render.resolution_x = scene.render.resolution_y = pixels
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.render.filepath = str(tmp_path / "floor.exr")
    bpy.ops.render.render(write_still=True)
    image = oiio.ImageBuf(str(tmp_path / "floor.exr")).get_pixels(oiio.FLOAT)[..., :3].mean(axis=2)
    return math.pi * image


def _floor_checks(dist, image, size_m=12.0, pixels=241):
    """(expected lx, rendered lx) at the floor points of directions of the file's own grid: the C
    planes 0, 90, 180, 270 at γ 0–40° (no interpolation between the file's angles on either side);
    the render read there bilinearly between pixel centres.

    Cycles lays the file's C = 0 along the light's −Y and C = 90 along its −X (found with the
    synthetic file, whose sin C term tells the two sides apart), so (C, γ) lands at
    (x, y) = −3 tan γ (sin C, cos C)."""
    pixel = size_m / pixels
    out = []
    for gamma in (0.0, 10.0, 20.0, 30.0, 40.0):
        for c in (0.0, 90.0, 180.0, 270.0):
            r = 3.0 * math.tan(math.radians(gamma))
            x, y = -r * math.sin(math.radians(c)), -r * math.cos(math.radians(c))
            d = math.sqrt(r * r + 9.0)
            col, row = x / pixel + pixels / 2 - 0.5, pixels / 2 - 0.5 - y / pixel  # in pixel centres
            c0, r0 = int(math.floor(col)), int(math.floor(row))
            tc, tr = col - c0, row - r0
            rendered = ((1 - tr) * ((1 - tc) * image[r0, c0] + tc * image[r0, c0 + 1])
                        + tr * ((1 - tc) * image[r0 + 1, c0] + tc * image[r0 + 1, c0 + 1]))
            out.append(((c, gamma), dist.at(c, gamma) * (3.0 / d) / d**2, float(rendered)))
    return out


@pytest.mark.slow
@pytest.mark.blender
def test_ies_round_trip_in_cycles_synthetic(tmp_path):
    bpy = require("bpy")
    dist = synthetic()
    E.write_ies(dist, tmp_path / "synthetic.ies")
    for where, expected, rendered in _floor_checks(dist, _cycles_floor(bpy, tmp_path / "synthetic.ies", tmp_path)):
        assert rendered == pytest.approx(expected, rel=0.03), where


@pytest.mark.slow
@pytest.mark.blender
def test_ies_round_trip_in_cycles_of_the_stop_lamp(tmp_path, repo_root):
    """The photometric stop lamp's beam, rendered on a (C, γ) grid of 30° × 10°, as an IES file: the
    floor at 3 m gets I cos θ / d² within 3 % at the grid's directions."""
    bpy = require("bpy")
    from core_tracer.scene import load_scene

    scene = load_scene(repo_root / "presets" / "photometric-stop-lamp.json")
    dist = E.measure_distribution(scene, grid=E.COARSE_GRID, photons=0, pixel_mm=1.0, replicates=1)
    assert dist.flux_lm == pytest.approx(440.0)
    E.write_ies(dist, tmp_path / "stop.ies")
    checks = _floor_checks(dist, _cycles_floor(bpy, tmp_path / "stop.ies", tmp_path))
    for where, expected, rendered in checks:
        assert rendered == pytest.approx(expected, rel=0.03), (where, expected, rendered)

"""The render API the Blender side uses: the acceleration structure built once per geometry
change, progress, cancellation, passes that sum to the image, samples."""

from __future__ import annotations

import numpy as np
import pytest
from needs import require

from core_tracer.freeform import GeometryCache, available, render_passes, shapes
from core_tracer.freeform.meshes import MeshData
from core_tracer.raytrace.engine import PASS_NAMES, RenderCancelled
from core_tracer.scene.validate import normalize, parse_scene

require("embreex")


def small_design():
    f, R, rim = 18.0, 45.0, 4.0
    vy = rim + R * R / (4 * f)
    meshes = [shapes.box("Lens", (-46, 0, -46), (46, 3, 46)), shapes.paraboloid_dish("Reflector", f, R, vy, 16, 48),
              shapes.uv_sphere("Bulb", (0, vy - f, 0), 8, 24), shapes.box("Body", (-110, 0, -60), (-50, 80, 60))]
    scene = parse_scene({"schema": "lamp-scene/2", "lamps": [{}], "image": {"width": 40, "height": 24},
                         "freeform": {"mesh_file": "s.glb", "parts": [
                             {"object": "Lens", "role": "lens"}, {"object": "Reflector", "role": "reflector"},
                             {"object": "Bulb", "role": "bulb"}, {"object": "Body", "role": "body"}]}})
    return scene, {m.name: m for m in meshes}


def test_available():
    assert available() == (True, "")


def test_geometry_is_built_once_per_geometry_change():
    scene, meshes = small_design()
    cache = GeometryCache()
    first = render_passes(scene, meshes, geometry_cache=cache)
    again = render_passes(scene, meshes, 20, 12, geometry_cache=cache)  # another size: same geometry
    assert cache.builds == 1 and first.stats["build_seconds"] > 0 and again.stats["build_seconds"] == 0
    # Values of a role are not geometry: no rebuild, but the image follows them.
    brighter = normalize({**scene, "freeform": {**scene["freeform"], "parts": [
        *scene["freeform"]["parts"][:2], {"object": "Bulb", "role": "bulb", "bulb": {"intensity": [20, 20, 20]}},
        scene["freeform"]["parts"][3]]}})
    lit = render_passes(brighter, meshes, geometry_cache=cache)
    assert cache.builds == 1 and lit.passes["bulb"].sum() > first.passes["bulb"].sum()
    # A mesh edited in place is a geometry change.
    meshes["Bulb"].vertices[:, 1] += 1.0
    render_passes(scene, meshes, geometry_cache=cache)
    assert cache.builds == 2
    # So is a role change.
    as_body = normalize({**scene, "freeform": {**scene["freeform"], "parts": [
        *scene["freeform"]["parts"][:3], {"object": "Body", "role": "socket"}]}})
    render_passes(as_body, meshes, geometry_cache=cache)
    assert cache.builds == 3


@pytest.mark.slow
def test_passes_sum_to_the_image_and_progress_reaches_one():
    scene, meshes = small_design()
    seen, bands = [], []

    def on_band(y0, y1, rows, passes):
        bands.append((y0, y1, rows.copy(), passes["bulb"].copy()))

    result = render_passes(scene, meshes, 2000, 40, progress=seen.append, on_band=on_band)  # 2 bands
    assert set(result.passes) == set(PASS_NAMES)
    np.testing.assert_allclose(sum(result.passes.values()), result.image, rtol=1e-6, atol=1e-7)
    assert seen and seen[-1] == 1.0 and seen == sorted(seen) and len(seen) == len(bands) > 1
    for y0, y1, rows, bulb in bands:
        np.testing.assert_array_equal(rows, result.image[y0:y1])
        np.testing.assert_array_equal(bulb, result.passes["bulb"][y0:y1])
    for name in ("lens_surface", "bulb", "reflector_constant", "reflector_scatter", "body"):
        assert result.passes[name].max() > 0, name


@pytest.mark.slow
def test_cancelled_between_bands():
    scene, meshes = small_design()
    calls = []

    def stop() -> bool:
        calls.append(1)
        return len(calls) > 1

    with pytest.raises(RenderCancelled):
        render_passes(scene, meshes, 64, 600, should_stop=stop)  # several bands


def test_samples_smooth_an_edge_and_keep_flat_areas():
    scene, meshes = small_design()
    one = render_passes(scene, meshes).image
    many = render_passes(scene, meshes, samples=16).image
    assert one.shape == many.shape
    # Inside the body's flat face the samples agree with the centre ray.
    np.testing.assert_allclose(many[12, 6], one[12, 6], rtol=1e-3)
    assert not np.array_equal(one, many)


def test_flat_and_smooth_meshes_are_both_accepted():
    scene, meshes = small_design()
    flat_bulb = MeshData("Bulb", meshes["Bulb"].vertices, meshes["Bulb"].triangles, None)
    image = render_passes(scene, {**meshes, "Bulb": flat_bulb}).image
    assert np.isfinite(image).all()


@pytest.mark.parametrize("role,pass_name,values,expected", [
    ("side_wall", "side_wall", {"color": [0.2, 0.3, 0.4]}, [0.2, 0.3, 0.4]),
    ("socket", "socket", {"color": [0.5, 0.1, 0.0]}, [0.5, 0.1, 0.0]),
    ("bulb", "bulb", {"intensity": [3.0, 2.0, 1.0]}, [3.0, 2.0, 1.0]),
    ("bulb", "bulb", {"intensity": [3.0, 2.0, 1.0], "on": False}, [0.0, 0.0, 0.0]),
])
def test_terminal_parts_end_a_ray_with_their_colour(role, pass_name, values, expected):
    # Seen straight on by the eye (k = 1): the pixel is the part's colour, in its own pass.
    scene = parse_scene({"schema": "lamp-scene/2", "lamps": [{}], "image": {"width": 5, "height": 5},
                         "camera": {"type": "orthographic", "position": [0, -500, 0], "target": [0, 0, 0],
                                    "width": 10.0},
                         "freeform": {"mesh_file": "t.glb", "parts": [{"object": "Part", "role": role, role: values}]}})
    result = render_passes(scene, {"Part": shapes.box("Part", (-20, 10, -20), (20, 20, 20))})
    np.testing.assert_allclose(result.passes[pass_name][2, 2], expected, rtol=1e-6)
    np.testing.assert_allclose(result.image[2, 2], expected, rtol=1e-6)


def test_reflector_adds_its_constant_and_blinn_scatter_toward_the_bulb():
    # A flat mirror facing the eye, the bulb off to the side: constant + w (cos β)^n I0 (eq. 3); the
    # mirror ray goes back out to the black background.
    # Counter-clockwise seen from -y: the plate faces the eye.
    plate = MeshData("Mirror", np.array([[-40, 50, -40], [40, 50, -40], [40, 50, 40], [-40, 50, 40]], float),
                     np.array([[0, 1, 2], [0, 2, 3]], np.int32))
    assert np.cross(*(plate.vertices[[1, 2]] - plate.vertices[0]))[1] < 0
    bulb = shapes.uv_sphere("Bulb", (30.0, 20.0, 0.0), 3.0, 32)
    scene = parse_scene({"schema": "lamp-scene/2", "lamps": [{}], "image": {"width": 5, "height": 5},
                         "camera": {"type": "orthographic", "position": [0, -500, 0], "target": [0, 0, 0],
                                    "width": 10.0},
                         "freeform": {"mesh_file": "r.glb", "parts": [
                             {"object": "Mirror", "role": "reflector",
                              "reflector": {"color": [0.3, 0.2, 0.1], "scatter": 0.7, "shininess": 12}},
                             {"object": "Bulb", "role": "bulb", "bulb": {"intensity": [8.0, 7.0, 6.0]}}]}})
    result = render_passes(scene, {"Mirror": plate, "Bulb": bulb})
    centroid = bulb.vertices[bulb.triangles].mean(axis=1)
    p = bulb.vertices[bulb.triangles]
    area = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    centre = (centroid * area[:, None]).sum(axis=0) / area.sum()  # the bulb's centre as the tracer takes it
    to_bulb = (centre - [0, 50, 0]) / np.linalg.norm(centre - [0, 50, 0])
    half = (np.array([0, -1.0, 0]) + to_bulb) / np.linalg.norm(np.array([0, -1.0, 0]) + to_bulb)
    cos_beta = -half[1]
    np.testing.assert_allclose(result.passes["reflector_constant"][2, 2], [0.3, 0.2, 0.1], rtol=1e-6)
    np.testing.assert_allclose(result.passes["reflector_scatter"][2, 2],
                               0.7 * cos_beta**12 * np.array([8.0, 7.0, 6.0]), rtol=1e-5)
    assert abs(centre[1] - 20.0) < 1e-9 and abs(centre[0] - 30.0) < 1e-9

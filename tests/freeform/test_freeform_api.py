"""The render API the Blender side uses: the acceleration structure built once per geometry
change, progress, cancellation, passes that sum to the image, samples."""

from __future__ import annotations

import numpy as np
import pytest

from core_tracer.freeform import GeometryCache, available, render_passes, shapes
from core_tracer.freeform.meshes import MeshData
from core_tracer.raytrace.tracer import PASS_NAMES, RenderCancelled
from core_tracer.scene.validate import normalize, parse_scene

pytest.importorskip("embreex")


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

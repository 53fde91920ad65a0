"""Surroundings: the environment image is looked up as Cycles' Environment Texture node does, the
lens mirrors it by its Fresnel reflectance, eye rays that miss see it, and it lights the body.

The expected values are computed here from Cycles' own formulas, written independently of
``environment``: direction_to_equirectangular with range (-2 pi, pi, -pi, pi), u = (atan2(y, x) - pi)
/ -2 pi, v = (acos(z) - pi) / -pi, and a bilinear lookup of pixel centres.
"""

from __future__ import annotations

import importlib.util
import json
import math
import subprocess
import sys

import numpy as np
import pytest
from helpers import assert_bad_input, baseline_doc, fresnel_unpolarised, run_cli, scene_with, smooth_sky, write_exr

from core_tracer import render_passes
from core_tracer.raytrace import engine, environment
from core_tracer.raytrace.camera import eye_rays, make_camera
from core_tracer.scene.reading import SceneError

W, H = 64, 32


@pytest.fixture
def ramp_exr(tmp_path) -> str:
    """R = column, G = row (from the top), B = 1: a bilinear lookup gives the continuous pixel coordinates."""
    cols, rows = np.meshgrid(np.arange(W, dtype=np.float32), np.arange(H, dtype=np.float32))
    return write_exr(tmp_path / "ramp.exr", np.stack([cols, rows, np.ones_like(cols)], axis=-1))


@pytest.fixture
def smooth_exr(tmp_path) -> str:
    """A smooth, everywhere-different sky for the pixel tests."""
    return write_exr(tmp_path / "sky.exr", smooth_sky(W, H))


def _cycles_uv(d: np.ndarray, rotation_deg: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    phi = math.radians(rotation_deg)
    x = math.cos(phi) * d[:, 0] - math.sin(phi) * d[:, 1]  # the Mapping node's Z rotation
    y = math.sin(phi) * d[:, 0] + math.cos(phi) * d[:, 1]
    z = d[:, 2] / np.sqrt(x * x + y * y + d[:, 2] ** 2)
    return (np.arctan2(y, x) - math.pi) / (-2 * math.pi), (np.arccos(z) - math.pi) / (-math.pi)


def _bilinear(pixels: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    h, w = pixels.shape[:2]
    out = []
    for uu, vv in zip(u, v, strict=True):
        x, y = uu * w - 0.5, (1 - vv) * h - 0.5
        i, j = math.floor(x), math.floor(y)
        fx, fy = x - i, y - j
        value = sum(pixels[(j + dj) % h, (i + di) % w] * (fx if di else 1 - fx) * (fy if dj else 1 - fy)
                    for di in (0, 1) for dj in (0, 1))
        out.append(value)
    return np.array(out)


def _env(path: str, strength: float = 1.0, rotation_deg: float = 0.0) -> environment.Environment:
    scene = {"environment": {"world": "file", "file": path, "strength": strength, "rotation_deg": rotation_deg}}
    return environment.from_scene(scene)


@pytest.mark.parametrize(("direction", "column", "row"), [
    ((1, 0, 0), 0.5 * W - 0.5, 0.5 * H - 0.5),  # +x: the image's centre
    ((0, 1, 0), 0.25 * W - 0.5, 0.5 * H - 0.5),  # +y (into the lamp): a quarter from the left
    ((0, -1, 0), 0.75 * W - 0.5, 0.5 * H - 0.5),  # -y, where the lamp faces
    ((1, 0, 1), 0.5 * W - 0.5, 0.25 * H - 0.5),  # 45 degrees up: a quarter from the top
])
def test_directions_land_where_cycles_puts_them(ramp_exr, direction, column, row):
    d = np.array([direction], dtype=np.float64)
    d /= np.linalg.norm(d)
    r, g, b = _env(ramp_exr).radiance(d)[0]
    assert (r, g, b) == pytest.approx((column, row, 1.0), abs=1e-6)


def test_rotation_is_the_mapping_nodes_z_rotation(ramp_exr):
    # R_z(90 deg) takes +x to +y, so +x looks up where +y did without rotation.
    r, g, _ = _env(ramp_exr, rotation_deg=90.0).radiance(np.array([[1.0, 0.0, 0.0]]))[0]
    assert (r, g) == pytest.approx((0.25 * W - 0.5, 0.5 * H - 0.5), abs=1e-6)


@pytest.mark.seed(7)
def test_radiance_is_cycles_bilinear_lookup_times_strength(smooth_exr, rng):
    d = rng.normal(size=(200, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    env = _env(smooth_exr, strength=2.5, rotation_deg=-30.0)
    expected = 2.5 * _bilinear(env.pixels.astype(np.float64), *_cycles_uv(d, -30.0))
    np.testing.assert_allclose(env.radiance(d), expected, rtol=1e-6)


def test_uniform_environment_gives_pi_times_its_radiance_as_irradiance(tmp_path):
    env = _env(write_exr(tmp_path / "grey.exr", np.full((H, W, 3), 0.3, np.float32)), strength=2.0)
    normals = np.array([[0, -1, 0], [0, 0, 1], [1, 0, 0], [0.6, 0.0, -0.8]], dtype=np.float64)
    # Pixel solid angles are exact; the cosine taken at each 5.6-degree band's centre leaves 0.12 % on the zenith.
    np.testing.assert_allclose(env.irradiance(normals), np.full((4, 3), math.pi * 0.6), rtol=1.5e-3)


@pytest.mark.slow
@pytest.mark.seed(11)
def test_irradiance_is_the_cosine_weighted_integral_of_the_radiance(tmp_path, rng):
    # A sky with a small bright sun: E(n) = sum over pixels of L max(0, n . w) dOmega, by brute force.
    cols, rows = np.meshgrid(np.arange(4 * W) + 0.5, np.arange(4 * H) + 0.5)
    lon, lat = cols / (4 * W) * 2 * np.pi, (0.5 - rows / (4 * H)) * np.pi
    sky = np.stack([1 + 0.5 * np.sin(lon), 1 + 0.4 * np.cos(lat), 1.2 + 0.6 * np.sin(lat)], -1).astype(np.float32)
    sky[40, 200] = 5000.0
    env = _env(write_exr(tmp_path / "sun_sky.exr", sky), strength=1.3, rotation_deg=25.0)
    d, solid = env._pixel_directions()
    normals = np.concatenate([np.eye(3), -np.eye(3), rng.normal(size=(30, 3))])
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    exact = 1.3 * np.array([(np.maximum(0.0, d @ n) * solid) @ sky.reshape(-1, 3).astype(np.float64)
                            for n in normals])
    np.testing.assert_allclose(env.irradiance(normals), exact, rtol=5e-3)


def test_sun_direction_is_the_brightest_region(tmp_path):
    sky = np.full((H, W, 3), 0.5, np.float32)
    sky[5, 40] = 1000.0  # row 5 from the top, column 40
    env = _env(write_exr(tmp_path / "sun.exr", sky))
    u, v = (40 + 0.5) / W, 1 - (5 + 0.5) / H
    phi, lat = (0.5 - u) * 2 * math.pi, (v - 0.5) * math.pi
    expected = [math.cos(lat) * math.cos(phi), math.cos(lat) * math.sin(phi), math.sin(lat)]
    np.testing.assert_allclose(env.sun_direction(), expected, atol=1e-9)


# -- In the tracer -----------------------------------------------------------------------------------

def _flat_clear_lens_oblique(path: str, rotation_deg: float = 20.0) -> dict:
    return scene_with(**{
        "camera": {"type": "perspective", "position": [-300, -700, 250], "target": [0, 0, 0], "up": [0, 0, 1],
                   "fov_deg": 12.0},
        "image": {"width": 24, "height": 24},
        "environment": {"world": "file", "file": path, "strength": 1.5, "rotation_deg": rotation_deg},
        "lamps[0].cuts.height": 0.0,
        "lamps[0].lens.absorption": [0.0, 0.0, 0.0],
        "lamps[0].lens.specular": 0.0,
        "lamps[0].lens.diffuse_color": [0.0, 0.0, 0.0],
    })


def test_flat_clear_lens_mirrors_the_environment_by_its_fresnel_reflectance(smooth_exr):
    scene = _flat_clear_lens_oblique(smooth_exr)
    result = render_passes(scene)
    surface = result.passes["lens_surface"].reshape(-1, 3)
    lens_pixels = np.nonzero(surface.max(axis=1) > 0)[0]
    assert len(lens_pixels) > 100
    cam = make_camera(scene["camera"], 24, 24)
    _, d = eye_rays(cam, lens_pixels)
    mirrored = d * np.array([1.0, -1.0, 1.0])  # the outer face is the plane y = 0
    r = np.array([fresnel_unpolarised(float(cos), 1.49) for cos in d[:, 1]])
    pixels = environment.read_image(smooth_exr).astype(np.float64)
    expected = r[:, None] * 1.5 * _bilinear(pixels, *_cycles_uv(mirrored, 20.0))
    np.testing.assert_allclose(surface[lens_pixels], expected, rtol=1e-5)


def test_eye_rays_that_miss_see_the_environment(smooth_exr):
    scene = _flat_clear_lens_oblique(smooth_exr)
    scene["camera"]["fov_deg"] = 60.0
    result = render_passes(scene)
    cam = make_camera(scene["camera"], 24, 24)
    _, d = eye_rays(cam, np.arange(24 * 24))
    image = result.image.reshape(-1, 3)
    others = sum(values for name, values in result.passes.items() if name != "background").reshape(-1, 3)
    missed = np.nonzero(others.max(axis=1) == 0)[0]
    assert len(missed) > 100
    pixels = environment.read_image(smooth_exr).astype(np.float64)
    expected = 1.5 * _bilinear(pixels, *_cycles_uv(d[missed], 20.0))
    np.testing.assert_allclose(image[missed], expected, rtol=1e-5)


@pytest.mark.slow
def test_body_under_a_uniform_environment_shows_its_colour_times_the_radiance(tmp_path):
    # A Lambertian surface under a uniform world W shows rho W (BLENDER-NOTES: Cycles gave 0.150 for 0.5, 0.3).
    grey = write_exr(tmp_path / "grey.exr", np.full((H, W, 3), 0.3, np.float32))
    scene = scene_with(**{"environment": {"world": "file", "file": grey},
                          "light": {"direction": [0.3, -1, 0.6], "color": [1, 1, 1], "ambient": 0.0, "strength": 0.0},
                          "body.specular": 0.0, "image": {"width": 16, "height": 16}})
    body = render_passes(scene).passes["body"].reshape(-1, 3)
    seen = body[body.max(axis=1) > 0]
    assert len(seen) > 20
    np.testing.assert_allclose(seen, np.broadcast_to(0.3 * np.array(scene["body"]["color"]), seen.shape), rtol=1e-3)


def test_none_is_the_papers_background(smooth_exr):
    plain = render_passes(scene_with(**{"image": {"width": 20, "height": 16}}))
    said = render_passes(scene_with(**{"image": {"width": 20, "height": 16},
                                       "environment": {"world": "none", "file": smooth_exr}}))
    np.testing.assert_array_equal(plain.image, said.image)


def test_a_missing_file_is_named(tmp_path):
    scene = scene_with(**{"environment": {"world": "file", "file": str(tmp_path / "nowhere.exr")}})
    with pytest.raises(SceneError, match=r"^environment\.file: .*does not exist; allowed"):
        engine.render(scene, 4, 4)
    scene["environment"]["file"] = str(tmp_path / "sky.png")
    with pytest.raises(SceneError, match=r"^environment\.file: .*allowed an \.exr or \.hdr file"):
        engine.render(scene, 4, 4)
    garbage = tmp_path / "garbage.exr"
    garbage.write_text("not an image")
    scene["environment"]["file"] = str(garbage)
    with pytest.raises(SceneError, match=r"^environment\.file: .*cannot be read as an image .*allowed an \.exr"):
        engine.render(scene, 4, 4)


@pytest.mark.slow
def test_bundled_worlds_are_found_without_importing_bpy(repo_root):
    code = ("import sys; from core_tracer.raytrace import environment as e; f = e.bundled_folder(); "
            "print(f is not None and all((f / (n + '.exr')).is_file() for n in e.BUNDLED_WORLDS), "
            "'bpy' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], cwd=repo_root, capture_output=True, text=True, check=True)
    found, imported = out.stdout.split()
    assert imported == "False"
    if importlib.util.find_spec("bpy") is not None:
        assert found == "True"


def test_without_blenders_worlds_the_render_says_so_and_names_the_alternative(monkeypatch):
    monkeypatch.setitem(sys.modules, "bpy", None)  # as on a machine without the bpy module
    assert environment.bundled_folder() is None
    scene = scene_with(**{"environment": {"world": "sunset"}})
    with pytest.raises(SceneError, match=r'^environment\.world: "sunset" is one of Blender\'s bundled world images, '
                                         r'which are not on this machine .*allowed "none", or "file"'):
        engine.render(scene, 4, 4)


@pytest.mark.slow
def test_cli_reports_a_missing_environment_file_in_one_line(tmp_path):
    doc = baseline_doc()
    doc["environment"] = {"world": "file", "file": str(tmp_path / "sky.hdr")}
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(doc))
    proc = run_cli("render", path, "-o", tmp_path / "out.png")
    assert_bad_input(proc, "environment.file", "does not exist; allowed an existing .exr or .hdr file")

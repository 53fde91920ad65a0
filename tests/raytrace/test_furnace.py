"""The white furnace: a lamp inside a uniform world of radiance 1, nothing in it emitting (the bulbs
off, no sun). A surface can only send back what reaches it, so no pixel may be brighter than the
world, and a white body must show the world exactly: each light reaches each surface once
(docs/model.md §8.18, "Energy bookkeeping").

On the code before that rule (main 6bc8af6) this test found, at 96 x 96: a white body 1.2501 (the
ambient d = 0.25 of eq. (1) added to the environment's light); the lens surface of a white lens
colour 2.25 r = 0.0871 instead of r = 0.0387 (its reflected share lit three times: as eq. (1)'s
diffuse lens colour under the ambient and under the environment, and as the mirrored sky; with the
paper's default reflector behind a clear lens that put lens pixels at 1.05); and with
``follow_environment`` the body's front face 2.52 brighter than sky and sun together (the image's
own sun lighting it beside the explicit sun that stands for it).

The one approximation is the quadrature of the environment's irradiance (a map of normals,
``environment``): for a uniform world it must give E = pi, and does within ``QUADRATURE``
(``test_uniform_world_irradiance_is_pi``); every bound below allows exactly that.
"""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest
from helpers import baseline_doc, write_exr
from needs import require

from core_tracer import render_passes
from core_tracer.raytrace import environment
from core_tracer.scene.validate import parse_scene

# |E / pi - 1| of a uniform 256 x 128 world over 20 000 random normals is at most 1.7e-4 (measured
# with this test's own sampling): the bound is that with a margin.
QUADRATURE = 5e-4
SIZE = 96


@pytest.fixture(scope="module")
def uniform_world(tmp_path_factory) -> str:
    return write_exr(tmp_path_factory.mktemp("furnace") / "uniform.exr", np.ones((128, 256, 3), np.float32))


def furnace_doc(world: str, *, lens_color=(0.0, 0.0, 0.0), absorption=(0.0, 0.0, 0.0),
                reflector_color=(0.2, 0.2, 0.2)) -> dict:
    """The paper's lamp in the furnace: white body, clear lens (``absorption``), the bulb off, no sun,
    ambient at its default. The reflector mirrors 0.8 and shows ``reflector_color``: together at most
    1 (its constant is a colour of its own, docs/model.md §8.18)."""
    doc = copy.deepcopy(baseline_doc())
    lamp = doc["lamps"][0]
    lamp["bulb"]["on"] = False
    lamp["lens"]["diffuse_color"] = list(lens_color)
    lamp["lens"]["absorption"] = list(absorption)
    lamp["reflector"]["color"] = list(reflector_color)
    doc["body"]["color"] = [1.0, 1.0, 1.0]
    doc["light"].pop("ambient")  # its default, 0.25
    doc["light"]["strength"] = 0.0
    doc["environment"] = {"world": "file", "file": world, "strength": 1.0}
    doc["image"] = {"width": SIZE, "height": SIZE}
    return doc


def test_ambient_default_is_the_papers():
    # The test is about the default: if it changed, the figures above would mean something else.
    assert parse_scene(furnace_doc("x.exr"))["light"]["ambient"] == 0.25


def test_uniform_world_irradiance_is_pi(uniform_world, rng):
    env = environment.from_scene({"environment": {"world": "file", "file": uniform_world, "strength": 1.0,
                                                  "rotation_deg": 0.0}})
    normals = rng.normal(size=(20000, 3))
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    assert np.abs(env.irradiance(normals) / math.pi - 1.0).max() < QUADRATURE
    assert np.array_equal(env.radiance(normals), np.ones((len(normals), 3)))  # lookups are exact


def _render(doc: dict):
    return render_passes(parse_scene(doc), threads=1)


def test_white_body_shows_the_world_exactly(uniform_world):
    result = _render(furnace_doc(uniform_world))
    body = result.passes["body"]
    on_body = body.max(axis=2) > 0
    assert on_body.sum() > SIZE * SIZE // 4
    # E / pi with E = pi: the white body is the world, neither more (ambient added) nor less.
    np.testing.assert_allclose(body[on_body], 1.0, atol=QUADRATURE)
    assert result.image.max() <= 1.0 + QUADRATURE


@pytest.mark.parametrize("lens_color", [(0.0, 0.0, 0.0), (1.0, 1.0, 1.0), (0.05, 0.0, 0.0)],
                         ids=["black", "white", "paper-red"])
@pytest.mark.parametrize("absorption", [(0.0, 0.0, 0.0), (0.02, 1.5, 1.6)], ids=["clear", "red"])
def test_no_pixel_brighter_than_the_world(uniform_world, lens_color, absorption):
    result = _render(furnace_doc(uniform_world, lens_color=lens_color, absorption=absorption))
    assert result.image.max() <= 1.0 + QUADRATURE


def test_lens_reflects_its_fresnel_share_of_the_world_once(uniform_world):
    """The lens surface pass of a white lens colour is the Fresnel reflectance of the outer face times
    the mirrored world (1): the lens colour lit by the world would add to it."""
    doc = furnace_doc(uniform_world, lens_color=(1.0, 1.0, 1.0))
    doc["camera"] = {"type": "orthographic", "position": [0, -500, 0], "target": [0, 0, 0], "up": [0, 0, 1],
                     "width": 20.0}
    doc["image"] = {"width": 9, "height": 9}
    surface = _render(doc).passes["lens_surface"]
    r = ((1.49 - 1.0) / (1.49 + 1.0)) ** 2  # normal incidence
    np.testing.assert_allclose(surface, r, rtol=1e-12)


# -- the sun that follows the environment's ---------------------------------------------------

SKY = 0.5
SUN_RADIANCE = 4000.0
SUN = np.array([0.3, -0.8, 0.5]) / np.linalg.norm([0.3, -0.8, 0.5])


def sky_with_sun(width: int = 512, height: int = 256) -> np.ndarray:
    """A uniform sky of radiance ``SKY`` with a sun disc of radius 1.5 degrees toward ``SUN`` (pixel
    centres looked up as ``environment`` places them, turn 0)."""
    d, _ = environment._pixel_directions(height, width, 0.0)
    pixels = np.full((height * width, 3), SKY, np.float32)
    pixels[d @ SUN >= math.cos(math.radians(1.5))] = SUN_RADIANCE
    return pixels.reshape(height, width, 3)


@pytest.fixture(scope="module")
def sunny_world(tmp_path_factory) -> str:
    return write_exr(tmp_path_factory.mktemp("sunny") / "sunny.exr", sky_with_sun())


def _sunny_env(path: str, follow: bool) -> environment.Environment:
    return environment.from_scene({"environment": {"world": "file", "file": path, "strength": 1.0,
                                                   "rotation_deg": 0.0},
                                   "light": {"follow_environment": follow}})


@pytest.mark.slow
def test_sun_that_follows_the_image_takes_its_sun_out_of_it(sunny_world):
    followed, seen = _sunny_env(sunny_world, True), _sunny_env(sunny_world, False)
    toward = SUN[None, :]
    assert seen.radiance(toward)[0] == pytest.approx(SUN_RADIANCE)
    assert followed.radiance(toward)[0] == pytest.approx(SKY)  # the sky behind the sun
    # The sun's direction (what the explicit sun follows) is the image's own either way.
    np.testing.assert_allclose(followed.sun_direction(), seen.sun_direction(), atol=1e-12)
    assert float(followed.sun_direction() @ SUN) > math.cos(math.radians(0.5))
    # What is left lights a surface as the uniform sky alone: E = pi SKY.
    normals = np.array([[0.0, -1.0, 0.0], SUN, [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
    np.testing.assert_allclose(followed.irradiance(normals) / math.pi, SKY, rtol=QUADRATURE)
    assert (seen.irradiance(normals[:3]) / math.pi > SKY + 1.0).all()  # the image's sun, counted by the map


def test_an_image_without_a_sun_standing_out_keeps_all_its_light(uniform_world):
    """The furnace stays a furnace when the sun follows the environment: a uniform image has no sun
    to take out (its brightest pixels are not brighter than the sky around them)."""
    sky = environment.read_image(uniform_world)
    assert np.array_equal(environment.sunless(sky), sky)
    doc = furnace_doc(uniform_world)
    doc["light"]["follow_environment"] = True
    result = _render(doc)
    on_body = result.passes["body"].max(axis=2) > 0
    np.testing.assert_allclose(result.passes["body"][on_body], 1.0, atol=QUADRATURE)
    assert result.image.max() <= 1.0 + QUADRATURE


def test_the_image_without_its_sun_enters_the_memory_estimate(sunny_world):
    from core_tracer.raytrace import world_image

    scene = {"environment": {"world": "file", "file": sunny_world}, "light": {"follow_environment": False}}
    alone = environment.world_bytes(scene)
    assert alone == world_image.peak_bytes(512, 256, 3)
    scene["light"]["follow_environment"] = True
    assert environment.world_bytes(scene) == alone + 512 * 256 * 12 + 515 * 259 * world_image.PADDED_BYTES


def test_body_lit_by_the_sun_once(sunny_world):
    """The body's front face under the sun that follows the image: the sky's E / pi plus eq. (1)'s
    sun, (1 - d) s cos(theta) C0, and nothing of the image's sun pixels along the same direction."""
    doc = furnace_doc(sunny_world)
    doc["light"].update(strength=1.0, follow_environment=True)
    doc["body"]["specular"] = 0.0
    doc["camera"] = {"type": "orthographic", "position": [90, -500, 45], "target": [90, 0, 45], "up": [0, 0, 1],
                     "width": 10.0}
    doc["image"] = {"width": 5, "height": 5}
    body = _render(doc).passes["body"]
    sun = _sunny_env(sunny_world, True).sun_direction()
    cos_theta = float(-sun[1])  # the front face's normal is -y
    expected = SKY + (1.0 - 0.25) * 1.0 * cos_theta
    np.testing.assert_allclose(body, expected, rtol=QUADRATURE)


# -- the photometric mode -----------------------------------------------------------------------

LUMINANCE = 1000.0  # cd/m², the furnace world's


def photometric_furnace_doc(world: str, **lens) -> dict:
    doc = furnace_doc(world)
    doc["schema"] = "lamp-scene/2"
    doc["light_model"] = "photometric"
    doc["light"]["illuminance_lux"] = 0.0
    doc["environment"].update(scale_by="luminance", luminance_cd_m2=LUMINANCE)
    doc["lamps"][0]["lens"].update({"material": "pmma", "filter": "clear", **lens})
    doc["image"] = {"width": 48, "height": 48}
    return doc


@pytest.mark.parametrize("lens", [{}, {"filter": "red"}, {"material": "polycarbonate"}],
                         ids=["clear-pmma", "red-pmma", "clear-polycarbonate"])
def test_photometric_furnace_never_exceeds_the_world(uniform_world, lens):
    """Y in cd/m² nowhere above the world's luminance; the white body (Smits's white is 1 in every
    band) shows it."""
    result = render_passes(parse_scene(photometric_furnace_doc(uniform_world, **lens)), threads=1)
    Y = result.image[..., 1]
    assert Y.max() <= LUMINANCE * (1.0 + QUADRATURE)
    body = result.passes["body"][..., 1]
    on_body = body > 0
    assert on_body.sum() > 48 * 48 // 4
    np.testing.assert_allclose(body[on_body], LUMINANCE, rtol=QUADRATURE)


# -- the free-form tracer: the same lighting on meshes --------------------------------------------


def test_free_form_meshes_in_the_furnace(uniform_world):
    """A white lens colour on a clear slab mesh and a white body mesh, ambient at its default: the lens
    surface is Fresnel's r of each eye ray times the world (1), the body the world."""
    require("embreex")
    from core_tracer.freeform import render_passes as freeform_passes
    from core_tracer.freeform import shapes
    from core_tracer.raytrace.camera import eye_rays, make_camera

    meshes = {"Slab": shapes.box("Slab", (-30, 0, -30), (30, 3, 30)),
              "Block": shapes.box("Block", (40, 0, -25), (120, 30, 25))}
    scene = parse_scene({
        "schema": "lamp-scene/2", "lamps": [{}], "image": {"width": 32, "height": 32},
        "camera": {"type": "perspective", "position": [-300, -700, 250], "target": [40, 0, 0], "up": [0, 0, 1],
                   "fov_deg": 16.0},
        "environment": {"world": "file", "file": uniform_world},
        "light": {"direction": [0.3, -1, 0.6], "color": [1, 1, 1], "strength": 0.0},  # ambient: its default
        "freeform": {"mesh_file": "furnace.glb", "parts": [
            {"object": "Slab", "role": "lens", "lens": {"ior": 1.49, "specular": 0.8, "diffuse_color": [1, 1, 1],
                                                        "absorption": [0, 0, 0]}},
            {"object": "Block", "role": "body", "body": {"color": [1, 1, 1], "specular": 0.5, "shininess": 30}}]}})
    assert scene["light"]["ambient"] == 0.25
    result = freeform_passes(scene, meshes)
    surface = result.passes["lens_surface"].reshape(-1, 3)
    on_lens = np.nonzero(surface.max(axis=1) > 0)[0]
    assert len(on_lens) > 50
    _, d = eye_rays(make_camera(scene["camera"], 32, 32), on_lens)
    cos_i = d[:, 1]  # the slab's front face is the plane y = 0, its normal -y
    sin_t = np.sqrt(1.0 - cos_i**2) / 1.49
    cos_t = np.sqrt(1.0 - sin_t**2)
    r = 0.5 * (((cos_i - 1.49 * cos_t) / (cos_i + 1.49 * cos_t)) ** 2
               + ((1.49 * cos_i - cos_t) / (1.49 * cos_i + cos_t)) ** 2)
    front = on_lens[np.abs(surface[on_lens, 0] - r) < 0.5 * r]  # the front face (the sides see other angles)
    assert len(front) > 30
    np.testing.assert_allclose(surface[front], np.repeat(r[np.isin(on_lens, front)][:, None], 3, axis=1),
                               rtol=1e-6)
    body = result.passes["body"].reshape(-1, 3)
    on_body = (body.max(axis=1) > 0) & (surface.max(axis=1) == 0)  # seen directly, not through the slab
    assert on_body.sum() > 50
    np.testing.assert_allclose(body[on_body], 1.0, atol=QUADRATURE)
    assert result.image.max() <= 1.0 + QUADRATURE

"""The live preview in the 3D Viewport: its camera, its progressive stages and its drawing.

- The camera made from a viewport's matrices (``lamp_addon.convert.viewport``) must project the
  design exactly as Blender's own view does. The matrices are Blender's: a camera's projection from
  ``Camera.calc_matrix_camera`` (the code the viewport's camera view uses, with the viewport's
  zoom and pan as a scaled, off-centre window) and ``matrix_world.inverted()``; a point on each
  tracer eye ray (``core_tracer.raytrace.camera``) must land on its pixel's centre to 1e-6 of
  the image.
- The progressive stages (``lamp_addon.render.preview``), stepped in the test's own thread:
  coarse then full, restarted on an edit, and a stale job never publishes.
  The viewport session (``lamp_addon.render.viewport``) restarts on design edits, view changes,
  region resizes and moves of the design root, and says why it shows nothing.
- The draw path (``ViewportSession.draw_frame``) drawn into a ``gpu.types.GPUOffScreen`` gives the
  tracer's image back; through Blender's view transform it equals the tracer's image under that
  transform within 1/255. Needs a display: run under ``xvfb-run -a`` (the README's test command
  does); without one those tests skip.
- The engine's film-transparent alpha (``render.engine.body_coverage``) is the tracer's own
  ray-box decision.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import FOUR_LAMPS

import core_tracer
from core_tracer.raytrace.camera import eye_rays, make_camera
from lamp_addon.convert import viewport

pytestmark = pytest.mark.blender


# ---------------------------------------------------------------------------------------------
# The camera


def _rows(matrix) -> list[list[float]]:
    return [list(row) for row in matrix]


def _blender_camera(kind: str, *, sensor_fit: str = "AUTO", shift=(0.0, 0.0), lens: float = 50.0,
                    ortho_scale: float = 0.3, location=(0.35, -1.2, 0.25), rotation=(1.35, 0.1, 0.4)):
    import bpy

    data = bpy.data.cameras.new("View")
    data.type = kind
    data.sensor_fit = sensor_fit
    data.lens = lens
    data.ortho_scale = ortho_scale
    data.shift_x, data.shift_y = shift
    data.clip_start, data.clip_end = 0.01, 100.0
    ob = bpy.data.objects.new("View", data)
    bpy.context.scene.collection.objects.link(ob)
    ob.location = location
    ob.rotation_euler = rotation
    bpy.context.view_layer.update()
    return ob


def _window_matrix(ob, width: int, height: int) -> list[list[float]]:
    import bpy

    depsgraph = bpy.context.evaluated_depsgraph_get()
    return _rows(ob.calc_matrix_camera(depsgraph, x=width, y=height))


def _pixel_errors(camera: dict, width: int, height: int, window, view, world_from_model=None) -> float:
    """Largest distance, in pixels, between each pixel's centre and Blender's projection of a point
    on the tracer's eye ray through it (every pixel of a coarse grid, and the corners)."""
    cam = make_camera(camera, width, height)
    rows = np.unique(np.r_[np.linspace(0, height - 1, 7).astype(int), 0, height - 1])
    cols = np.unique(np.r_[np.linspace(0, width - 1, 9).astype(int), 0, width - 1])
    rr, cc = np.meshgrid(rows, cols, indexing="ij")
    pixels = (rr * width + cc).ravel()
    origins, directions = eye_rays(cam, pixels)
    to_world = viewport.model_matrix() if world_from_model is None else np.asarray(world_from_model)
    clip_from_model = np.asarray(window) @ np.asarray(view) @ to_world
    worst = 0.0
    for t in (150.0, 900.0, 2500.0):  # millimetres along the ray: in front of, at and behind the lamp
        points = np.c_[origins + t * directions, np.ones(len(pixels))]
        clip = points @ clip_from_model.T
        ndc = clip[:, :2] / clip[:, 3:4]
        x = (ndc[:, 0] + 1.0) / 2.0 * width
        y = (1.0 - ndc[:, 1]) / 2.0 * height  # from the top, like the tracer's rows
        worst = max(worst, float(np.max(np.hypot(x - (cc.ravel() + 0.5), y - (rr.ravel() + 0.5)))))
    return worst


@pytest.mark.slow
def test_the_viewport_camera_needs_no_blender():
    """convert.viewport is bpy-free: it imports with bpy and mathutils unavailable."""
    import subprocess
    import sys

    from helpers import ROOT

    code = ("import sys; sys.modules['bpy'] = sys.modules['mathutils'] = None\n"
            "from lamp_addon.convert import viewport\n"
            "window = [[2, 0, 0, 0], [0, 2, 0, 0], [0, 0, -1, -0.02], [0, 0, -1, 0]]\n"
            "view = [[1, 0, 0, 0], [0, 0, 1, 0], [0, -1, 0, -1], [0, 0, 0, 1]]\n"
            "camera = viewport.camera_from_view(64, 64, window, view)\n"
            "assert camera['type'] == 'perspective' and abs(camera['fov_deg'] - 53.130102354) < 1e-6, camera\n"
            "assert max(abs(a - b) for a, b in zip(camera['position'], [0, -1000, 0])) < 1e-9, camera\n"
            "print('ok')\n")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=60)
    assert out.returncode == 0 and out.stdout.strip() == "ok", out.stderr


VIEWS = [
    # kind, sensor fit, shift, region size: landscape, portrait, square, odd sizes, off-centre
    ("PERSP", "AUTO", (0.0, 0.0), (1024, 768)),
    ("PERSP", "AUTO", (0.13, -0.21), (333, 517)),
    ("PERSP", "HORIZONTAL", (-0.3, 0.05), (640, 640)),
    ("PERSP", "VERTICAL", (0.02, 0.4), (801, 299)),
    ("ORTHO", "AUTO", (0.0, 0.0), (1024, 768)),
    ("ORTHO", "VERTICAL", (0.25, -0.1), (411, 733)),
    ("ORTHO", "HORIZONTAL", (-0.05, 0.3), (97, 61)),
]


@pytest.mark.parametrize("kind, fit, shift, size", VIEWS)
def test_viewport_camera_projects_as_blender(bl_scene, kind, fit, shift, size):
    ob = _blender_camera(kind, sensor_fit=fit, shift=shift)
    width, height = size
    window, view = _window_matrix(ob, width, height), _rows(ob.matrix_world.inverted())
    camera = viewport.camera_from_view(width, height, window, view)
    assert camera["type"] == ("perspective" if kind == "PERSP" else "orthographic")
    assert _pixel_errors(camera, width, height, window, view) < 1e-6 * max(width, height)


def test_viewport_camera_in_the_design_roots_space(bl_scene):
    """A built design moved, turned and scaled as a whole: the camera is in the root's local
    space, and the tracer still sees what Blender's view shows."""
    from mathutils import Euler, Matrix

    ob = _blender_camera("PERSP", shift=(0.1, 0.0))
    root = Matrix.LocRotScale((0.4, -0.2, 0.9), Euler((0.2, -0.1, 0.7)), (1.5, 1.5, 1.5))
    model = viewport.model_matrix(_rows(root))
    window, view = _window_matrix(ob, 640, 480), _rows(ob.matrix_world.inverted())
    camera = viewport.camera_from_view(640, 480, window, view, model)
    assert _pixel_errors(camera, 640, 480, window, view, model) < 1e-6 * 640
    ortho = _blender_camera("ORTHO", shift=(0.0, -0.2))
    window, view = _window_matrix(ortho, 640, 480), _rows(ortho.matrix_world.inverted())
    camera = viewport.camera_from_view(640, 480, window, view, model)
    assert _pixel_errors(camera, 640, 480, window, view, model) < 1e-6 * 640


def test_viewport_camera_refuses_an_unevenly_scaled_root(bl_scene):
    from mathutils import Matrix

    ob = _blender_camera("PERSP")
    root = Matrix.Diagonal((1.0, 2.0, 1.0, 1.0))
    with pytest.raises(ValueError, match="scaled unevenly"):
        viewport.camera_from_view(64, 48, _window_matrix(ob, 64, 48), _rows(ob.matrix_world.inverted()),
                                  viewport.model_matrix(_rows(root)))


def _camera_view_window(ob, width: int, height: int, zoom: float, offset: tuple[float, float]):
    """The window matrix of camera view in a region of ``width`` x ``height``, zoomed by ``zoom``
    (the camera's window is 1/zoom of the region's natural size) and panned by ``offset`` (a
    fraction of the region), built as Blender's ``BKE_camera_params_compute_viewplane`` does:
    the viewport's zoom scales the window and its pan adds ``offset * region / viewfac`` to the
    lens shift. Returned with the camera restored."""
    cam = ob.data
    saved = cam.lens, cam.ortho_scale, cam.shift_x, cam.shift_y
    fit = cam.sensor_fit
    if fit == "AUTO":
        fit = "HORIZONTAL" if width >= height else "VERTICAL"
    viewfac = width if fit == "HORIZONTAL" else height
    try:
        cam.lens = saved[0] * zoom
        cam.ortho_scale = saved[1] / zoom
        cam.shift_x = saved[2] + offset[0] * width / viewfac
        cam.shift_y = saved[3] + offset[1] * height / viewfac
        return _window_matrix(ob, width, height)
    finally:
        cam.lens, cam.ortho_scale, cam.shift_x, cam.shift_y = saved


@pytest.mark.parametrize("kind", ["PERSP", "ORTHO"])
@pytest.mark.seed(7)
def test_camera_view_shows_the_cameras_frame(bl_scene, kind, rng):
    """Camera view, zoomed and panned off centre: the tracer's camera projects as the region's
    matrices do, and a point seen by the scene camera at a fraction (fx, fy) of its rendered frame
    lies at the same fraction of the camera border drawn in the viewport."""
    import bpy

    ob = _blender_camera(kind, sensor_fit="HORIZONTAL", shift=(0.05, -0.1))
    bl_scene.render.resolution_x, bl_scene.render.resolution_y = 800, 450
    width, height = 1000, 700
    window = _camera_view_window(ob, width, height, zoom=1.6, offset=(0.12, -0.07))
    view = _rows(ob.matrix_world.inverted())
    camera = viewport.camera_from_view(width, height, window, view)
    assert _pixel_errors(camera, width, height, window, view) < 1e-6 * width

    # The camera border: the camera's frame corners (Camera.view_frame, in the camera's space)
    # projected by the region's matrices.
    depsgraph = bpy.context.evaluated_depsgraph_get()
    corners = [ob.matrix_world @ v for v in ob.data.view_frame(scene=bl_scene)]
    clip = np.asarray(window) @ np.asarray(view)

    def region_xy(point) -> np.ndarray:
        c = clip @ np.r_[np.asarray(point), 1.0]
        return np.array([(c[0] / c[3] + 1) / 2 * width, (c[1] / c[3] + 1) / 2 * height])

    border = np.array([region_xy(c) for c in corners])
    x0, y0 = border.min(axis=0)
    x1, y1 = border.max(axis=0)
    assert (x1 - x0) / (y1 - y0) == pytest.approx(800 / 450, rel=1e-5)  # the render's shape
    render_clip = np.asarray(_rows(ob.calc_matrix_camera(depsgraph, x=800, y=450))) @ np.asarray(view)
    for point in rng.uniform((-0.2, -0.1, -0.1), (0.2, 0.1, 0.1), (20, 3)):
        c = render_clip @ np.r_[point, 1.0]
        fx, fy = (c[0] / c[3] + 1) / 2, (c[1] / c[3] + 1) / 2  # where F12 shows it, in the frame
        expected = np.array([x0 + fx * (x1 - x0), y0 + fy * (y1 - y0)])
        assert np.max(np.abs(region_xy(point) - expected)) < 1e-3  # pixels (single-precision frame)


def test_orthographic_view_sees_the_lamp_behind_the_viewer(bl_scene):
    """Blender's orthographic viewport clips at -clip_end/2 and +clip_end/2 around its eye point,
    so it shows what lies behind the eye: the tracer's rays start on the near plane. The eye
    stands 300 mm behind the lamp's front face, looking the same way as the lamp faces away; the
    lit lenses must show."""
    ob = _blender_camera("ORTHO", location=(0.0, 0.3, 0.0), rotation=(math.pi / 2, 0.0, 0.0))
    window, view = _window_matrix(ob, 64, 48), _rows(ob.matrix_world.inverted())
    near, far = -50.0, 50.0  # a camera cannot clip behind itself; the viewport's matrix does
    window[2][2], window[2][3] = -2.0 / (far - near), -(far + near) / (far - near)
    camera = viewport.camera_from_view(64, 48, window, view)
    assert camera["position"][1] == pytest.approx(300.0 - 50_000.0, abs=1e-3)  # single precision
    assert _pixel_errors(camera, 64, 48, window, view) < 1e-6 * 64
    image = core_tracer.render(core_tracer.parse_scene({**_four_lamps_doc(), "camera": camera,
                                                        "image": {"width": 64, "height": 48}}))
    assert image.max() > 1.0  # a lit lens (values reach ~11); the body alone stays below 1


def _four_lamps_doc() -> dict:
    import json

    return json.loads(FOUR_LAMPS.read_text())


# ---------------------------------------------------------------------------------------------
# The progressive stages


def _four_lamps() -> dict:
    return core_tracer.parse_scene(_four_lamps_doc())


def _refined(lamp_addon, scene: dict, width: int, height: int) -> np.ndarray:
    """The refined stage's image: full resolution at the preview's samples per pixel."""
    samples = lamp_addon.render.preview.REFINE_SAMPLES
    return core_tracer.render_passes(scene, width, height, samples=samples, keep_passes=False).image


@pytest.mark.slow
def test_stages_run_coarse_then_full_then_refined(lamp_addon):
    scene = _four_lamps()
    preview = lamp_addon.render.preview.ProgressivePreview(divisors=(8, 1), threads=1)
    assert not preview.step() and preview.frame() is None  # nothing to do before a restart
    preview.restart(scene, 64, 48)
    assert preview.busy() and preview.frame() is None
    assert preview.step()
    coarse = preview.frame()
    assert (coarse.generation, coarse.stage, coarse.divisor) == (1, 0, 8)
    np.testing.assert_array_equal(coarse.image, core_tracer.render(scene, 8, 6))
    assert preview.take_news() and not preview.take_news()  # one redraw per finished stage
    assert preview.step()
    full = preview.frame()
    assert (full.stage, full.divisor, full.samples) == (1, 1, 1)
    np.testing.assert_array_equal(full.image, core_tracer.render(scene, 64, 48))
    assert preview.busy()  # more samples per pixel to come
    assert preview.step()
    refined = preview.frame()
    assert (refined.stage, refined.divisor, refined.samples) == (2, 1, lamp_addon.render.preview.REFINE_SAMPLES)
    np.testing.assert_array_equal(refined.image, _refined(lamp_addon, scene, 64, 48))
    assert not preview.step() and not preview.busy()
    assert preview.history == [(1, 0), (1, 1), (1, 2)]


@pytest.mark.slow
def test_an_edit_during_refinement_restarts_from_the_coarse_stage(lamp_addon):
    scene = _four_lamps()
    edited = core_tracer.parse_scene({**_four_lamps_doc(), "background": [0.2, 0.3, 0.4]})
    preview = lamp_addon.render.preview.ProgressivePreview(divisors=(8, 1), threads=1)
    preview.restart(scene, 64, 48)
    preview.step()
    preview.step()  # full resolution; the refined stage is next
    refining = preview.job
    preview.restart(edited, 64, 48)
    assert refining.cancelled and refining.run_next_stage() is None  # its refined stage never runs
    while preview.step():
        pass
    assert preview.history == [(1, 0), (1, 1), (2, 0), (2, 1), (2, 2)]
    np.testing.assert_array_equal(preview.frame().image, _refined(lamp_addon, edited, 64, 48))


def test_without_refinement_the_stages_end_at_full_resolution(lamp_addon):
    rp = lamp_addon.render.preview
    assert rp.stage_plan((8, 1), 16) == ((8, 1), (1, 1), (1, 16))
    assert rp.stage_plan((8, 1), 1) == ((8, 1), (1, 1))
    preview = rp.ProgressivePreview(divisors=(8, 1), threads=1, refine_samples=1)
    preview.restart(_four_lamps(), 64, 48)
    while preview.step():
        pass
    assert preview.history == [(1, 0), (1, 1)] and preview.frame().samples == 1


def test_an_edit_restarts_from_the_coarse_stage(lamp_addon):
    scene = _four_lamps()
    edited = core_tracer.parse_scene({**_four_lamps_doc(), "background": [0.2, 0.3, 0.4]})
    preview = lamp_addon.render.preview.ProgressivePreview(divisors=(8, 1), threads=1)
    preview.restart(scene, 64, 48)
    preview.step()  # the coarse image of the first design
    stale = preview.job
    preview.restart(edited, 64, 48)
    assert stale.cancelled and stale.run_next_stage() is None  # the old job's full stage never runs
    assert preview.frame().generation == 1  # still shown until the new coarse image arrives
    preview.step()
    preview.step()
    assert preview.history == [(1, 0), (2, 0), (2, 1)]
    np.testing.assert_array_equal(preview.frame().image, core_tracer.render(edited, 64, 48))


def test_a_stage_finished_after_the_view_changed_is_never_shown(lamp_addon):
    rp = lamp_addon.render.preview
    preview = rp.ProgressivePreview(divisors=(8, 1), threads=1)
    preview.restart(_four_lamps(), 64, 48)
    old = preview.job
    late = old.run_next_stage()  # finishes just as the viewport turns
    preview.restart(_four_lamps(), 80, 48)
    preview.publish(old, late)
    assert preview.frame() is None and preview.history == [] and not preview.take_news()


def test_a_stopped_job_stops_between_bands(lamp_addon):
    """The tracer polls the job's cancel flag between bands: a cancelled stage ends early."""
    rp = lamp_addon.render.preview
    job = rp.PreviewJob(_four_lamps(), 512, 512, generation=1, divisors=(1,), threads=1)
    bands = []
    original = job._cancel.is_set

    def cancel_after_two_bands() -> bool:
        bands.append(1)
        if len(bands) == 2:
            job.cancel()
        return original()

    job._cancel.is_set = cancel_after_two_bands
    assert job.run_next_stage() is None
    assert len(bands) == 2 and not job.done


def _design_session(lamp_addon, bl_scene):
    lamp_addon.design.properties.scene_to_design(bl_scene, _four_lamps())
    session = lamp_addon.render.viewport.ViewportSession(None, in_background=False)
    session.update(bl_scene)
    return session


def _design_session_with_root(lamp_addon, bl_scene):
    """A viewport session of the four-lamp design, and the design's root empty (not yet moved)."""
    import bpy

    session = _design_session(lamp_addon, bl_scene)
    root = bpy.data.objects.new("Lamp Design", None)
    root[lamp_addon.design.root.PART_KEY] = lamp_addon.design.root.ROOT_PART
    bl_scene.collection.objects.link(root)
    return session, root


@pytest.mark.slow
def test_the_viewport_restarts_on_design_edits_and_view_changes(lamp_addon, bl_scene):
    session = _design_session(lamp_addon, bl_scene)
    ob = _blender_camera("PERSP")
    window, view = _window_matrix(ob, 64, 48), ob.matrix_world.inverted()
    session.sync(bl_scene, 64, 48, window, view)
    assert session.preview.generation == 1
    session.sync(bl_scene, 64, 48, window, view)  # a redraw of the same view: keeps going
    assert session.preview.generation == 1
    assert session.preview.step()  # the coarse stage of view 1

    bl_scene.lamp_design.lamps[0].bulb.intensity = (3.0, 2.0, 1.0)  # a design edit
    session.update(bl_scene)
    session.sync(bl_scene, 64, 48, window, view)
    assert session.preview.generation == 2
    ob.location.x += 0.01  # orbiting
    bl_scene.view_layers[0].update()
    session.sync(bl_scene, 64, 48, window, ob.matrix_world.inverted())
    assert session.preview.generation == 3
    session.sync(bl_scene, 80, 48, _window_matrix(ob, 80, 48), ob.matrix_world.inverted())  # region resized
    assert session.preview.generation == 4
    while session.preview.step():
        pass
    assert session.preview.history == [(1, 0), (4, 0), (4, 1), (4, 2)]
    assert session.status() == "Lamp Tracer: full resolution, 16 samples per pixel"
    assert session.preview.frame().image.shape == (48, 80, 3)


@pytest.mark.slow
def test_the_viewport_says_why_an_invalid_design_shows_nothing(lamp_addon, bl_scene):
    """The viewport's text line gives the design's state, its objects' state and the field to change."""
    session = _design_session(lamp_addon, bl_scene)
    bl_scene.lamp_design.lamps[0].bulb.radius = 1000.0  # far outside its reflector
    session.update(bl_scene)
    ob = _blender_camera("PERSP")
    session.sync(bl_scene, 64, 48, _window_matrix(ob, 64, 48), ob.matrix_world.inverted())
    assert session.preview.generation == 0 and session.preview.frame() is None
    status = session.status()
    assert status.startswith("Lamp Tracer: design not valid (not built); Lamp 1 › Bulb › Radius: "), status
    assert "mm" in status.split("Radius: ", 1)[1]  # the allowed range, in mm

    lamp_addon.design.builder.build_lamp(bl_scene, _four_lamps())  # built before the bad edit
    session.update(bl_scene)
    assert session.status().startswith("Lamp Tracer: design not valid (objects as last built); Lamp 1 › Bulb")
    bl_scene.lamp_design.lamps.clear()
    session.update(bl_scene)
    assert session.status() == "Lamp Tracer: no lamp yet: Add Lamp (Lamp tab, Lamps) or apply a preset"


# ---------------------------------------------------------------------------------------------
# Drawing: needs a GPU (a display; xvfb-run in CI)

DRAWN_PNG_ENV = "LAMP_VIEWPORT_PNG"  # set to a path to keep the AgX read-back for a look


def _draw_viewport(lamp_addon, bl_scene, width: int, height: int, window, view) -> dict:
    """What the engine's viewport path draws for this view, read back from an offscreen: the
    session as view_draw drives it (update, sync, both stages, draw_frame), drawn by a real engine
    instance (``tools/make_docs_images.draw_viewport``, which the docs' picture is made with)."""
    import bpy

    from tools.make_docs_images import draw_viewport

    out = draw_viewport(bpy, lamp_addon, bl_scene, width, height, window, view)
    assert out["status"] == "Lamp Tracer: full resolution, 16 samples per pixel"
    return out


def _display(bl_scene, rgba_bottom_up: np.ndarray, path) -> np.ndarray:
    """Blender's own display transform of a scene-linear image (the scene's view settings), as
    8-bit values, top row first: the image saved as a render to PNG and read back."""
    import bpy
    from OpenImageIO import UINT8, ImageBuf

    height, width = rgba_bottom_up.shape[:2]
    image = bpy.data.images.new("drawn", width, height, float_buffer=True, alpha=True)
    try:
        image.pixels.foreach_set(np.ascontiguousarray(rgba_bottom_up, np.float32).ravel())
        settings = bl_scene.render.image_settings
        settings.file_format, settings.color_mode, settings.color_depth = "PNG", "RGB", "8"
        image.save_render(str(path), scene=bl_scene)
    finally:
        bpy.data.images.remove(image)
    return np.asarray(ImageBuf(str(path)).get_pixels(format=UINT8), np.float64)[:, :, :3]


def _srgb(linear: np.ndarray) -> np.ndarray:
    linear = np.clip(linear, 0.0, 1.0)
    return np.where(linear <= 0.0031308, 12.92 * linear, 1.055 * linear ** (1 / 2.4) - 0.055)


def _three_quarter_view(width: int, height: int):
    """A viewport orbited to the lamp's front left, a little above, looking at the body's centre."""
    from mathutils import Vector

    eye, centre = Vector((-0.38, -0.62, 0.22)), Vector((0.0, 0.04, 0.0))
    rotation = (centre - eye).to_track_quat("-Z", "Y").to_euler()
    ob = _blender_camera("PERSP", lens=35.0, location=eye, rotation=rotation)
    return _window_matrix(ob, width, height), ob.matrix_world.inverted()


@pytest.mark.slow
def test_drawn_pixels_are_the_tracers_image_under_the_view_transform(lamp_addon, bl_scene, gpu_context, tmp_path):
    """Standard view transform with an exposure: the drawn region, colour-managed by Blender,
    equals the sRGB encoding of 2^exposure times the tracer's image within 1/255."""
    width, height = 160, 120
    lamp_addon.design.properties.scene_to_design(bl_scene, _four_lamps())
    window, view = _three_quarter_view(width, height)
    drawn = _draw_viewport(lamp_addon, bl_scene, width, height, window, view)
    traced = _refined(lamp_addon, drawn["scene"], width, height)
    assert traced.max() > 5.0  # lit lenses in view, far above display white

    pixels = drawn["pixels"]  # bottom row first, as the GPU stores it
    # Half floats (11-bit mantissa), and the texture's linear filter taking up to ~1e-5 of a
    # neighbouring texel where the rasteriser's texture coordinate is not exactly a texel centre.
    np.testing.assert_allclose(pixels[::-1, :, :3], traced, rtol=2.0 ** -10, atol=2e-4)
    np.testing.assert_array_equal(pixels[:, :, 3], 1.0)

    settings = bl_scene.view_settings
    settings.view_transform, settings.look, settings.exposure, settings.gamma = "Standard", "None", -2.5, 1.0
    shown = _display(bl_scene, pixels, tmp_path / "standard.png")
    expected = np.round(_srgb(traced * 2.0 ** -2.5) * 255.0)
    assert np.max(np.abs(shown - expected)) <= 1.0
    assert len(np.unique(shown[..., 0])) > 50  # a real picture, not a clipped flat disk


@pytest.mark.slow
def test_drawn_pixels_under_agx_match_the_tracers_image_under_agx(lamp_addon, bl_scene, gpu_context, tmp_path):
    """AgX (Blender's default): the drawn region and the tracer's own image, both through Blender's
    AgX, agree within 1/255."""
    import os
    import shutil

    width, height = 320, 240
    lamp_addon.design.properties.scene_to_design(bl_scene, _four_lamps())
    window, view = _three_quarter_view(width, height)
    drawn = _draw_viewport(lamp_addon, bl_scene, width, height, window, view)
    traced = _refined(lamp_addon, drawn["scene"], width, height)
    settings = bl_scene.view_settings
    settings.view_transform, settings.look, settings.exposure = "AgX", "None", 0.0
    shown = _display(bl_scene, drawn["pixels"], tmp_path / "agx-drawn.png")
    reference = np.ones((height, width, 4), np.float32)
    reference[:, :, :3] = traced[::-1]
    expected = _display(bl_scene, reference, tmp_path / "agx-traced.png")
    assert np.max(np.abs(shown - expected)) <= 1.0
    if os.environ.get(DRAWN_PNG_ENV):
        shutil.copyfile(tmp_path / "agx-drawn.png", os.environ[DRAWN_PNG_ENV])


# ---------------------------------------------------------------------------------------------
# The engine's alpha (film transparent) is the tracer's own ray-box decision


@pytest.mark.parametrize("position", [[30.0, -700.0, 20.0], [0.0, 40.0, 0.0]])  # outside; inside the body
def test_body_coverage_is_where_the_tracer_hits_the_body(lamp_addon, position):
    """Alpha 0 exactly where the tracer shows the background: the full background colour in the
    background pass (lens pixels show only a Fresnel fraction of it, body pixels none). A viewport
    may stand anywhere, even inside the body (the scene file's check of the camera is for files)."""
    doc = {**_four_lamps_doc(), "background": [0.2, 0.3, 0.4], "image": {"width": 48, "height": 32}}
    scene = core_tracer.parse_scene(doc)
    scene["camera"] = {**scene["camera"], "position": position, "target": [0.0, 500.0, 0.0], "fov_deg": 60.0}
    passes = core_tracer.render_passes(scene).passes
    coverage = lamp_addon.render.engine.body_coverage(scene, 0, 32)
    background_only = np.all(np.isclose(passes["background"], [0.2, 0.3, 0.4]), axis=-1)
    np.testing.assert_array_equal(coverage == 0, background_only)


@pytest.mark.slow
def test_stages_on_the_worker_thread(lamp_addon):
    """What the engine does: the stages on a worker thread; a restart while it runs means nothing
    of the old job is published afterwards."""
    rp = lamp_addon.render.preview
    scene = _four_lamps()
    preview = rp.ProgressivePreview(divisors=(8, 1), threads=2)
    preview.restart(scene, 64, 48)
    preview.start()
    preview.wait()
    assert preview.history == [(1, 0), (1, 1), (1, 2)] and not preview.busy() and preview.take_news()
    np.testing.assert_array_equal(preview.frame().image, _refined(lamp_addon, scene, 64, 48))

    preview.restart(scene, 640, 480)
    preview.start()
    preview.restart(scene, 64, 40)  # the view changed while the 640x480 job was running
    published_before = len(preview.history)
    preview.start()
    preview.wait()
    assert preview.history[published_before:] == [(3, 0), (3, 1), (3, 2)]
    assert preview.frame().image.shape == (40, 64, 3)


def test_moving_the_design_root_moves_the_view_of_the_lamp(lamp_addon, bl_scene):
    """The tracer's camera is the viewport in the root's local space: a root moved 0.2 m to the
    right shows the lamp 200 mm further right, i.e. the camera 200 mm to the left in model space."""
    session, root = _design_session_with_root(lamp_addon, bl_scene)
    ob = _blender_camera("PERSP")
    window, view = _window_matrix(ob, 64, 48), ob.matrix_world.inverted()
    session.update(bl_scene)
    session.sync(bl_scene, 64, 48, window, view)
    before = session.scene["camera"]["position"]
    root.location.x = 0.2
    bl_scene.view_layers[0].update()
    session.update(bl_scene)  # the depsgraph update of the root
    session.sync(bl_scene, 64, 48, window, view)
    assert session.preview.generation == 2
    after = session.scene["camera"]["position"]
    np.testing.assert_allclose(np.subtract(after, before), [-200.0, 0.0, 0.0], atol=1e-3)


@pytest.mark.parametrize("size, divisor", [((1024, 768), 8), ((1920, 1080), 16), ((3840, 2160), 32),
                                           ((300, 200), 4), ((200, 150), 2), ((40, 30), 2)])
def test_the_coarse_stage_keeps_to_its_pixel_budget(lamp_addon, size, divisor):
    rp = lamp_addon.render.preview
    assert rp.coarse_divisor(*size) == divisor
    assert rp.stages_for(*size) == (divisor, 1)
    w, h = rp.stage_size(*size, divisor)
    assert w * h <= rp.COARSE_PIXELS * 1.05  # (sizes round up)


def test_an_unevenly_scaled_root_is_said_and_undone(lamp_addon, bl_scene):

    session, root = _design_session_with_root(lamp_addon, bl_scene)
    ob = _blender_camera("PERSP")
    window, view = _window_matrix(ob, 64, 48), ob.matrix_world.inverted()
    root.scale = (1.0, 2.0, 1.0)
    bl_scene.view_layers[0].update()
    session.update(bl_scene)
    session.sync(bl_scene, 64, 48, window, view)
    assert "scaled unevenly" in session.status() and session.preview.generation == 0
    root.scale = (2.0, 2.0, 2.0)  # a uniform scale is fine
    bl_scene.view_layers[0].update()
    session.update(bl_scene)
    session.sync(bl_scene, 64, 48, window, view)
    assert session.status() == "Lamp Tracer: rendering" and session.preview.generation == 1

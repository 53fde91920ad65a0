"""Shared fixtures. Their names are stable: every test module of the project uses them.

``bpy`` is imported lazily, inside the fixtures, so the tracer's tests run without it.

Session fixtures
- ``repo_root``: ``pathlib.Path`` of the repository (the extension's source folder).
- ``blender_user_resources``: the temporary folder set as ``BLENDER_USER_RESOURCES``. It is put into the
  environment when this file is imported, which pytest does before any test module can import bpy,
  so Blender's preferences, extensions and caches never touch the home folder.
- ``addon``: enables the add-on from the working tree through a development extension repository
  (``tools/dev_extension.py``, the same set-up as ``tools/compare_preset.py``) and returns its module name,
  ``"bl_ext.lamp_dev.lamp_styling"``. Disabled again at the end of the session.
- ``lamp_addon``: the add-on's ``lamp_addon`` package as Blender imported it (``lamp_addon.design.properties``,
  ``lamp_addon.design.builder``, ...).
- ``addon_core``: the add-on's own copy of ``core_tracer`` (``bl_ext.lamp_dev.lamp_styling.core_tracer``).
  Catch ``addon_core.SceneError`` for errors raised inside the add-on: the top-level ``core_tracer``
  package that the tracer tests import is a different module object with its own ``SceneError``.

Function fixtures
- ``rng``: a ``numpy.random.Generator`` seeded by the test's ``@pytest.mark.seed(N)`` (on the test, its class
  or its module), else by its ``seed`` parameter, else by ``DEFAULT_SEED``: the same numbers on every run.
- ``bl_scene``: ``bpy.context.scene`` of the freshly reset file.
- ``gpu_context``: Blender's ``gpu`` module with its GPU context made (skipped without a display).
- ``startup_scene``: Blender's factory startup file (Cube, Camera, Light; the add-on stays enabled),
  checked to be what the tests expect of it; its scene.
- ``world_images`` (session): Blender's folder of world images (the bpy wheel's); without it the test
  skips, and fails under CI (``tests/needs.py``).

Hypothesis runs with the profile ``lamp`` registered here: no example database left in the work tree,
no deadline (a shared machine may pause any example); ``helpers.fuzz(n)`` sets the examples a test.
- ``_reset_blender`` (autouse): before every test that uses ``addon`` (directly or through another
  fixture) or is marked ``blender``, ``bpy.ops.wm.read_homefile(use_empty=True)`` empties the file;
  it keeps the enabled add-ons.
"""

from __future__ import annotations

import atexit
import os
import shutil
import sys
import tempfile
from pathlib import Path

import needs
import numpy as np
import pytest
from hypothesis import HealthCheck, settings

from core_tracer.raytrace import environment

REPO_ROOT = Path(__file__).resolve().parent.parent
EXTENSION_ID = "lamp_styling"
DEV_REPO_MODULE = "lamp_dev"
DEFAULT_SEED = 1990  # the paper's year

# Before bpy can be imported by anything: Blender reads this once, at start-up.
_USER_RESOURCES = tempfile.mkdtemp(prefix="lamp-blender-user-")
os.environ["BLENDER_USER_RESOURCES"] = _USER_RESOURCES
atexit.register(shutil.rmtree, _USER_RESOURCES, True)  # removes the link to the repository, not its target

if str(REPO_ROOT) not in sys.path:  # `import core_tracer` however pytest was started
    sys.path.insert(0, str(REPO_ROOT))

settings.register_profile("lamp", deadline=None, database=None,
                          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                                 HealthCheck.function_scoped_fixture])
settings.load_profile("lamp")


@pytest.fixture(scope="session")
def repo_root() -> Path:
    return REPO_ROOT


@pytest.fixture(scope="session")
def blender_user_resources() -> Path:
    return Path(_USER_RESOURCES)


@pytest.fixture(scope="session")
def addon(blender_user_resources) -> str:
    import bpy

    from tools import dev_extension

    with dev_extension.enabled_from_source(bpy, DEV_REPO_MODULE, reuse_enabled=False, strict=True) as module_name:
        assert module_name in sys.modules, f"{module_name} did not load"
        yield module_name


@pytest.fixture(scope="session")
def lamp_addon(addon):
    return sys.modules[f"{addon}.lamp_addon"]


@pytest.fixture(scope="session")
def addon_core(addon):
    return sys.modules[f"{addon}.core_tracer"]


@pytest.fixture(autouse=True)
def _reset_blender(request):
    if "addon" in request.fixturenames or request.node.get_closest_marker("blender"):
        import bpy

        bpy.ops.wm.read_homefile(use_empty=True)
    yield


@pytest.fixture
def bl_scene(addon):
    import bpy

    return bpy.context.scene


@pytest.fixture
def rng(request) -> np.random.Generator:
    marker = request.node.get_closest_marker("seed")
    if marker is not None:
        seed = marker.args[0]
    elif "seed" in request.fixturenames:
        seed = request.getfixturevalue("seed")
    else:
        seed = DEFAULT_SEED
    return np.random.default_rng(seed)


@pytest.fixture
def gpu_context(bl_scene):
    """Blender's GPU module, initialised. The bpy module starts in background mode and creates its
    GPU context the first time a draw engine renders: a Workbench render of an empty scene."""
    import os

    import bpy

    if not os.environ.get("DISPLAY") and not os.environ.get("WAYLAND_DISPLAY"):
        pytest.skip("GPU drawing needs a display: run the tests under `xvfb-run -a` (docs/model.md)")
    import gpu

    try:
        gpu.types.GPUOffScreen(4, 4).free()
    except SystemError:
        camera = bpy.data.objects.new("GPU start", bpy.data.cameras.new("GPU start"))
        bl_scene.collection.objects.link(camera)
        bl_scene.camera = camera
        bl_scene.render.engine = "BLENDER_WORKBENCH"
        bl_scene.render.resolution_x = bl_scene.render.resolution_y = 4
        bpy.ops.render.render()
        bl_scene.camera = None
        bpy.data.objects.remove(camera)
        try:
            gpu.types.GPUOffScreen(4, 4).free()
        except SystemError as e:
            pytest.skip(f"no GPU context on this display: {e}")
    return gpu


@pytest.fixture
def startup_scene(addon):
    """Blender's factory startup file (the add-on stays enabled); its scene."""
    import bpy

    bpy.ops.wm.read_homefile(use_factory_startup=True)
    scene = bpy.context.scene
    assert {o.name for o in bpy.data.objects} == {"Cube", "Camera", "Light"} and hasattr(scene, "lamp_design")
    assert scene.render.engine == "BLENDER_EEVEE" and scene.view_settings.exposure == 0.0
    return scene


@pytest.fixture(scope="session")
def world_images() -> Path:
    folder = environment.bundled_folder()
    if folder is None:
        needs.missing("Blender's world images are not on this machine (no bpy module)")
    return folder

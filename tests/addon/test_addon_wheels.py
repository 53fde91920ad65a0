"""The bundled Embree binding: per-platform zips from ``tools/build-extension --split-platforms``, each
with only its own ``embreex`` wheel, and the linux one installs headless with the wheel's module usable
from the extension's own site-packages (not the test environment's copy)."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import tomllib
import zipfile
from pathlib import Path

import pytest
from helpers import ROOT

pytestmark = pytest.mark.slow

PLATFORMS = {"linux_x64": "manylinux", "windows_x64": "win_amd64", "macos_arm64": "macosx"}


@pytest.fixture(scope="module")
def split_zips(tmp_path_factory) -> dict[str, Path]:
    out = tmp_path_factory.mktemp("dist")
    env = dict(os.environ, PYTHON=sys.executable)
    env.pop("BLENDER", None)
    proc = subprocess.run([str(ROOT / "tools" / "build-extension"), "--split-platforms", str(out)],
                          capture_output=True, text=True, env=env, timeout=600)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    zips = [Path(line) for line in proc.stdout.split()]
    assert all(z.parent == out and z.is_file() for z in zips)
    return {z.stem.split("-")[-1]: z for z in zips}


def test_manifest_lists_a_wheel_per_platform():
    manifest = tomllib.loads((ROOT / "blender_manifest.toml").read_text())
    assert manifest["platforms"] == ["linux-x64", "windows-x64", "macos-arm64"]
    wheels = manifest["wheels"]
    for tag in PLATFORMS.values():
        assert sum(tag in w and "cp311" in w and "embreex-4.4.0.post1" in w for w in wheels) == 1


def test_one_zip_per_platform_with_only_its_wheel(split_zips):
    assert set(split_zips) == set(PLATFORMS)
    for platform, zip_path in split_zips.items():
        names = zipfile.ZipFile(zip_path).namelist()
        wheels = [n for n in names if n.endswith(".whl")]
        assert len(wheels) == 1 and PLATFORMS[platform] in wheels[0], (platform, wheels)
        assert "lamp_addon/__init__.py" in names and "core_tracer/__init__.py" in names


INSTALL_SCRIPT = textwrap.dedent("""
    import os, sys
    import bpy, addon_utils

    result = bpy.ops.extensions.package_install_files(filepath=sys.argv[1], repo="user_default",
                                                      enable_on_install=True)
    assert result == {"FINISHED"}, result
    assert addon_utils.check("bl_ext.user_default.lamp_styling")[1], "not enabled after install"
    site = os.path.join(os.environ["BLENDER_USER_RESOURCES"], "extensions", ".local", "lib",
                        "python3.11", "site-packages")
    assert os.path.isdir(os.path.join(site, "embreex")), os.listdir(site)
    # The test environment has its own embreex; import the installed one to show that it works.
    sys.modules.pop("embreex", None)
    sys.path.insert(0, site)
    import numpy as np
    import embreex
    from embreex import rtcore_scene, mesh_construction
    assert embreex.__file__.startswith(site), embreex.__file__
    scene = rtcore_scene.EmbreeScene()
    triangle = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]]], dtype=np.float32)
    mesh_construction.TriangleMesh(scene, triangle)
    hits = scene.run(np.array([[0.25, 0.25, 1.0]], np.float32), np.array([[0, 0, -1.0]], np.float32), output=1)
    assert hits["geomID"][0] == 0 and abs(hits["tfar"][0] - 1.0) < 1e-6, hits
    print("WHEEL-OK")
""")


def test_linux_zip_installs_with_a_working_embree(split_zips, tmp_path):
    script = tmp_path / "install.py"
    script.write_text(INSTALL_SCRIPT)
    env = dict(os.environ, BLENDER_USER_RESOURCES=str(tmp_path / "user"))
    proc = subprocess.run([sys.executable, str(script), str(split_zips["linux_x64"])], capture_output=True,
                          text=True, env=env, timeout=300, cwd=tmp_path)
    assert proc.returncode == 0 and "WHEEL-OK" in proc.stdout, proc.stdout[-3000:] + proc.stderr[-3000:]

"""The extension as a user gets it: built and validated by Blender's own tool, installed headless from
the zip, enabled, used, disabled and enabled again.

The build runs ``tools/build-extension`` (Blender's ``blender_ext.py`` from the bpy wheel); the install
runs in a fresh Python process with its own ``BLENDER_USER_RESOURCES``, so it neither sees nor
disturbs the development copy of the add-on that the other tests enable.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import zipfile
from pathlib import Path

import pytest
from helpers import ROOT

pytestmark = pytest.mark.slow

MANIFEST_ID = "lamp_styling"


@pytest.fixture(scope="module")
def built_zip(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("dist")
    env = dict(os.environ, PYTHON=sys.executable)
    env.pop("BLENDER", None)
    proc = subprocess.run([str(ROOT / "tools" / "build-extension"), str(out)], capture_output=True, text=True,
                          env=env, timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    zip_path = Path(proc.stdout.strip().splitlines()[-1])
    assert zip_path.parent == out and zip_path.is_file()
    return zip_path


def _blender_ext() -> Path:
    import importlib.util

    spec = importlib.util.find_spec("bpy")
    return sorted(Path(spec.submodule_search_locations[0]).glob("*/scripts/addons_core/bl_pkg/cli/blender_ext.py"))[-1]


def test_zip_contents(built_zip):
    names = set(zipfile.ZipFile(built_zip).namelist())
    for required in ("blender_manifest.toml", "__init__.py", "lamp_addon/__init__.py",
                     "lamp_addon/design/properties.py", "lamp_addon/convert/meshes/builder.py",
                     "core_tracer/__init__.py", "core_tracer/scene/validate.py", "core_tracer/scene/spec.py"):
        assert required in names
    presets = {p.name for p in (ROOT / "presets").glob("*.json")}
    assert presets and {f"presets/{p}" for p in presets} <= names  # the built-in presets travel
    assert "presets/freeform-sculpted-wrap-lamp.glb" in names  # with the free-form example's meshes
    thumbnails = {p.name for p in (ROOT / "presets" / "thumbnails").glob("*.png")}
    assert len(thumbnails) == len(presets) and {f"presets/thumbnails/{t}" for t in thumbnails} <= names
    for name in names:
        top = name.split("/")[0]
        assert top not in {"tests", "tools", "benchmarks", "docs", ".ci", ".venv", "dist", ".git"}, name
        assert "__pycache__" not in name and not name.endswith(".pyc"), name
        assert name not in {"pyproject.toml", "requirements.txt", ".gitignore"}, name


def test_blender_validator_accepts_the_zip(built_zip):
    proc = subprocess.run([sys.executable, str(_blender_ext()), "validate", str(built_zip)], capture_output=True,
                          text=True, timeout=120)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "Success" in proc.stdout


def test_manifest_rules():
    import tomllib

    manifest = tomllib.loads((ROOT / "blender_manifest.toml").read_text())
    assert manifest["id"] == MANIFEST_ID and manifest["name"] == "Lamp Styling"
    assert manifest["license"] == ["SPDX:GPL-3.0-or-later"]
    assert manifest["blender_version_min"] == "4.2.0"
    for text in (manifest["tagline"], *manifest["permissions"].values()):
        assert len(text) <= 64 and text[-1] not in ".!?,;:"
    assert "files" in manifest["permissions"]
    assert (ROOT / "__init__.py").read_text().count("import") == 1  # the root only hands over


INSTALL_SCRIPT = textwrap.dedent("""
    import os, sys
    import bpy
    import addon_utils

    def fail(ex):
        raise ex

    zip_path = sys.argv[1]
    name = "bl_ext.user_default.{id}"
    result = bpy.ops.extensions.package_install_files(filepath=zip_path, repo="user_default",
                                                      enable_on_install=True)
    assert result == {{"FINISHED"}}, result
    assert addon_utils.check(name)[1], "not enabled after install"
    mod = sys.modules[name]
    installed = os.path.dirname(mod.__file__)
    assert installed.startswith(os.environ["BLENDER_USER_RESOURCES"]), installed

    # Use it: a built-in preset from the installed copy, built as objects by the operator.
    scene = mod.core_tracer.scene.load_scene(os.path.join(installed, "presets", "paper-baseline.json"))
    mod.lamp_addon.design.properties.scene_to_design(bpy.context.scene, scene)
    assert bpy.ops.lamp.build() == {{"FINISHED"}}
    assert "Lamp 1 Lens" in bpy.data.objects

    addon_utils.disable(name, default_set=True, handle_error=fail)
    assert not hasattr(bpy.types.Scene, "lamp_design")
    assert not hasattr(bpy.types, "LAMP_OT_build") and not hasattr(bpy.types, "LAMP_PT_design")

    addon_utils.enable(name, default_set=True, handle_error=fail)
    assert hasattr(bpy.types, "LAMP_PT_design")
    # The design stored in the scene survived: the properties read it back.
    assert mod.lamp_addon.design.properties.design_to_scene(bpy.context.scene) == scene
    assert bpy.ops.lamp.build() == {{"FINISHED"}}
    assert len([o for o in bpy.data.objects if o.get("lamp_part")]) == 7  # the root and its six parts

    addon_utils.disable(name, default_set=True, handle_error=fail)
    addon_utils.enable(name, default_set=True, handle_error=fail)
    print("INSTALL-OK")
""").format(id=MANIFEST_ID)


def test_install_enable_disable_enable(built_zip, tmp_path):
    script = tmp_path / "install.py"
    script.write_text(INSTALL_SCRIPT)
    env = dict(os.environ, BLENDER_USER_RESOURCES=str(tmp_path / "user"))
    proc = subprocess.run([sys.executable, str(script), str(built_zip)], capture_output=True, text=True, env=env,
                          timeout=300, cwd=tmp_path)
    assert proc.returncode == 0 and "INSTALL-OK" in proc.stdout, proc.stdout[-3000:] + proc.stderr[-3000:]

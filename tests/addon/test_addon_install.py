"""The extension as a user gets it: built and validated by Blender's own tool, installed headless from
the zip, enabled, used, disabled and enabled again; and the walk a designer makes with it through the
LED presets (F12 with the Lamp Tracer, Measure Design).

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


# Both scripts start so: the built zip (``zip_path``) installed into the user's extensions and
# enabled; ``mod`` its module, ``installed`` its folder.
INSTALLED = textwrap.dedent(f"""
    name = "bl_ext.user_default.{MANIFEST_ID}"
    result = bpy.ops.extensions.package_install_files(filepath=zip_path, repo="user_default",
                                                      enable_on_install=True)
    assert result == {{"FINISHED"}}, result
    assert addon_utils.check(name)[1], "not enabled after install"
    mod = sys.modules[name]
    installed = os.path.dirname(mod.__file__)""").strip()

INSTALL_SCRIPT = textwrap.dedent("""
    import os, sys
    import bpy
    import addon_utils

    def fail(ex):
        raise ex

    zip_path = sys.argv[1]
    {installed}
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
""").format(id=MANIFEST_ID, installed=INSTALLED)


def test_install_enable_disable_enable(built_zip, tmp_path):
    script = tmp_path / "install.py"
    script.write_text(INSTALL_SCRIPT)
    env = dict(os.environ, BLENDER_USER_RESOURCES=str(tmp_path / "user"))
    proc = subprocess.run([sys.executable, str(script), str(built_zip)], capture_output=True, text=True, env=env,
                          timeout=300, cwd=tmp_path)
    assert proc.returncode == 0 and "INSTALL-OK" in proc.stdout, proc.stdout[-3000:] + proc.stderr[-3000:]


LED_WALK_SCRIPT = textwrap.dedent("""
    import glob, json, os, sys, time
    import bpy
    import addon_utils
    import numpy as np

    zip_path, out = sys.argv[1], sys.argv[2]
    {installed}
    walked = {{}}
    for preset in sorted(glob.glob(os.path.join(installed, "presets", "led-*.json"))):
        started = time.perf_counter()
        bpy.ops.wm.read_homefile(use_factory_startup=True)
        assert addon_utils.check(name)[1], "disabled by the startup file"
        bpy.ops.lamp.preset_refresh()
        wm = bpy.context.window_manager
        wm.lamp_presets_index = next(i for i, item in enumerate(wm.lamp_presets)
                                     if os.path.basename(item.file) == os.path.basename(preset))
        assert bpy.ops.lamp.preset_apply() == {{"FINISHED"}}, preset
        scene = bpy.context.scene
        scene.render.engine = mod.lamp_addon.render.engine.ENGINE_ID
        scene.render.resolution_percentage = 50
        settings = scene.render.image_settings
        settings.file_format, settings.color_depth = "OPEN_EXR", "32"
        stem = os.path.splitext(os.path.basename(preset))[0]
        assert bpy.ops.render.render() == {{"FINISHED"}}, preset
        f12 = os.path.join(out, stem + ".exr")
        bpy.data.images["Render Result"].save_render(f12, scene=scene)
        image = bpy.data.images.load(f12)
        pixels = np.array(image.pixels[:], dtype=np.float32).reshape(image.size[1], image.size[0], 4)[:, :, :3]
        y = pixels @ np.array([0.2126, 0.7152, 0.0722], dtype=np.float32)  # Rec.709 luminance, scene-linear
        assert bpy.ops.lamp.measures_run() == {{"FINISHED"}}, preset
        folder = scene.lamp_measures.folder
        walked[stem] = {{"size": list(image.size), "max": float(y.max()), "median": float(np.median(y)),
                        "lit_fraction": float((y > 0.5).mean()), "folder": folder, "files": sorted(os.listdir(folder)),
                        "functions": sorted(json.load(open(os.path.join(folder, "measures.json")))["functions"]),
                        "seconds": time.perf_counter() - started}}
        print(stem, walked[stem], flush=True)
    print("LED-WALK " + json.dumps(walked))
""").format(id=MANIFEST_ID, installed=INSTALLED)


def test_the_four_led_presets_render_lit_and_measure_from_the_installed_zip(built_zip, tmp_path):
    """The walk a designer makes after installing the zip: each LED preset applied from the preset
    browser of the installed copy, F12 with the Lamp Tracer (at half size), then Measure Design; the
    pictures are lit and each measures folder holds its report (``measures.json``, ``measures.png``)
    with a figure for every function of the lamp."""
    import json

    script = tmp_path / "led_walk.py"
    script.write_text(LED_WALK_SCRIPT)
    (tmp_path / "out").mkdir()
    env = dict(os.environ, BLENDER_USER_RESOURCES=str(tmp_path / "user"))
    proc = subprocess.run([sys.executable, str(script), str(built_zip), str(tmp_path / "out")], capture_output=True,
                          text=True, env=env, timeout=1800, cwd=tmp_path)
    assert proc.returncode == 0 and "LED-WALK " in proc.stdout, proc.stdout[-3000:] + proc.stderr[-3000:]
    walked = json.loads(proc.stdout.split("LED-WALK ", 1)[1].splitlines()[0])
    presets = sorted(p.stem for p in (ROOT / "presets").glob("led-*.json"))
    assert sorted(walked) == presets and len(presets) == 4
    for stem, seen in walked.items():
        doc = json.loads((ROOT / "presets" / f"{stem}.json").read_text(encoding="utf-8"))
        w, h = doc["image"]["width"] // 2, doc["image"]["height"] // 2
        assert seen["size"] == [w, h], stem
        # lit: the lamp's light stands out of its night surroundings (the light guide is a thin line: 0.18 %)
        assert seen["lit_fraction"] > 0.001 and seen["max"] > 20 * max(seen["median"], 1e-3), (stem, seen)
        assert {"measures.json", "measures.png"} <= set(seen["files"]), (stem, seen)
        assert seen["functions"], stem

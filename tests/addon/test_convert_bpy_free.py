"""The conversion layer (``lamp_addon.convert``) imports and works without Blender.

The add-on's modules use relative imports (inside Blender the package is ``bl_ext.<repo>.lamp_styling``),
so the repository is imported here as a package of its own, ``lamp_styling``, in a fresh interpreter
where ``import bpy`` and ``import mathutils`` fail.
"""

from __future__ import annotations

import math
import subprocess
import sys

import pytest
from helpers import ROOT

pytestmark = pytest.mark.slow

PRELUDE = f"""
import importlib, importlib.util, pkgutil, sys
sys.modules["bpy"] = None  # any 'import bpy' now raises ImportError
sys.modules["mathutils"] = None
spec = importlib.util.spec_from_file_location("lamp_styling", {str(ROOT / "__init__.py")!r},
                                              submodule_search_locations=[{str(ROOT)!r}])
sys.modules["lamp_styling"] = importlib.util.module_from_spec(spec)  # the package, its __init__ not run
convert = importlib.import_module("lamp_styling.lamp_addon.convert")
"""


def _run(code: str) -> str:
    proc = subprocess.run([sys.executable, "-c", PRELUDE + code], capture_output=True, text=True, timeout=120,
                          cwd=ROOT)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return proc.stdout


def test_every_convert_module_imports_without_blender():
    out = _run("""
prefix = "lamp_styling.lamp_addon.convert."
names = sorted(m.name.removeprefix(prefix) for m in pkgutil.walk_packages(convert.__path__, prefix))
for name in names:
    importlib.import_module(f"lamp_styling.lamp_addon.convert.{name}")
loaded = [m for m, v in sys.modules.items() if v is not None and (m.split(".")[0] in ("bpy", "mathutils"))]
assert not loaded, loaded
print(" ".join(names))
""")
    assert set(out.split()) >= {"cycles", "layout", "meshes", "units"}


def test_cycles_numbers_and_layout_without_blender():
    out = _run("""
from lamp_styling.lamp_addon.convert import cycles, layout
from lamp_styling.core_tracer.scene.validate import parse_scene
a = [0.02, 1.5, 1.6]
density, color = cycles.absorption_volume(a)
print(density, *(density * (1 - c) / 1000 for c in color))  # Cycles absorbs Density (1 - Color) per BU
print(*cycles.emission_of([8, 7, 6]), cycles.emission_of([8, 7, 6], on=False)[0])
print(cycles.blinn_roughness(20.0), cycles.sun_strength(0.25))
doc = parse_scene({"schema": "lamp-scene/1", "lamps": [{}]})
doc = layout.design_with_new_lamp(doc, 0)
print(len(doc["lamps"]), doc["lamps"][1]["center"][0] - doc["lamps"][0]["center"][0],
      2 * doc["lamps"][0]["lens"]["radius"] + layout.MARGIN_MM)
""")
    lines = out.splitlines()
    density, *absorbed = map(float, lines[0].split())
    assert density == pytest.approx(1600.0) and absorbed == pytest.approx([0.02, 1.5, 1.6], rel=1e-12)
    assert lines[1] == "8 (1.0, 0.875, 0.75) 0.0"
    n = 20.0
    roughness, sun = map(float, lines[2].split())
    assert math.isclose(roughness, (2 / (n + 2)) ** 0.25) and math.isclose(sun, math.pi * 0.75)
    count, step, expected = lines[3].split()
    assert count == "2" and float(step) == pytest.approx(float(expected))  # right of the first, 5 mm apart

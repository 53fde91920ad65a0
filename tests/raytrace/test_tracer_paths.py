"""Path classes against Table 1, symmetry, determinism and the bpy-free split."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from helpers import PRESETS, ROOT, scene_with

from core_tracer import load_scene, render, render_passes
from core_tracer.raytrace import paths

PRESET_FILES = sorted(PRESETS.glob("*.json"))


def test_table_1_is_the_papers():
    assert set(paths.TABLE_1) == set(range(1, 13))
    assert paths.TABLE_1[2] == (frozenset({6, 7, 8}), frozenset({3, 9, 11, 12}))
    assert paths.TABLE_1[5] == (frozenset({3, 9, 11, 12}), frozenset({6, 7, 8}))
    for end in paths.ENDS:
        table = paths.TABLE_1 if end in paths.TABLE_1 else paths.PLATE_TABLE if end in paths.PLATE_TABLE else \
            paths.GUIDE_TABLE
        assert table[end] == (frozenset(), frozenset())
    # every class the classifier can produce is a class of the paper, of the prism plate's or the guide's table
    assert set(np.unique(paths.CLASS_OF)) - {0} <= set(range(1, 13)) | set(paths.PLATE_TABLE) | set(paths.GUIDE_TABLE)
    assert set(paths.GUIDE_TABLE) - set(paths.PLATE_TABLE) - set(range(1, 13)) == set(range(20, 23))
    assert set(paths.PLATE_TABLE) - set(range(1, 13)) == set(range(13, 20))


@pytest.mark.slow
@pytest.mark.parametrize("preset", PRESET_FILES, ids=lambda p: p.stem)
def test_every_transition_while_rendering_presets_is_in_table_1(preset):
    scene = load_scene(preset)
    result = render_passes(scene, 64, 48, record_transitions=True)
    seen = result.stats["transitions"]
    assert seen, "no transitions recorded"
    bad = [t for t in seen if not paths.allowed(*t)]
    assert not bad, f"transitions outside Table 1: {bad}"
    assert np.all(np.isfinite(result.image)) and np.all(result.image >= 0)


@pytest.mark.slow
@pytest.mark.parametrize("samples", [1, 8])
def test_recording_transitions_changes_no_pixel(samples):
    """Without recording, the rays carry no path classes (``rays.UNRECORDED``): the same image and
    passes, bit for bit, as a render that records every transition."""
    scene = load_scene(PRESETS / "four-lamp-rear-combination.json")
    plain = render_passes(scene, 64, 48, samples=samples, threads=1)
    recorded = render_passes(scene, 64, 48, samples=samples, threads=1, record_transitions=True)
    assert not plain.stats["transitions"] and recorded.stats["transitions"]
    for name in plain.passes:
        np.testing.assert_array_equal(plain.passes[name], recorded.passes[name])
    assert plain.stats["segments"] == recorded.stats["segments"]


def test_rich_scene_reaches_most_path_classes():
    # A deep-cut, high-index lens exercises the internal paths (⑧, ⑨) as well.
    scene = scene_with(**{"lamps[0].cuts.height": 4.0, "lamps[0].cuts.pitch": 7.0, "lamps[0].lens.ior": 1.7})
    seen = render_passes(scene, 96, 96, record_transitions=True).stats["transitions"]
    classes = {c for *_, c in seen}
    assert classes >= {2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12}


def test_centred_lamp_seen_on_axis_with_light_straight_on_is_mirror_symmetric():
    scene = scene_with(**{"light": {"direction": [0.0, -1.0, 0.0], "color": [1, 1, 1], "ambient": 0.25},
                          "image": {"width": 96, "height": 96}})
    image = render(scene).astype(np.float64)
    scale = image.max()
    for flipped in (image[:, ::-1], image[::-1, :]):
        diff = np.abs(image - flipped) / scale
        assert np.mean(diff) < 1e-5
        # rays that graze a crease between lenslets may fall on either side; allow a handful
        assert np.mean(diff > 1e-4) < 0.002


def test_render_is_deterministic_and_thread_count_does_not_matter():
    scene = scene_with(**{"image": {"width": 80, "height": 40}})
    a = render_passes(scene, threads=1).image
    b = render_passes(scene, threads=2).image
    np.testing.assert_array_equal(a, b)


@pytest.mark.slow
def test_core_tracer_imports_and_renders_without_bpy():
    code = (
        "import sys; sys.modules['bpy'] = None\n"  # any 'import bpy' now raises ImportError
        "import core_tracer, numpy\n"
        "s = core_tracer.load_scene(sys.argv[1])\n"
        "img = core_tracer.render(s, 16, 16)\n"
        "assert img.shape == (16, 16, 3) and numpy.isfinite(img).all()\n"
        "assert not any(m == 'bpy' or m.startswith('bpy.') for m, v in sys.modules.items() if v is not None)\n"
        "print('ok')\n"
    )
    out = subprocess.run([sys.executable, "-c", code, str(PRESETS / "paper-baseline.json")], cwd=ROOT,
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "ok"


def test_tracer_sources_never_import_bpy():
    for source in (ROOT / "core_tracer").rglob("*.py"):
        text = source.read_text()
        assert "import bpy" not in text and "from bpy" not in text, source
        assert "import lamp_addon" not in text and "from lamp_addon" not in text, source
        assert "from ..lamp_addon" not in text, source
    assert Path(ROOT / "core_tracer" / "__init__.py").exists()

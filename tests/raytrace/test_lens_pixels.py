"""The lens pixels found by geometry (``raytrace.engine.lens_pixels``): the eye ray through each pixel
centre meets a lens's outer face first, whatever the lens shows.

Checked against two independent estimators: the lit paper baseline's lens-surface pass (non-zero
exactly where an eye ray meets a lens: its Fresnel share of eq. 1 there), and, for an unlit
photometric design where that pass is zero everywhere (the mask Compare used before gave 0 lens
pixels), the lens discs projected by intersecting each pixel's ray with the front plane y = 0.
"""

from __future__ import annotations

import json

import numpy as np
from helpers import BASELINE, PRESETS

import core_tracer
from core_tracer.raytrace.camera import eye_rays, make_camera
from core_tracer.raytrace.engine import lens_pixels

SIZE = (96, 64)


def _projected_discs(scene: dict, width: int, height: int) -> np.ndarray:
    """(H, W) int: the round lens whose disc (radius R about its centre, in y = 0) each pixel's ray
    crosses, -1 where none; every lens's outer face lies in that plane (docs/model.md §2)."""
    o, d = eye_rays(make_camera(scene["camera"], width, height), np.arange(width * height))
    t = -o[:, 1] / d[:, 1]
    x, z = o[:, 0] + t * d[:, 0], o[:, 2] + t * d[:, 2]
    seen = np.full(width * height, -1)
    for i, lamp in enumerate(scene["lamps"]):
        cx, cz = lamp["center"]
        seen[(t > 0) & ((x - cx) ** 2 + (z - cz) ** 2 <= lamp["lens"]["radius"] ** 2)] = i
    return seen.reshape(height, width)


def test_the_lens_pixels_are_where_the_lit_lens_shows_its_surface():
    scene = core_tracer.load_scene(str(BASELINE))
    lens = lens_pixels(scene, *SIZE)
    surface = core_tracer.render_passes(scene, *SIZE, samples=1).passes["lens_surface"].max(axis=2) > 0
    assert surface.sum() > 0.1 * surface.size
    np.testing.assert_array_equal(lens >= 0, surface)


def _unlit_photometric_stop_lamp() -> dict:
    doc = json.loads((PRESETS / "photometric-stop-lamp.json").read_text(encoding="utf-8"))
    doc["lamps"][0]["bulb"]["on"] = False
    doc.pop("environment", None)
    doc["light"]["illuminance_lux"] = 0.0
    doc["image"] = {"width": SIZE[0], "height": SIZE[1], "samples": 1}
    return core_tracer.parse_scene(doc)


def test_an_unlit_lens_has_its_lens_pixels():
    scene = _unlit_photometric_stop_lamp()
    passes = core_tracer.render_passes(scene, *SIZE, samples=1).passes
    assert not passes["lens_surface"].any()  # what the old mask looked at: no lens at all
    lens = lens_pixels(scene, *SIZE)
    projected = _projected_discs(scene, *SIZE)
    assert (projected >= 0).sum() > 0.1 * projected.size
    np.testing.assert_array_equal(lens, projected)


def test_each_lamp_of_a_four_lamp_design_is_told_apart():
    scene = core_tracer.load_scene(str(PRESETS / "four-lamp-rear-combination.json"))
    lens = lens_pixels(scene, *SIZE)
    np.testing.assert_array_equal(lens, _projected_discs(scene, *SIZE))
    assert sorted(np.unique(lens)) == [-1, 0, 1, 2, 3]

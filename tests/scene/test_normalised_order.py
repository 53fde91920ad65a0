"""A normalised scene reads back from its own JSON with its keys in the same order: the hash that
names a preset's thumbnail is of that text (``library.presets.digest``). A lens giving neither
``absorption`` nor ``transmitted_color`` once got the default form's key at the end, and read back
in the section's order (the photometric four-lamp presets' thumbnails never matched)."""

from __future__ import annotations

import json

from helpers import baseline_doc

from core_tracer.library import presets as P
from core_tracer.scene.validate import normalize, parse_scene


def _key_orders(scene: dict) -> list[list[str]]:
    return [list(lamp["lens"]) for lamp in scene["lamps"]]


def test_a_lens_without_its_colour_form_reads_back_in_the_same_order():
    doc = baseline_doc()
    for lamp in doc["lamps"]:
        for key in ("absorption", "transmitted_color", "reference_thickness"):
            lamp["lens"].pop(key, None)
    scene = parse_scene(doc)
    again = parse_scene(json.loads(json.dumps(normalize(scene))))
    assert _key_orders(again) == _key_orders(scene)
    assert P.digest(again) == P.digest(scene)

"""The reflector's constant colour C in Cycles is added where the model adds it (docs/model.md §5.2): on the
first reflector hit of a path from the eye, not on every hit.

The case: a flat clear lens over a reflector with a mirror (reflectance 0.8), no scatter lobe, a
constant colour, bulb off, black socket, side wall and body, no sun, the paper's black background,
seen obliquely so that most eye rays meet the reflector two or three times before they leave. The
tracer's lens pixel is then T·C (T the lens's Fresnel transmission on the way in) and nothing else;
a Cycles emission seen on every hit adds ρ·T·C for each further hit (measured +33 % here). Measured
figures are printed (``pytest -s``).
"""

from __future__ import annotations

import numpy as np
import pytest
from helpers import dark_clear_lens_doc

import core_tracer

pytestmark = pytest.mark.blender

SIZE = (48, 32)
SAMPLES = 64  # Cycles' only noise is its choice of reflection or transmission at the glass: ~0.2 % here
# Relative, per channel: the Glossy Depth gate also hides C from the rare paths that reflect inside the
# lens before their first reflector hit (about r squared, 0.2 %).
TOLERANCE = 0.01


def _constant_scene() -> dict:
    doc = dark_clear_lens_doc({"reflectance": 0.8, "scatter": 0.0, "color": [0.3, 0.2, 0.1]})
    doc["body"]["specular"] = 0.0
    doc["image"] = {"width": SIZE[0], "height": SIZE[1], "samples": 1}
    return core_tracer.parse_scene(doc)


@pytest.mark.slow
def test_the_reflector_constant_is_seen_once_per_path_as_in_the_model(lamp_addon, bl_scene):
    scene = _constant_scene()
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    result = lamp_addon.compare.comparison.compare_design(bl_scene, samples=SAMPLES, resolution=SIZE)
    tracer, cycles = result["tracer"].astype(np.float64), result["cycles"].astype(np.float64)
    passes = core_tracer.render_passes(scene, *SIZE, samples=1).passes
    # Only the constant lights this lamp: the pixels where the reflector is seen (not the bulb or
    # socket), away from the outlines, where Cycles' tessellated bulb, socket and rim cover a few pixels
    # differently. Both renderers sample the pixel centres (one sample; Cycles' 0.01 px box).
    reflector = passes["reflector_constant"].max(axis=2) > 0
    np.testing.assert_allclose(tracer[reflector], passes["reflector_constant"][reflector], rtol=1e-6)  # nothing else
    seen = reflector.copy()
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            seen &= np.roll(reflector, (dy, dx), axis=(0, 1))
    assert seen.sum() > 300
    t = tracer[seen].mean(axis=0)
    c = cycles[seen].mean(axis=0)
    relative = (c - t) / t
    print(f"\nreflector constant (0.3, 0.2, 0.1), mirror 0.8, {SAMPLES} spp Cycles, {seen.sum()} reflector "
          f"pixels: tracer {t}, Cycles {c}, relative difference {relative}")
    assert np.abs(relative).max() < TOLERANCE


def _reflector_trees(bpy) -> list:
    return [m.node_tree for m in bpy.data.materials if m.node_tree and m.node_tree.nodes.get("Reflector Constant")]


def test_a_reflector_built_with_the_constant_on_every_hit_is_gated_on_the_next_build(lamp_addon, bl_scene):
    import bpy

    scene = _constant_scene()
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    lamp_addon.design.builder.build_lamp(bl_scene, scene)
    (tree,) = _reflector_trees(bpy)
    gate, path = tree.nodes["Constant Not For Diffuse Rays"], tree.nodes["Light Path"]
    assert gate.inputs[0].links[0].from_node.name == lamp_addon.design.materials.CONSTANT_GATE
    # The layout of earlier versions: the gate fed by Is Diffuse Ray alone.
    for name in (lamp_addon.design.materials.CONSTANT_GATE, "After A Glossy Bounce"):
        tree.nodes.remove(tree.nodes[name])
    tree.links.new(path.outputs["Is Diffuse Ray"], gate.inputs[0])
    scene["lamps"][0]["reflector"]["color"] = [0.2, 0.2, 0.2]  # any change: the lamp is built again
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    lamp_addon.design.builder.build_lamp(bl_scene, scene)
    (tree,) = _reflector_trees(bpy)
    gate = tree.nodes["Constant Not For Diffuse Rays"]
    assert gate.inputs[0].links[0].from_node.name == lamp_addon.design.materials.CONSTANT_GATE
    # A designer's own link into the gate stays.
    for name in (lamp_addon.design.materials.CONSTANT_GATE, "After A Glossy Bounce"):
        tree.nodes.remove(tree.nodes[name])
    tree.links.new(tree.nodes["Light Path"].outputs["Is Camera Ray"], gate.inputs[0])
    scene["lamps"][0]["reflector"]["color"] = [0.25, 0.2, 0.2]
    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    lamp_addon.design.builder.build_lamp(bl_scene, scene)
    (tree,) = _reflector_trees(bpy)
    assert tree.nodes["Constant Not For Diffuse Rays"].inputs[0].links[0].from_socket.name == "Is Camera Ray"

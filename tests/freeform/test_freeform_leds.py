"""LED dies beside a free-form design's meshes (``core_tracer/freeform/leds.py``): a lamp whose source is
``"led"`` lights a free-form design with its dies, found and lit as the parametric tracer's (opaque,
L = Φ / (π A) toward the front, 0 from behind), nearer or farther than the meshes' triangles; and the
light-tracing estimator's sources count their flux."""

from __future__ import annotations

import math

import numpy as np
import pytest

from core_tracer.freeform import render_passes, shapes
from core_tracer.freeform.design import DesignMeshes
from core_tracer.freeform.light_tracing import context, sources
from core_tracer.scene.validate import parse_scene

pytest.importorskip("embreex")

DIE_LM = 40.0
DIE_MM = 2.0
DIE_Y = 40.0


def design(parts: list[dict], meshes: list, facing: float = -1.0, columns: int = 1) -> tuple[dict, dict]:
    """A photometric free-form design lit by one lamp's LED dies (at y = DIE_Y, facing ``facing`` along
    y), seen from −y by an orthographic camera 1 mm wide, in the dark."""
    led = {"position": [0.0, DIE_Y, 0.0], "normal": [0.0, facing, 0.0], "die_size": [DIE_MM, DIE_MM],
           "columns": columns, "rows": 1, "pitch": [3.0, 3.0], "flux_lm": DIE_LM, "spectrum": "red_led"}
    doc = {"schema": "lamp-scene/2", "light_model": "photometric", "lamps": [{"source": "led", "led": led}],
           "camera": {"type": "orthographic", "position": [0, -500, 0], "target": [0, 0, 0], "up": [0, 0, 1],
                      "width": 1.0, "exposure": "ev100", "ev100": 10.0},
           "light": {"illuminance_lux": 0.0},
           "image": {"width": 5, "height": 5},
           "freeform": {"mesh_file": "design.glb", "parts": parts}}
    return parse_scene(doc), {m.name: m for m in meshes}


def wall(y0: float, y1: float) -> tuple[dict, object]:
    """A bulb part (a lit box, 100 lm) between y0 and y1."""
    part = {"object": "Wall", "role": "bulb", "bulb": {"type": "custom", "flux_lm": 100.0, "spectrum": "incandescent"}}
    return part, shapes.box("Wall", (-20.0, y0, -20.0), (20.0, y1, 20.0))


def test_a_die_in_front_of_a_mesh_shows_its_luminance():
    """The die, nearer than the lit wall behind it, ends the eye ray: Y = Φ / (π A) (cd/m², lm over m²),
    in the image and the bulb pass; the wall alone (the lamp's LEDs taken away) shows its own."""
    part, mesh = wall(DIE_Y + 5.0, DIE_Y + 10.0)
    scene, meshes = design([part], [mesh])
    result = render_passes(scene, meshes)
    expected = DIE_LM / (math.pi * (DIE_MM * 1e-3) ** 2)
    np.testing.assert_allclose(result.image[:, :, 1], expected, rtol=1e-5)
    np.testing.assert_allclose(result.passes["bulb"][:, :, 1], expected, rtol=1e-5)
    bare = dict(scene, lamps=[{**scene["lamps"][0], "source": "bulb"}])
    wall_only = render_passes(bare, meshes).image[:, :, 1]
    assert np.all(wall_only > 0.0) and abs(wall_only.mean() / expected - 1.0) > 0.5


def test_a_mesh_in_front_of_a_die_hides_it_and_a_die_is_dark_from_behind():
    """An unlit socket box between the camera and the die hides it (0); a die turned away from the
    camera (facing +y) is opaque and dark from behind, and hides the lit wall behind it (0 too)."""
    hide = shapes.box("Box", (-20.0, DIE_Y - 10.0, -20.0), (20.0, DIE_Y - 5.0, 20.0))
    scene, meshes = design([{"object": "Box", "role": "socket", "socket": {"color": [0.1, 0.1, 0.1]}}], [hide])
    assert render_passes(scene, meshes).image.max() == 0.0
    part, mesh = wall(DIE_Y + 5.0, DIE_Y + 10.0)
    scene, meshes = design([part], [mesh], facing=1.0)
    assert render_passes(scene, meshes).image.max() == 0.0


def test_the_light_tracing_sources_carry_the_dies_flux():
    """The second intensity estimator's sources (``light_tracing.sources``) include each LED lamp's dies:
    their photons' luminous flux sums to N Φ (683 lm/W times ∫ ȳ(λ) Φ(λ) dλ over the carried bands)."""
    part, mesh = wall(DIE_Y + 5.0, DIE_Y + 10.0)
    part["bulb"]["on"] = False  # only the dies
    scene, meshes = design([part], [mesh], columns=3)
    ctx = context(scene, DesignMeshes(meshes))
    emit = sources(ctx, scene)
    assert len(emit) == 1
    rays, flux = emit[0](20000, np.random.default_rng(1))
    y = ctx.to_xyz[:, 1]  # per band: cd/m² per W/(m² sr nm), i.e. lm per W/nm
    assert np.allclose(rays.o[:, 1], DIE_Y) and np.all(rays.d[:, 1] < 0.0)
    np.testing.assert_allclose((flux @ y).sum(), 3 * DIE_LM, rtol=1e-3)

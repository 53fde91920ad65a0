"""The lamp renderer of Nishio, Yasuda, Yokoi and Toriwaki (IPSJ 1990), in numpy.

Never imports bpy: the Blender add-on (``lamp_addon``) depends on this package, not the reverse.
"""

from .raytrace.engine import PASS_NAMES, RenderCancelled, RenderResult, render, render_passes
from .scene.reading import SceneError, scene_to_json
from .scene.validate import load_scene, normalize, parse_scene

__all__ = [
    "PASS_NAMES", "RenderCancelled", "RenderResult", "SceneError", "load_scene", "normalize", "parse_scene",
    "render", "render_passes", "scene_to_json",
]

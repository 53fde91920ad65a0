"""The scene document ``lamp-scene/1``: field declarations (``spec``), JSON reading with limits
(``reading``), validation (``validate``), derived quantities (``derived``), the lamp functions
(``functions``), text made safe for messages (``safe_text``) and the field table of
docs/scene-format.md (``fields_doc``).

The names below are the package's public API; code inside ``core_tracer`` imports the module that
defines a name.
"""

from .derived import cut_sphere_radius, default_camera, lamp_geometry, lens_absorption, new_lamp
from .reading import SceneError, parse_json_text, read_json, scene_to_json
from .validate import load_scene, normalize, parse_scene

__all__ = [
    "SceneError", "cut_sphere_radius", "default_camera", "lamp_geometry", "lens_absorption", "load_scene",
    "new_lamp", "normalize", "parse_json_text", "parse_scene", "read_json", "scene_to_json",
]

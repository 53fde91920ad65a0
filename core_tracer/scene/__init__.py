"""The scene document ``lamp-scene/2``, in the order a design flows through it: field declarations
(``spec``, of the kinds in ``field_kinds``), JSON reading with limits (``reading``), the walk of a
document against the declarations (``validate``), the rules that relate several fields
(``geometry_checks``, ``bulb_checks``, ``prism_checks``) and their limits in words for the panel
(``limits``), derived quantities (``derived``), the lens outline (``outline``), the lamp functions
(``functions``), how messages show values (``messages``), text made safe for messages
(``safe_text``) and the field table of docs/scene-format.md (``fields_doc``).

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

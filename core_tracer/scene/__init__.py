"""The scene document ``lamp-scene/1``: field declarations (``spec``), JSON reading and validation
(``validate``) and the README's field table (``fields_doc``).

The names below are the package's public API; code inside ``core_tracer`` imports the module that
defines a name.
"""

from .validate import (
    SceneError,
    cut_sphere_radius,
    default_camera,
    lamp_geometry,
    lens_absorption,
    load_scene,
    new_lamp,
    normalize,
    parse_json_text,
    parse_scene,
    read_json,
    scene_to_json,
)

__all__ = [
    "SceneError", "cut_sphere_radius", "default_camera", "lamp_geometry", "lens_absorption", "load_scene",
    "new_lamp", "normalize", "parse_json_text", "parse_scene", "read_json", "scene_to_json",
]

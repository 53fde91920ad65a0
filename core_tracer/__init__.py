from .scene import SceneError, load_scene, parse_scene

"""The environment image as another renderer shows it (Blender's world, for Build and Compare):
the pixels the tracer sees, so that both count each light once (docs/model.md §8.18)."""

from __future__ import annotations

import os
import tempfile

from ..images import imageio
from . import environment, world_cache, world_image


def shown_file(scene: dict) -> str:
    """The image file that stands for a normalised scene's environment: the image itself, or where
    the scene's sun follows the image's (``light.follow_environment``) a copy without its sun, the
    pixels the tracer sees (``environment.sunless``), written once per image into the world cache's
    folder (else the temporary folder). A ``SceneError`` naming the field when the image cannot be
    read; ``OSError`` when the copy cannot be written."""
    path = environment.image_path(scene["environment"])
    if not scene["light"].get("follow_environment", False):
        return path
    folder = world_cache.cache_folder() or tempfile.gettempdir()
    name = f"{world_image.file_digest(path)[:40]}-{world_image.LAYOUT}-{environment.SUNLESS}.exr"
    copy = os.path.join(folder, name)
    if not os.path.isfile(copy):
        imageio.write_image(copy, environment.sunless(environment.read_image(path)))
    return copy

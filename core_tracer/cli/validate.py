"""``validate SCENE.json``: check a scene file without rendering it."""

from __future__ import annotations

import argparse

from ..scene.reading import SceneError
from ..scene.safe_text import printable
from .common import load_scene_file

HELP = "check a lamp-scene file and report the first problem"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scene", metavar="SCENE.json", help="the scene file")


def run(args: argparse.Namespace) -> int:
    scene = load_scene_file(args.scene)
    lamps = len(scene["lamps"])
    image = scene["image"]
    what = f"{lamps} lamp{'s' if lamps > 1 else ''}"
    if "freeform" in scene:
        what = _check_freeform(args.scene, scene)
    print(f"{printable(args.scene)}: valid {scene['schema']}, \"{printable(scene['name'])}\", {what}, "
          f"{image['width']}x{image['height']} px")
    return 0


def _check_freeform(path: str, scene: dict) -> str:
    """Read and check the meshes of a free-form design (the lens checks; overlaps too where Embree
    is available); returns what the design holds, in words."""
    # free-form only: the mesh modules load when a design has meshes (start-up speed)
    from ..freeform import available
    from ..freeform.cache import GeometryCache
    from ..freeform.geometry import build_geometry
    from ..freeform.loading import load_meshes

    meshes = load_meshes(path, scene)
    try:
        if available()[0]:
            geometry = GeometryCache().get(scene, meshes)[0]
        else:
            geometry = build_geometry(scene, meshes)
    except SceneError as e:
        raise SceneError(f"{printable(path)}: {e.path}" if e.path else printable(path), e.message) from None
    parts = len(scene["freeform"]["parts"])
    return f"{parts} free-form part{'s' if parts > 1 else ''} ({len(geometry.triangles)} triangles)"

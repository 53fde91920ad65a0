"""A free-form design from its files: the ``lamp-scene/2`` JSON and the .glb beside it.

The mesh file is data from whoever shared the design: it is named by a plain file name (checked
when the JSON is read), must lie in the same folder as the JSON (after following links), and is
read with size and triangle limits (``gltf``) before any of it is used.
"""

from __future__ import annotations

import os

from ..scene.beside import path_beside
from ..scene.freeform_section import check_mesh_file_name
from ..scene.reading import SceneError
from ..scene.safe_text import printable
from ..scene.validate import load_scene
from .gltf import MAX_MESH_FILE_BYTES, read_glb
from .meshes import MeshData


def mesh_file_path(json_path: str | os.PathLike, mesh_file: str) -> str:
    """The mesh file beside ``json_path``; refuses a name with folders and a link leading out of
    the folder; checks that it is a regular file within the size limit (without reading it)."""
    json_path = os.fspath(json_path)
    check_mesh_file_name(mesh_file)
    where = f"{printable(json_path, 200)}: freeform.mesh_file"
    path, size = path_beside(json_path, mesh_file, where, "a .glb", " (export the meshes again)")
    if size > MAX_MESH_FILE_BYTES:
        raise SceneError(where, f'"{printable(mesh_file, 60)}" is {size} bytes; allowed at most '
                                f"{MAX_MESH_FILE_BYTES} bytes")
    return path


def load_meshes(json_path: str | os.PathLike, scene: dict) -> dict[str, MeshData]:
    """The meshes of the parts of a loaded free-form scene, by object name ({} without freeform)."""
    section = scene.get("freeform")
    if not section:
        return {}
    return read_glb(mesh_file_path(json_path, section["mesh_file"]))


def load(json_path: str | os.PathLike) -> tuple[dict, dict[str, MeshData]]:
    """(normalised scene, meshes by name) of a design file; ``SceneError`` names the file and field."""
    try:
        scene = load_scene(json_path)
    except SceneError as e:
        name = printable(os.fspath(json_path), 200)
        if e.path == name or e.path.startswith(name + ":"):
            raise
        raise SceneError(f"{name}: {e.path}" if e.path else name, e.message) from None
    return scene, load_meshes(json_path, scene)

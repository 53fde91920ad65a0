"""A free-form design from its files: the ``lamp-scene/2`` JSON and the .glb beside it.

The mesh file is data from whoever shared the design: it is named by a plain file name (checked
when the JSON is read), must lie in the same folder as the JSON (after following links), and is
read with size and triangle limits (``gltf``) before any of it is used.
"""

from __future__ import annotations

import os
import stat

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
    folder = os.path.dirname(os.path.abspath(json_path))
    path = os.path.join(folder, mesh_file)
    where = f"{printable(json_path, 200)}: freeform.mesh_file"
    if os.path.dirname(os.path.realpath(path)) != os.path.realpath(folder):
        raise SceneError(where, f'"{printable(mesh_file, 60)}" leads outside the design\'s folder; allowed a '
                                "file beside the JSON")
    try:
        st = os.stat(path)
    except OSError:
        raise SceneError(where, f'"{printable(mesh_file, 60)}" is missing; allowed a .glb beside the JSON '
                                "(export the meshes again)") from None
    if not stat.S_ISREG(st.st_mode):
        raise SceneError(where, f'"{printable(mesh_file, 60)}" is not a regular file; allowed a .glb file')
    if st.st_size > MAX_MESH_FILE_BYTES:
        raise SceneError(where, f'"{printable(mesh_file, 60)}" is {st.st_size} bytes; allowed at most '
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

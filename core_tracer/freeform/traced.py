"""A scene rendered whatever it is: a free-form design on its meshes, any other on the parametric
tracer (``render_scene``). The studies' and optimisations' workers render variant scenes they were
sent; a free-form variant names its mesh file by a full path (the copy the study found beside the
design, or the bytes a Dask worker was sent, ``cluster.cells``), read once per process and kept
with its checked geometry (``DesignMeshes``) while the variants that follow use the same file.
"""

from __future__ import annotations

import functools
import hashlib
import os
from pathlib import Path

from ..raytrace.engine.render import RenderResult

KEPT_DESIGNS = 2  # mesh files a worker keeps read (a study or an optimisation has one)


def render_scene(scene: dict, width: int | None = None, height: int | None = None, *, keep_passes: bool = True,
                 **options) -> RenderResult:
    """``raytrace.engine.render_passes`` of ``scene``, or ``freeform.render.render_passes`` on the
    meshes of the file ``scene["freeform"]["mesh_file"]`` names by its full path. The free-form tracer
    always keeps its passes; ``keep_passes`` False drops them from the result as the parametric one would."""
    meshes = meshes_of(scene)
    if meshes is None:
        from ..raytrace.engine import render_passes

        return render_passes(scene, width, height, keep_passes=keep_passes, **options)
    result = meshes.render_passes(scene, width, height, **options)
    if not keep_passes:
        result.passes = {}
    return result


def meshes_of(scene: dict):
    """The ``freeform.design.DesignMeshes`` of a free-form scene whose mesh file is a full path (kept
    while the file is unchanged); None for a parametric scene."""
    if "freeform" not in scene:
        return None
    path = scene["freeform"]["mesh_file"]
    stat = os.stat(path)
    return _design(path, stat.st_size, stat.st_mtime_ns)


def by_content(scene: dict) -> dict:
    """``scene`` with its mesh file named by the SHA-256 of its bytes, for a cache key (the same
    design anywhere has the same key; the file changed, a new one)."""
    if "freeform" not in scene:
        return scene
    digest = hashlib.sha256(Path(scene["freeform"]["mesh_file"]).read_bytes()).hexdigest()
    return {**scene, "freeform": {**scene["freeform"], "mesh_file": f"sha256:{digest}.glb"}}


@functools.lru_cache(maxsize=KEPT_DESIGNS)
def _design(path: str, size: int, mtime_ns: int):
    """The meshes of the .glb at ``path`` (as it is now: its size and time are part of the key)."""
    from .design import DesignMeshes
    from .gltf import read_glb

    return DesignMeshes(read_glb(path))

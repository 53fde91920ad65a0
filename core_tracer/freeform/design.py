"""A free-form design's meshes with the geometry every render of them shares (``DesignMeshes``)."""

from __future__ import annotations

from .cache import GeometryCache
from .meshes import MeshData
from .render import render_passes


class DesignMeshes:
    """A free-form design's meshes by name and the one ``GeometryCache`` every render of them shares
    (the measures render a design from many directions: its geometry is built once)."""

    def __init__(self, meshes: dict[str, MeshData]):
        self.meshes = meshes
        self.cache = GeometryCache()

    def render_passes(self, scene: dict, width: int | None = None, height: int | None = None, **options):
        """``freeform.render.render_passes`` of ``scene`` on these meshes."""
        return render_passes(scene, self.meshes, width, height, geometry_cache=self.cache, **options)

"""The checked geometry of a free-form design and its Embree scene, kept between renders and built
again only when the meshes or their roles change (``GeometryCache``): the one place where the
geometry (``geometry``), the acceleration structure (``embree``) and the lens-overlap check
(``overlap``, which needs the Embree scene) meet."""

from __future__ import annotations

from ..scene.reading import SceneError
from .embree import EmbreeScene, embree_missing
from .geometry import Geometry, build_geometry, fingerprint, part_meshes
from .meshes import MeshData
from .overlap import check_lens_overlap


class GeometryCache:
    """The checked geometry and its Embree scene, rebuilt only when the meshes or roles change.

    Keep one per design (a viewport, a render job) and pass it to every ``render_passes``: the
    build (``stats["build_seconds"]``) is paid once per geometry change."""

    def __init__(self) -> None:
        self.geometry: Geometry | None = None
        self.embree: EmbreeScene | None = None
        self.builds = 0

    def get(self, scene: dict, meshes: dict[str, MeshData]) -> tuple[Geometry, EmbreeScene, bool]:
        """(geometry, Embree scene, whether it was built now)."""
        reason = embree_missing()
        if reason is not None:
            raise SceneError("freeform", reason)
        key = fingerprint(scene, part_meshes(scene, meshes))
        if self.geometry is not None and self.geometry.fingerprint == key:
            return self.geometry, self.embree, False
        geometry = build_geometry(scene, meshes, key)
        embree = EmbreeScene(geometry.vertices, geometry.triangles)
        check_lens_overlap(scene, geometry, embree)
        self.geometry, self.embree = geometry, embree
        self.builds += 1
        return geometry, embree, True

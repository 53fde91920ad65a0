"""Free-form lamps: the paper's model traced on the designer's own triangle meshes (paper §5).

A free-form design is a ``lamp-scene/2`` document with a ``freeform`` section (the meshes'
roles and values) beside a glTF binary holding the meshes by name. Ray queries go through
Embree (``embreex``); where it is missing, ``available()`` says so and the rest of the program
works as before.

Public API (used by the Blender side):

- ``MeshData``: one triangle mesh in model space (``meshes``).
- ``available() -> (bool, reason)``.
- ``load(json_path) -> (scene, meshes)``: the JSON and its .glb, validated.
- ``render_passes(scene, meshes, width, height, *, progress, should_stop, samples,
  geometry_cache) -> RenderResult``: as ``core_tracer.raytrace.engine.render_passes``.
- ``GeometryCache``: the checked geometry and its acceleration structure, built once per geometry
  change and reused (keep one per design and pass it to every render).
- ``surface_hits(scene, meshes, o, d, geometry_cache)``: the first surface along given rays.
"""

from __future__ import annotations

from .meshes import MeshData


def available() -> tuple[bool, str]:
    """Whether free-form rendering works here, and if not, why (one line to show the user)."""
    from .embree import embree_missing

    reason = embree_missing()
    return (reason is None, reason or "")


def __getattr__(name: str):
    # The tracer, loader and cache are imported on first use: importing this package must work
    # (and stay cheap) where embreex is missing.
    if name in ("render_passes", "surface_hits"):
        from . import render
        return getattr(render, name)
    if name == "GeometryCache":
        from .cache import GeometryCache
        return GeometryCache
    if name == "load":
        from .loading import load
        return load
    raise AttributeError(name)


__all__ = ["GeometryCache", "MeshData", "available", "load", "render_passes", "surface_hits"]

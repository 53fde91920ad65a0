"""Rendering a design with free-form parts: which tracer, with which meshes.

``prepare`` turns the scene a render was going to trace (the design seen through a camera) into the
free-form scene when the depsgraph shows parts with roles: the ``freeform`` section added, the parts'
meshes and the acceleration-structure cache from ``freeform.geometry``. ``render_passes`` then calls
``core_tracer.freeform.render_passes`` for such a scene and the parametric tracer otherwise, so
F12, the viewport and Compare all decide the same way. The free-form tracer traces the parts with
the parametric lamps the design still uses (``freeform.parametric``: the built parts a Convert did
not hide, as meshes with the roles Convert would give them), with the design's camera, light and
background; a lamp that is not built up to date is left out, and the panel says so. Where Embree
is missing, the parts are left out and the parametric lamp is rendered as before; the reason is said once per session
(``missing_embree_note``), and the Free-form Parts panel says it always.
"""

from __future__ import annotations

from dataclasses import dataclass

import bpy

from ..design import curves as design_curves
from . import geometry as freeform_geometry
from . import parametric as freeform_parametric
from . import scene as freeform_scene
from . import status


@dataclass(frozen=True)
class Prepared:
    scene: dict  # what to trace: with its freeform section when geometry is not None
    geometry: freeform_geometry.Geometry | None
    note: str | None = None  # a warning to show once (the parts were left out)


_said: set[str] = set()


def missing_embree_note(reason: str) -> str | None:
    """The warning about missing Embree, the first time only."""
    if reason in _said:
        return None
    _said.add(reason)
    return f"free-form parts are not rendered: {reason}"


def prepare(bl_scene: bpy.types.Scene, depsgraph: bpy.types.Depsgraph, scene: dict) -> Prepared:
    """The scene to trace, with the free-form parts the depsgraph shows. Raises ``SceneError`` for a
    role value that is not allowed, naming the part."""
    parts = freeform_geometry.parts_in(depsgraph)
    if not parts:
        return Prepared(scene, None)
    ok, reason = status.available()
    if not ok:
        return Prepared(scene, None, missing_embree_note(reason))
    built = freeform_parametric.built_parts(bl_scene, depsgraph)
    try:
        with_parts = freeform_scene.with_freeform(scene, parts, built=freeform_parametric.part_documents(built, scene))
    except freeform_scene.SceneError as e:
        raise freeform_scene.SceneError("free-form part", status.part_error_text(e, parts)) from None
    # photometric: the parts' measured curves by their full paths, beside the .blend file or the preset
    # (the lamps' were found with the design, ``design.camera.scene_for_render``)
    with_parts = design_curves.with_curves(bl_scene, with_parts, ("freeform",))
    return Prepared(with_parts, freeform_geometry.geometry(bl_scene, depsgraph, parts, built))


def render_passes(prepared: Prepared, width: int, height: int, **options):
    """Render ``prepared`` with the tracer it needs; ``options`` as ``engine.render_passes`` takes
    them (the free-form tracer takes the ones it knows: progress, should_stop, samples, threads)."""
    if prepared.geometry is None:
        from ...core_tracer.raytrace.engine import render_passes as parametric

        return parametric(prepared.scene, width, height, **options)
    from ...core_tracer import freeform

    known = {key: options[key] for key in ("progress", "should_stop", "samples", "threads", "world_seen", "bands")
             if key in options}
    return freeform.render_passes(prepared.scene, prepared.geometry.meshes, width, height,
                                  geometry_cache=prepared.geometry.cache, **known)

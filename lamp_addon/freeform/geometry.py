"""The free-form parts' geometry, made once per geometry change and reused by every render.

For each Blender scene the meshes of its parts (``freeform.meshes``) are kept with a key (the parts'
names and roles) beside one ``core_tracer.freeform.GeometryCache``, which holds the acceleration
structure and rebuilds it only when the meshes or roles it is given differ from the last ones. A
depsgraph update that changes the geometry or transform of a part, or moves the design root, marks
the scene's meshes stale (``_on_depsgraph_update``); the next render or viewport redraw reads them
again, and every other render reuses them and the structure: F12 after F12, each refinement stage
of the viewport, Compare. A role's values are not geometry, but Blender tags an object's geometry on
any edit of its properties: the meshes are then read again (milliseconds) and, being the same, the
structure is kept (the cache compares their contents).

Renders run on other threads (F12's render thread, the viewport's worker) while the main thread
marks entries stale; one lock guards the table.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass

import bpy
from bpy.app.handlers import persistent

from ...core_tracer.scene.reading import SceneError
from ..design import root as design_root
from . import meshes as freeform_meshes
from . import parametric, properties, status


@dataclass(frozen=True)
class Geometry:
    key: tuple  # ((object name, role), ...) of the parts, in document order
    meshes: dict  # object name -> MeshData
    cache: object  # the scene's core_tracer.freeform.GeometryCache (shared by its Geometry entries)
    generation: int  # counts mesh reads: a changed generation means changed geometry

    @property
    def triangles(self) -> int:
        return sum(m.triangle_count for m in self.meshes.values())


_lock = threading.Lock()
_entries: dict[str, Geometry] = {}
_stale: set[str] = set()
_reads = [0]  # how many times parts' meshes were read from Blender


def parts_in(depsgraph: bpy.types.Depsgraph) -> list[bpy.types.Object]:
    """The scene's parts that ``depsgraph`` shows (hidden ones are left out, as every renderer does)."""
    shown = {obj.original.name for obj in depsgraph.objects if obj.type == "MESH"}
    return [obj for obj in properties.role_objects(depsgraph.scene) if obj.name in shown]


def refuse_parts(what: str, command: str) -> None:
    """A panel that works on the parametric lamp (which the free-form parts stand in for, Convert hides
    it) says so in one line instead of working on the hidden lamp: ``SceneError`` when parts are shown."""
    if parts_in(bpy.context.evaluated_depsgraph_get()):
        raise SceneError("Free-form Parts", f"are not {what} here yet; allowed: Export Free-form Design, then "
                                            f"python -m core_tracer {command} on the exported .json")


def part_key(objects) -> tuple:
    return tuple((obj.name, obj.lamp_role.role) for obj in objects)


def geometry(bl_scene: bpy.types.Scene, depsgraph: bpy.types.Depsgraph, objects, built=()) -> Geometry:
    """The meshes of ``objects`` (parts of ``bl_scene`` as ``depsgraph`` evaluates them) and of the
    built parametric parts ``built`` (``freeform.parametric``), and the scene's acceleration-structure
    cache: the kept meshes when nothing they were made from changed, else read now."""
    from ...core_tracer.freeform import GeometryCache

    key = part_key(objects) + tuple((obj.name, obj[design_root.PART_KEY]) for obj in built)
    with _lock:
        entry = _entries.get(bl_scene.name)
        if entry is not None and entry.key == key and bl_scene.name not in _stale:
            return entry
        _stale.discard(bl_scene.name)
    meshes = freeform_meshes.scene_meshes(bl_scene, depsgraph, objects)
    meshes.update(parametric.part_meshes(bl_scene, depsgraph, built))
    with _lock:
        _reads[0] += 1
        cache = entry.cache if entry is not None else GeometryCache()
        entry = Geometry(key, meshes, cache, _reads[0])
        _entries[bl_scene.name] = entry
    return entry


def reads() -> int:
    """How many times parts' meshes were read from Blender in this session."""
    return _reads[0]


def forget(scene_name: str | None = None) -> None:
    """Drop the kept geometry of one scene (every scene when None)."""
    with _lock:
        if scene_name is None:
            _entries.clear()
        else:
            _entries.pop(scene_name, None)


def _touches_parts(update) -> bool:
    obj = update.id
    if not isinstance(obj, bpy.types.Object):
        return False
    if not (update.is_updated_geometry or update.is_updated_transform):
        return False
    obj = obj.original
    # the designer's parts, the design root, and the built parametric parts traced with them
    return properties.has_role(obj) or obj.get(design_root.PART_KEY) is not None


def note_updates(bl_scene: bpy.types.Scene, depsgraph: bpy.types.Depsgraph) -> None:
    """Mark the scene's meshes stale if ``depsgraph``'s updates touch a part (the viewport engine
    calls it too: its ``view_update`` may come before the handlers run)."""
    if bl_scene.name in _entries and any(_touches_parts(update) for update in depsgraph.updates):
        with _lock:
            _stale.add(bl_scene.name)


@persistent
def _on_depsgraph_update(scene, depsgraph) -> None:
    note_updates(scene, depsgraph)


@persistent
def _on_load(*_args) -> None:
    forget()
    status.forget_mesh_problems()


def register() -> None:
    bpy.app.handlers.depsgraph_update_post.append(_on_depsgraph_update)
    bpy.app.handlers.load_post.append(_on_load)


def unregister() -> None:
    for handlers, fn in ((bpy.app.handlers.depsgraph_update_post, _on_depsgraph_update),
                         (bpy.app.handlers.load_post, _on_load)):
        if fn in handlers:
            handlers.remove(fn)
    forget()

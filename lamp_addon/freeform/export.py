"""Export a free-form design for headless use: a ``lamp-scene/2`` JSON and a ``.glb`` beside it.

The JSON is the design as F12 renders it (``design.camera.scene_for_render``: the scene camera's
numbers as F12 reads them, at the render size; so the file renders what F12 shows, bit for bit) with
a ``freeform`` section: the mesh file's name and each part's object name, role and values.
The ``.glb`` is written by Blender's own glTF exporter (``export_scene.gltf``, GLB, +Y up, no
materials) and holds the parts, and the parametric lamps the design still uses as meshes with their
roles (``freeform.parametric``, the numbers F12 traces), in the design root's frame: what it exports are temporary
objects with no transform carrying the parts' meshes already in that frame (``freeform.meshes
.frame_mesh``, modifiers applied), in a temporary scene. Node names are the object names, which the
JSON refers to; the temporary objects need those names for the length of the export, so the parts
are renamed aside meanwhile and get their names back right after (also when the export fails).

Both files are written atomically (``core_tracer.fileio``): the glb first, then the JSON that refers
to it. Without ``overwrite`` neither file is replaced if either exists (``TargetExistsError``).
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import bpy

from ...core_tracer import fileio
from ...core_tracer.scene.reading import SceneError, scene_to_json
from ...core_tracer.scene.validate import parse_scene
from . import meshes as freeform_meshes
from . import parametric as freeform_parametric
from . import properties, status
from . import scene as freeform_scene

_ASIDE = ".lamp-export-aside"


@dataclass(frozen=True)
class ExportReport:
    json_path: str
    glb_path: str
    parts: int
    triangles: int


def glb_path_for(json_path: str) -> str:
    stem, _ = os.path.splitext(json_path)
    return stem + ".glb"


def write_glb(bl_scene: bpy.types.Scene, objects: list, path: str, built: list = ()) -> None:
    """Write ``objects`` (parts of ``bl_scene``) and the meshes of the built parametric parts
    ``built`` (``freeform.parametric``) to ``path`` with Blender's glTF exporter, in the design's
    frame, modifiers applied."""
    depsgraph = bpy.context.evaluated_depsgraph_get()
    to_design = freeform_meshes.design_from_world(bl_scene)
    names = [obj.name for obj in objects]
    export_scene = bpy.data.scenes.new("Lamp Free-form Export")
    made: list[bpy.types.Object] = []
    meshes: list[bpy.types.Mesh] = []
    try:
        framed = []
        for obj in objects:
            meshes.append(freeform_meshes.frame_mesh(obj, depsgraph, to_design))
            framed.append(meshes[-1])
        parametric = freeform_parametric.blender_meshes(bl_scene, depsgraph, built)
        meshes += parametric.values()
        for obj in objects:
            obj.name = obj.name + _ASIDE
        for name, mesh in zip([*names, *parametric], [*framed, *parametric.values()], strict=True):
            tmp = bpy.data.objects.new(name, mesh)
            made.append(tmp)
            if tmp.name != name:  # pragma: no cover - the names were just freed
                raise SceneError("freeform.parts", f'could not export "{name}" under its own name')
            export_scene.collection.objects.link(tmp)
        with bpy.context.temp_override(scene=export_scene, view_layer=export_scene.view_layers[0]):
            result = bpy.ops.export_scene.gltf(filepath=path, export_format="GLB", use_active_scene=True,
                                               export_yup=True, export_apply=True, export_materials="NONE",
                                               export_animations=False, export_cameras=False,
                                               export_lights=False, export_extras=False)
        if result != {"FINISHED"}:
            raise OSError(f"Blender's glTF exporter did not finish ({', '.join(sorted(result))})")
    finally:
        for tmp in made:
            bpy.data.objects.remove(tmp)
        for mesh in meshes:
            bpy.data.meshes.remove(mesh)
        bpy.data.scenes.remove(export_scene)
        for obj, name in zip(objects, names, strict=True):
            obj.name = name


def export_pair(bl_scene: bpy.types.Scene, json_path: str, *, overwrite: bool = False) -> ExportReport:
    """Write the scene's free-form design to ``json_path`` and the ``.glb`` beside it. Raises
    ``SceneError`` (the design or a part is not valid), ``fileio.TargetExistsError`` or ``OSError``;
    nothing is written then."""
    from ...core_tracer.freeform import cache, geometry

    json_path = os.path.abspath(json_path)
    glb_path = glb_path_for(json_path)
    objects = properties.role_objects(bl_scene)
    built = freeform_parametric.built_parts(bl_scene, bpy.context.evaluated_depsgraph_get())
    scene, meshes = freeform_scene.design_for_export(bl_scene, os.path.basename(glb_path), objects, built)
    # The checks the tracer makes before rendering (closed outward lenses, limits; overlapping lenses
    # where Embree is here to find them): a colleague never receives a pair that cannot render.
    if status.available()[0]:
        cache.GeometryCache().get(scene, meshes)
    else:
        geometry.build_geometry(scene, meshes)
    if not overwrite:
        for path in (json_path, glb_path):
            if os.path.exists(path):
                raise fileio.TargetExistsError(17, "exists already; tick Replace Existing to replace it", path)
    fileio.check_writable(json_path)
    with fileio.atomic_path(glb_path, overwrite=overwrite) as tmp:
        write_glb(bl_scene, objects, tmp, built)
    fileio.atomic_write_text(json_path, scene_to_json(parse_scene(scene)), overwrite=overwrite)
    return ExportReport(json_path, glb_path, len(scene["freeform"]["parts"]),
                        sum(m.triangle_count for m in meshes.values()))

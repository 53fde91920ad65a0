"""Build a lamp design as Blender objects in a "Lamp Design" collection (issue 3, item 4).

Objects (each lamp i counted from 1): "Lamp Body", "Lamp Sun", and per lamp "Lamp i Lens" (glass and
side wall, two material slots), "Lamp i Reflector", "Lamp i Bulb", "Lamp i Socket". The scene's world
becomes "Lamp Design World". Geometry comes from ``meshes`` (chord tolerance ``CHORD_TOLERANCE_MM`` =
0.05 mm, measured), positions from ``core_tracer.scene.lamp_geometry``; 1 mm = 0.001 Blender units and
the lamp's front faces -Y (MODEL.md §2).

Everything the builder makes carries the custom property ``lamp_part`` (e.g. ``"lamps[0].lens"``), by
which a rebuild finds it again: objects, meshes, materials and lights are reused and updated in place,
parts that no longer exist (a removed lamp) are deleted with their data, so no duplicates or orphans
are left. Cameras are never touched. Undo is the operator's business (one step).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import bpy
import numpy as np
from mathutils import Vector
from mathutils.geometry import tessellate_polygon

from ..core_tracer.scene import functions
from ..core_tracer.scene import validate as lamp_scene
from . import design_materials
from .convert import meshes, units

MM = units.BU_PER_MM
PART_KEY = "lamp_part"
COLLECTION_NAME = "Lamp Design"
WORLD_NAME = "Lamp Design World"
CHORD_TOLERANCE_MM = meshes.CHORD_TOLERANCE_MM


@dataclass
class BuildReport:
    """What a build made: object names and the measured deviation (mm) of each tessellated part."""

    objects: list[str] = field(default_factory=list)
    max_deviation: dict[str, float] = field(default_factory=dict)
    tolerance: float = CHORD_TOLERANCE_MM

    @property
    def worst_deviation(self) -> float:
        return max(self.max_deviation.values(), default=0.0)


def build_lamp(bl_scene: bpy.types.Scene, scene: dict) -> BuildReport:
    """Create or update the objects of a normalised scene in ``bl_scene``; returns a ``BuildReport``."""
    for obj in list(bpy.data.objects):  # parts whose collection the user deleted: free their data
        if obj.get(PART_KEY) and obj.users == 0:
            bpy.data.objects.remove(obj)
    coll = _collection(bl_scene)
    owned = {obj.get(PART_KEY): obj for obj in coll.objects if obj.get(PART_KEY)}
    report = BuildReport()
    wanted: set[str] = set()

    def place(part: str, name: str, data, location=(0.0, 0.0, 0.0)) -> bpy.types.Object:
        obj = owned.get(part)
        if obj is None or obj.type != ("MESH" if isinstance(data, bpy.types.Mesh) else "LIGHT"):
            if obj is not None:
                bpy.data.objects.remove(obj)
            obj = bpy.data.objects.new(name, data)
            coll.objects.link(obj)
            obj[PART_KEY] = part
        elif obj.data != data:
            obj.data = data
        obj.name = name
        obj.parent = None
        obj.location = location
        obj.rotation_mode = "XYZ"
        obj.rotation_euler = (0.0, 0.0, 0.0)
        obj.scale = (1.0, 1.0, 1.0)
        wanted.add(part)
        report.objects.append(obj.name)
        return obj

    def mesh(part: str, name: str, data: meshes.MeshData, slots: list[tuple[str, str]]) -> bpy.types.Mesh:
        """This scene's mesh of ``part`` (reused) with materials ``slots`` = [(material part, name)]."""
        obj = owned.get(part)
        block = obj.data if obj is not None and obj.type == "MESH" else None
        mats = []
        for i, (mat_part, mat_name) in enumerate(slots):
            mat = block.materials[i] if block is not None and i < len(block.materials) else None
            if mat is None or mat.get(PART_KEY) != mat_part:
                mat = bpy.data.materials.new(mat_name)
                mat[PART_KEY] = mat_part
            mat.name = mat_name
            mats.append(mat)
        if block is None or block.get(PART_KEY) != part or block.users > 1:
            block = bpy.data.meshes.new(name)
            block[PART_KEY] = part
        block.name = name
        block.materials.clear()  # before the geometry: clearing slots resets the faces' material indices
        for mat in mats:
            block.materials.append(mat)
        fill_mesh(block, data)
        return block

    segments = []
    rims = []
    bores = []
    lamp_objects = []
    for i, lamp in enumerate(scene["lamps"]):
        g = lamp_scene.lamp_geometry(lamp)
        R = lamp["lens"]["radius"]
        n = meshes.circle_segments(R)
        reflector = meshes.reflector_mesh(lamp, g, n)
        n = _ring_segments(reflector)  # the reflector may have refined the rim
        segments.append(n)
        cx, cz = lamp["center"]
        rims.append(meshes.rim_polygon(R, n) + np.array([cx, cz]))
        bores.append((g["plane_b"], g["rim"]))
        lamp_objects.append((i, lamp, g, reflector))

    body_data = meshes.body_mesh(scene, rims, bores, tessellate_polygon)
    body = place("body", "Lamp Body", mesh("body", "Lamp Body", body_data, [("body", "Lamp Body")]))
    design_materials.diffuse(body.data.materials[0], scene["body"]["color"], "Body BSDF")

    for (i, lamp, g, reflector_data), n in zip(lamp_objects, segments, strict=True):
        base = f"lamps[{i}]"
        label = functions.lamp_label(scene["lamps"], i)  # "Stop" for a stop lamp, else "Lamp 2"
        cx, cz = lamp["center"]
        axis = (cx * MM, 0.0, cz * MM)

        lens_data = meshes.lens_mesh(lamp, n)
        lens = place(f"{base}.lens", f"{label} Lens", mesh(f"{base}.lens", f"{label} Lens", lens_data, [
            (f"{base}.lens", f"{label} Lens"), (f"{base}.side_wall", f"{label} Side Wall")]), axis)
        design_materials.lens_glass(lens.data.materials[meshes.LENS_GLASS], lamp)
        design_materials.diffuse(lens.data.materials[meshes.LENS_SIDE_WALL], lamp["lens"]["side_wall_color"],
                          "Side Wall BSDF")
        report.max_deviation[f"{base}.lens"] = lens_data.max_deviation

        reflector = place(f"{base}.reflector", f"{label} Reflector", mesh(
            f"{base}.reflector", f"{label} Reflector", reflector_data, [(f"{base}.reflector", f"{label} Reflector")]),
            axis)
        design_materials.reflector(reflector.data.materials[0], lamp)
        report.max_deviation[f"{base}.reflector"] = reflector_data.max_deviation

        bulb_data = meshes.sphere_mesh(lamp["bulb"]["radius"])
        bx, by, bz = g["bulb_center"]
        bulb = place(f"{base}.bulb", f"{label} Bulb", mesh(
            f"{base}.bulb", f"{label} Bulb", bulb_data, [(f"{base}.bulb", f"{label} Bulb")]),
            ((cx + bx) * MM, by * MM, (cz + bz) * MM))
        design_materials.bulb(bulb.data.materials[0], lamp)
        report.max_deviation[f"{base}.bulb"] = bulb_data.max_deviation

        socket_data = meshes.socket_mesh(lamp["socket"]["radius"], g["vertex"], by)
        socket = place(f"{base}.socket", f"{label} Socket", mesh(
            f"{base}.socket", f"{label} Socket", socket_data, [(f"{base}.socket", f"{label} Socket")]), axis)
        design_materials.diffuse(socket.data.materials[0], lamp["socket"]["color"], "Socket BSDF")
        report.max_deviation[f"{base}.socket"] = socket_data.max_deviation

    old_sun = owned.get("sun")
    light = old_sun.data if old_sun is not None and old_sun.type == "LIGHT" else None
    if light is None or light.get(PART_KEY) != "sun" or light.users > 1:
        light = bpy.data.lights.new("Lamp Sun", "SUN")
        light[PART_KEY] = "sun"
    if light.type != "SUN":
        light.type = "SUN"
        light = bpy.data.lights[light.name]  # the type change gives the datablock its SunLight type
    light.name = "Lamp Sun"
    design_materials.sun(light, scene)
    direction = Vector(scene["light"]["direction"]).normalized()
    sun = place("sun", "Lamp Sun", light, tuple(direction * 0.5))
    sun.rotation_mode = "QUATERNION"
    sun.rotation_quaternion = direction.to_track_quat("Z", "Y")  # the sun shines along its -Z

    wld = bl_scene.world
    if wld is None or wld.get(PART_KEY) != "world":
        if wld is not None:
            wld.use_fake_user = True  # keep the user's own world when ours replaces it
        wld = bpy.data.worlds.new(WORLD_NAME)
        wld[PART_KEY] = "world"
        bl_scene.world = wld
    design_materials.world(wld, scene)

    _remove_stale(coll, wanted)
    for view_layer in bl_scene.view_layers:  # objects' matrix_world valid for whoever reads them next
        view_layer.update()
    return report


def _ring_segments(data: meshes.MeshData) -> int:
    """Segments of the reflector's rim ring (its vertices at the largest radius)."""
    r = np.hypot(data.verts[:, 0], data.verts[:, 2])
    return int(np.count_nonzero(r > r.max() * (1 - 1e-9)))


def _collection(bl_scene: bpy.types.Scene) -> bpy.types.Collection:
    for coll in bl_scene.collection.children:
        if coll.get(PART_KEY) == "collection":
            return coll
    coll = bpy.data.collections.new(COLLECTION_NAME)
    coll[PART_KEY] = "collection"
    bl_scene.collection.children.link(coll)
    return coll


def fill_mesh(mesh: bpy.types.Mesh, data: meshes.MeshData) -> None:
    """Replace ``mesh``'s geometry: vertices (mm -> BU), faces, material slots, smooth faces and sharp creases."""
    mesh.clear_geometry()
    sizes = np.fromiter((len(f) for f in data.faces), dtype=np.int32, count=len(data.faces))
    starts = np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(np.int32)
    flat = np.fromiter((i for f in data.faces for i in f), dtype=np.int32, count=int(sizes.sum()))
    mesh.vertices.add(len(data.verts))
    mesh.vertices.foreach_set("co", (data.verts * MM).astype(np.float32).ravel())
    mesh.loops.add(len(flat))
    mesh.loops.foreach_set("vertex_index", flat)
    mesh.polygons.add(len(sizes))
    mesh.polygons.foreach_set("loop_start", starts)
    mesh.update(calc_edges=True)
    mesh.polygons.foreach_set("material_index", data.material)
    mesh.polygons.foreach_set("use_smooth", data.group != meshes.FLAT)
    # An edge is a sharp crease where the faces on it belong to different smoothing groups.
    edge_index = np.empty(len(mesh.loops), dtype=np.int32)
    mesh.loops.foreach_get("edge_index", edge_index)
    loop_group = np.repeat(data.group, sizes)
    lo = np.full(len(mesh.edges), np.iinfo(np.int32).max, dtype=np.int64)
    hi = np.full(len(mesh.edges), np.iinfo(np.int32).min, dtype=np.int64)
    np.minimum.at(lo, edge_index, loop_group)
    np.maximum.at(hi, edge_index, loop_group)
    mesh.edges.foreach_set("use_edge_sharp", lo != hi)
    mesh.update()


def _remove_stale(coll: bpy.types.Collection, wanted: set[str]) -> None:
    """Delete the builder's objects that the design no longer has, then its unused datablocks."""
    for obj in list(coll.objects):
        part = obj.get(PART_KEY)
        if part and part not in wanted:
            bpy.data.objects.remove(obj)
    for blocks in (bpy.data.meshes, bpy.data.materials, bpy.data.lights, bpy.data.worlds):
        for block in list(blocks):
            if block.get(PART_KEY) and block.users == 0:
                blocks.remove(block)

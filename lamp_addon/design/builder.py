"""Build a lamp design as Blender objects under one root, and rebuild it without undoing the designer's work.

Objects (each lamp i counted from 1): the root Empty "Lamp Design" (``design.root``), and under it
"Lamp Body", "Lamp Sun" and per lamp "Lamp i Lens" (glass and side wall, two material slots),
"Lamp i Reflector", "Lamp i Bulb", "Lamp i Socket", all in the "Lamp Design" collection. The scene's
world becomes "Lamp Design World". Geometry comes from ``convert.meshes`` (chord tolerance
``CHORD_TOLERANCE_MM`` = 0.05 mm, measured), positions from ``core_tracer.scene.lamp_geometry``;
1 mm = 0.001 Blender units and the lamp's front faces -Y (docs/model.md §2).

Everything the builder makes carries the custom property ``lamp_part`` (e.g. ``"lamps[0].lens"``), by
which a rebuild finds it again, whatever its name or collection. A rebuild changes only what a
design parameter drives:

- mesh data, and only when the numbers its shape is made from changed (``GEOMETRY_KEY`` on the mesh);
- the driven sockets of the materials (``design.materials``), the sun's strength, the world's colours;
- a part's transform by the change of its design position (``DRIVEN_KEY`` holds the transform the
  design gave it, relative to the root): a lens the designer nudged keeps the nudge when its lamp moves.

Names, parenting (to the root, to another part, or elsewhere), the root's own transform and parent,
modifiers, visibility, extra material nodes and materials the designer put in a slot themselves are
kept. Parts that no longer exist (a removed lamp) are deleted with their data; objects the builder did
not make are never touched (children of a deleted part move to the root, where they were in the world).

What the parts are (shapes, materials, places) is ``design.parts``; this module puts them into
Blender. The root records what it was built from (``DIGEST_KEY``), so ``build_status`` tells whether
the objects are up to date with the design. ``build_lamp(..., preview=True)`` makes lighter lenses
(fewer quads per lenslet cell, ``design.parts.PREVIEW_CUT_QUADS``) for Auto Build while the designer
drags; the root then says "preview" until a full build. Undo is the operator's business (one step).
"""

from __future__ import annotations

import hashlib
import itertools
import json
from dataclasses import dataclass, field

import bpy
import numpy as np
from mathutils import Matrix, Vector

from ...core_tracer.raytrace import environment, sunlight, world_file
from ...core_tracer.scene import functions
from ...core_tracer.scene.reading import SceneError
from ...core_tracer.scene.validate import parse_scene
from ..convert import cycles, photometric_cycles, units
from ..convert.meshes import builder as mesh_builder
from . import curves, materials, properties
from . import parts as design_parts
from . import root as design_root

MM = units.BU_PER_MM
PART_KEY = design_root.PART_KEY
COLLECTION_NAME = design_root.COLLECTION_NAME
WORLD_NAME = "Lamp Design World"
CHORD_TOLERANCE_MM = design_parts.CHORD_TOLERANCE_MM

DRIVEN_KEY = "lamp_driven_matrix"  # part object: the transform the design gave it, relative to the root
GEOMETRY_KEY = "lamp_geometry"  # mesh: the numbers its shape was made from
DEVIATION_KEY = "lamp_max_deviation"  # mesh: its measured distance from the analytic surface, mm
DIGEST_KEY = "lamp_design_digest"  # root: digest of the design the objects were built from
PREVIEW_KEY = "lamp_preview"  # root: some lens is a preview mesh
PARTS_KEY = "lamp_parts"  # root: the parts of that build
# part object and mesh: the name the build gave it ("Stop Lens"). While the part still has it, a
# later build renames it when the design names it otherwise (the lamp's function changed: "Turn
# Lens"); a name the designer gave is theirs and kept.
NAME_KEY = "lamp_given_name"
# Scene fields no object depends on: changing them leaves the objects up to date.
NOT_BUILT_FROM = ("schema", "name", "author", "description", "tags", "camera", "image")

UP_TO_DATE, PREVIEW, OUT_OF_DATE, NOT_BUILT, INVALID = "up to date", "preview", "out of date", "not built", "invalid"


@dataclass
class BuildReport:
    """What a build made: object names, the measured deviation (mm) of each tessellated part, the parts
    whose mesh it remade, and the driven material nodes it could not find (deleted by the designer)."""

    objects: list[str] = field(default_factory=list)
    max_deviation: dict[str, float] = field(default_factory=dict)
    tolerance: float = CHORD_TOLERANCE_MM
    remeshed: list[str] = field(default_factory=list)
    not_driven: list[str] = field(default_factory=list)
    preview: bool = False

    @property
    def worst_deviation(self) -> float:
        return max(self.max_deviation.values(), default=0.0)


# ---------------------------------------------------------------------------------------------
# Status


def design_digest(scene: dict) -> str:
    """A digest of the fields of a normalised scene that the objects are built from."""
    built_from = {key: value for key, value in scene.items() if key not in NOT_BUILT_FROM}
    return hashlib.sha256(json.dumps(built_from, sort_keys=True).encode()).hexdigest()


def build_status(bl_scene: bpy.types.Scene, scene: dict | None = None) -> str:
    """``UP_TO_DATE``, ``PREVIEW`` (built from this design with a lighter lens), ``OUT_OF_DATE``,
    ``NOT_BUILT`` or ``INVALID`` (the design cannot be built). ``scene`` is the scene's design when
    the caller has it already."""
    root = design_root.find_root(bl_scene)
    if root is None:
        return NOT_BUILT
    digest = design_digest(scene) if scene is not None else _current_digest(bl_scene)
    if digest is None:
        return INVALID
    if root.get(DIGEST_KEY) != digest:
        return OUT_OF_DATE
    present = {obj.get(PART_KEY) for obj in bl_scene.objects}
    if not set(root.get(PARTS_KEY, ())) <= present:
        return OUT_OF_DATE  # the designer deleted a part
    return PREVIEW if root.get(PREVIEW_KEY) else UP_TO_DATE


_last_design: dict = {"document": None, "digest": None}  # panels ask at every redraw: check a design once


def _current_digest(bl_scene: bpy.types.Scene) -> str | None:
    """``design_digest`` of the scene's design, None when it is invalid."""
    document = json.dumps(properties.design_document(bl_scene), sort_keys=True)
    if _last_design["document"] != document:
        try:
            digest = design_digest(parse_scene(json.loads(document)))
        except SceneError:
            digest = None
        _last_design.update(document=document, digest=digest)
    return _last_design["digest"]


def is_up_to_date(bl_scene: bpy.types.Scene) -> bool:
    """Whether the scene's objects show its current design at full quality."""
    return build_status(bl_scene) == UP_TO_DATE


# ---------------------------------------------------------------------------------------------
# Building


def follow_name(block, name: str) -> None:
    """Give ``block`` (a part's object or mesh) the name the design gives it, unless someone renamed
    it since the build last named it (``NAME_KEY``). Blender's ".001" for a name taken elsewhere
    counts as the given name."""
    given = block.get(NAME_KEY)
    if given is None:  # new, or built before names were followed: the current name is the build's
        block[NAME_KEY] = block.name
        given = block.name
    if block.name != given:
        return  # the designer's own name
    if _base_name(given) != name:
        block.name = name
        block[NAME_KEY] = block.name


def _base_name(name: str) -> str:
    """A name without the ".001" Blender adds when it is taken."""
    base, dot, number = name.rpartition(".")
    return base if dot and number.isdigit() and len(number) == 3 else name


def build_lamp(bl_scene: bpy.types.Scene, scene: dict, *, preview: bool = False) -> BuildReport:
    """Create or update the objects of a normalised scene in ``bl_scene``; returns a ``BuildReport``.
    ``preview``: lenses with fewer quads per cut cell, where that is lighter (Auto Build while dragging)."""
    not_driven = []
    try:  # photometric: Cycles' lights in W (convert.photometric_cycles)
        shown = photometric_cycles.equivalent(curves.with_curves(bl_scene, scene))
    except SceneError as e:  # a measured curve not found: the objects keep the paper's values until it is
        shown = scene
        not_driven.append(f"photometric values: {e}")
    try:  # the sun's phantom light in the reflectors, its light on the lenses (reflector_glow, lens_surface)
        phantoms, sun = cycles.phantoms(shown), cycles.lens_sun(shown)
    except SceneError as e:  # an environment image that cannot be read: the sun reports it too
        phantoms, sun = [None] * len(shown["lamps"]), None
        not_driven.append(f"the sun's light on the lenses and in the reflectors ({e})")
    lamps = [design_parts.lamp_parts(i, {**lamp, cycles.PHANTOM: phantom, cycles.LENS_SUN: sun}, preview,
                                     functions.lamp_label(shown["lamps"], i))
             for i, (lamp, phantom) in enumerate(zip(shown["lamps"], phantoms, strict=True))]
    body = design_parts.body_part(shown, [rim for _, rim, _, _ in lamps], [bore for _, _, bore, _ in lamps], sun)
    specs = [body, *(part for parts, _, _, _ in lamps for part in parts)]
    # Every shape that changed is made before the first change to the scene: a design whose geometry
    # fails (or an interrupt while a deep-cut lens is meshed) leaves the objects as they were, so an
    # apply that fails part-way is put back whole (presets.state restores what was added, not meshes refilled).
    geometry = {spec.part: design_parts.shapes.get(spec.shape, spec.make) for spec in _changed_shapes(bl_scene, specs)}
    _free_parts_whose_collection_was_deleted()
    build = _Build(bl_scene)
    build.report.not_driven += not_driven
    for spec in specs:
        build.mesh_part(spec, geometry.get(spec.part))
    build.report.preview |= any(lens_preview for _, _, _, lens_preview in lamps)
    build.sun(shown)
    build.world(shown)
    build.finish(design_digest(scene))
    return build.report


def _changed_shapes(bl_scene: bpy.types.Scene, specs: list) -> list:
    """The parts whose mesh a build will refill: no object of ours yet, or its mesh made from other
    numbers (``GEOMETRY_KEY``). Reads the scene, changes nothing."""
    meshes = {ob.get(PART_KEY): ob.data for ob in bl_scene.objects if ob.type == "MESH" and ob.get(PART_KEY)}
    return [spec for spec in specs
            if spec.part not in meshes or meshes[spec.part].get(GEOMETRY_KEY) != repr(spec.shape)]


class _Build:
    """One build into one Blender scene: finds the existing parts, updates or makes each, removes the rest."""

    def __init__(self, bl_scene: bpy.types.Scene):
        self.bl_scene = bl_scene
        self.coll = _collection(bl_scene)
        self.matrices_current = False  # world matrices evaluated since the designer's last change
        self.new_root = design_root.find_root(bl_scene) is None
        self.root = _root(bl_scene, self.coll)
        self.owned: dict[str, bpy.types.Object] = {}
        # Under our root first, then in our collection: a copy the designer made of a part (Shift+D copies
        # its tags) stays theirs.
        for obj in [*self.root.children_recursive, *self.coll.objects, *bl_scene.objects]:
            part = obj.get(PART_KEY)
            if part and part != design_root.ROOT_PART:
                self.owned.setdefault(part, obj)
        self.report = BuildReport()
        self.wanted: set[str] = set()
        self.moves: list[tuple[bpy.types.Object, Matrix]] = []

    def mesh_part(self, spec: design_parts.MeshPart, data=None) -> None:
        """Update or make the object of one mesh part; ``data``: its shape made beforehand (``_changed_shapes``)."""
        obj = self._existing(spec.part, "MESH")
        old = obj.data if obj is not None else None
        mesh = old if old is not None and old.get(PART_KEY) == spec.part and old.users == 1 else None
        if mesh is None:  # new, or shared with an object of the designer's: ours gets its own
            mesh = bpy.data.meshes.new(spec.name)
            mesh[PART_KEY] = spec.part
        self._materials(mesh, old, spec)
        shape = repr(spec.shape)
        if mesh.get(GEOMETRY_KEY) != shape:
            data = data if data is not None else design_parts.shapes.get(spec.shape, spec.make)
            fill_mesh(mesh, data)
            mesh[GEOMETRY_KEY] = shape
            mesh[DEVIATION_KEY] = data.max_deviation
            self.report.remeshed.append(spec.part)
        if spec.part != "body":
            self.report.max_deviation[spec.part] = mesh[DEVIATION_KEY]
        self._place(self._object(spec.part, spec.name, obj, mesh), spec.matrix)

    def _materials(self, mesh: bpy.types.Mesh, old: bpy.types.Mesh | None, spec: design_parts.MeshPart) -> None:
        """Drive our material in each slot; keep a material the designer put there themselves."""
        before = list(old.materials) if old is not None else []
        for i, slot in enumerate(spec.slots):
            mat = before[i] if i < len(before) else None
            if mat is not None and mat.get(PART_KEY) is None:
                self.report.not_driven.append(f"{slot.name}: the designer's material {mat.name!r}")
                new = None
            elif mat is None or mat.get(PART_KEY) != slot.part:
                mat = bpy.data.materials.new(slot.name)
                mat[PART_KEY] = slot.part
                new = True
            else:
                new = False
            if new is not None:
                self.report.not_driven += [f"{mat.name}: {node}" for node in slot.drive(mat, new=new)]
            if i < len(mesh.materials):
                if mesh.materials[i] != mat:
                    mesh.materials[i] = mat
            else:
                mesh.materials.append(mat)

    def sun(self, scene: dict) -> None:
        obj = self._existing("sun", "LIGHT")
        light = obj.data if obj is not None else None
        new = light is None or light.get(PART_KEY) != "sun" or light.users > 1
        if new:
            light = bpy.data.lights.new("Lamp Sun", "SUN")
            light[PART_KEY] = "sun"
        elif light.type != "SUN":
            light.type = "SUN"
            light = bpy.data.lights[light.name]  # the type change gives the datablock its SunLight type
        materials.sun(light, scene, new=new)
        try:
            direction = Vector(sunlight.sun_direction(scene).tolist())
        except SceneError as e:  # an environment image that cannot be read: the tracer reports it too
            self.report.not_driven.append(f"Lamp Sun direction ({e})")
            direction = Vector(scene["light"]["direction"]).normalized()
        # Half a metre out along the light direction, shining along its -Z toward the lamp.
        matrix = Matrix.Translation(direction * 0.5) @ direction.to_track_quat("Z", "Y").to_matrix().to_4x4()
        self._place(self._object("sun", "Lamp Sun", obj, light), matrix)

    def world(self, scene: dict) -> None:
        wld = self.bl_scene.world
        new = wld is None or wld.get(PART_KEY) != "world"
        if new:
            if wld is not None:
                wld.use_fake_user = True  # keep the user's own world when ours replaces it
            wld = bpy.data.worlds.new(WORLD_NAME)
            wld[PART_KEY] = "world"
            self.bl_scene.world = wld
        image = None
        if scene["environment"]["world"] != "none":
            try:
                # Its header counted as the tracer counts it, before Blender's own reader is given the
                # file: an image declaring 30000 x 15000 px would take gigabytes when Blender draws it.
                environment.world_bytes(scene)
                # without its sun where the Lamp Sun follows it, as the tracer sees it (docs/model.md §8.18)
                image = world_file.shown_file(scene)
            except (SceneError, OSError) as e:
                self.report.not_driven.append(f"{wld.name}: surroundings ({e})")
        self.report.not_driven += [f"{wld.name}: {node}"
                                   for node in materials.world(wld, scene, new=new, image_path=image)]

    def _existing(self, part: str, kind: str) -> bpy.types.Object | None:
        obj = self.owned.get(part)
        if obj is not None and obj.type != kind:  # converted to another kind: not ours to update any more
            del obj[PART_KEY]
            obj = None
        return obj

    def _object(self, part: str, name: str, obj: bpy.types.Object | None, data) -> bpy.types.Object:
        if obj is None:
            obj = bpy.data.objects.new(name, data)
            obj[PART_KEY] = part
            self.coll.objects.link(obj)
        elif obj.data != data:
            obj.data = data
        follow_name(obj, name)
        if data is not None and data.users == 1:
            follow_name(data, name)
        self.wanted.add(part)
        self.report.objects.append(obj.name)
        return obj

    def _place(self, obj: bpy.types.Object, matrix: Matrix) -> None:
        """Put a new part where the design says; move an existing one by the change of that place
        (in the root's space), so whatever the designer did to it is kept."""
        driven = obj.get(DRIVEN_KEY)
        if driven is None:  # new, or made before parts had a root
            obj.parent = self.root
            obj.matrix_parent_inverse = Matrix.Identity(4)
            obj.matrix_basis = matrix
        else:
            if self.new_root and obj.parent is None:  # the designer deleted the root: the new one takes the parts
                self._evaluate()
                world = obj.matrix_world.copy()
                obj.parent = self.root  # a new root stands at the origin: the part stays where it is
                obj.matrix_world = world
            before = Matrix([driven[i:i + 4] for i in range(0, 16, 4)])
            if before != matrix:
                self._evaluate()  # the part's offset is read from its world matrix
                root = self.root.matrix_world
                in_root = root.inverted_safe() @ obj.matrix_world
                self.moves.append((obj, root @ matrix @ before.inverted_safe() @ in_root))
        obj[DRIVEN_KEY] = [x for row in matrix for x in row]

    def _evaluate(self) -> None:
        """World matrices as the designer sees them (once per build, and only if a part is moved)."""
        if not self.matrices_current:
            _update_view_layers(self.bl_scene)
            self.matrices_current = True

    def finish(self, digest: str) -> None:
        for obj, matrix in sorted(self.moves, key=lambda move: _depth(move[0])):
            obj.matrix_world = matrix  # parents first: a child's matrix is set against its parent's new one
        _remove_stale(self.bl_scene, self.root, self.wanted)
        self.root[DIGEST_KEY] = digest
        self.root[PREVIEW_KEY] = self.report.preview
        self.root[PARTS_KEY] = sorted(self.wanted)
        _update_view_layers(self.bl_scene)  # objects' matrix_world valid for whoever reads them next


def _update_view_layers(bl_scene: bpy.types.Scene) -> None:
    for view_layer in bl_scene.view_layers:
        view_layer.update()


def _depth(obj: bpy.types.Object) -> int:
    depth = 0
    while obj.parent is not None:
        obj, depth = obj.parent, depth + 1
    return depth


def _collection(bl_scene: bpy.types.Scene) -> bpy.types.Collection:
    for coll in bl_scene.collection.children_recursive:
        if coll.get(PART_KEY) == "collection":
            return coll
    coll = bpy.data.collections.new(COLLECTION_NAME)
    coll[PART_KEY] = "collection"
    bl_scene.collection.children.link(coll)
    return coll


def _root(bl_scene: bpy.types.Scene, coll: bpy.types.Collection) -> bpy.types.Object:
    root = design_root.find_root(bl_scene)
    if root is None:
        root = bpy.data.objects.new(design_root.ROOT_NAME, None)
        root.empty_display_type = "ARROWS"
        root.empty_display_size = 0.1  # metres: about the size of one lamp
        root[PART_KEY] = design_root.ROOT_PART
        coll.objects.link(root)
    return root


def _free_parts_whose_collection_was_deleted() -> None:
    for obj in list(bpy.data.objects):
        if obj.get(PART_KEY) and obj.users == 0:
            bpy.data.objects.remove(obj)


def fill_mesh(mesh: bpy.types.Mesh, data: mesh_builder.MeshData) -> None:
    """Replace ``mesh``'s geometry: vertices (mm -> BU), faces, material slots, smooth faces and sharp creases."""
    mesh.clear_geometry()
    sizes = np.fromiter(map(len, data.faces), dtype=np.int32, count=len(data.faces))
    starts = np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(np.int32)
    flat = np.fromiter(itertools.chain.from_iterable(data.faces), dtype=np.int32, count=int(sizes.sum()))
    # Through the attributes where Blender has them: ``vertices.foreach_set("co", ...)``,
    # ``polygons.foreach_set("use_smooth", ...)`` and the like go one item at a time (0.05-0.13 s each for
    # a deep cut's 180,000 faces; the attributes take under a millisecond).
    mesh.vertices.add(len(data.verts))
    mesh.attributes["position"].data.foreach_set("vector", (data.verts * MM).astype(np.float32).ravel())
    mesh.loops.add(len(flat))
    _corners(mesh, ".corner_vert", "vertex_index", "foreach_set", flat)
    mesh.polygons.add(len(sizes))
    mesh.polygons.foreach_set("loop_start", starts)
    mesh.update(calc_edges=True)
    _set_attribute(mesh, "material_index", "INT", "FACE", data.material)
    _set_attribute(mesh, "sharp_face", "BOOLEAN", "FACE", data.group == mesh_builder.FLAT)
    # An edge is a sharp crease where the faces on it belong to different smoothing groups.
    edge_index = np.empty(len(mesh.loops), dtype=np.int32)
    _corners(mesh, ".corner_edge", "edge_index", "foreach_get", edge_index)
    order = np.argsort(edge_index, kind="stable")
    edge, group = edge_index[order], np.repeat(data.group, sizes)[order]
    first = np.flatnonzero(np.concatenate([[True], edge[1:] != edge[:-1]]))  # every edge has a loop
    sharp = np.zeros(len(mesh.edges), dtype=bool)
    sharp[edge[first]] = np.minimum.reduceat(group, first) != np.maximum.reduceat(group, first)
    _set_attribute(mesh, "sharp_edge", "BOOLEAN", "EDGE", sharp)
    mesh.update()


def _corners(mesh: bpy.types.Mesh, attribute: str, loop_property: str, method: str, values: np.ndarray) -> None:
    """Set or get a per-corner value through Blender's own attribute (4.0 on), else through the loops."""
    layer = mesh.attributes.get(attribute)
    if layer is not None:
        getattr(layer.data, method)("value", values)
    else:
        getattr(mesh.loops, method)(loop_property, values)


def _set_attribute(mesh: bpy.types.Mesh, name: str, kind: str, domain: str, values: np.ndarray) -> None:
    attribute = mesh.attributes.get(name) or mesh.attributes.new(name, kind, domain)
    attribute.data.foreach_set("value", values)


def _remove_stale(bl_scene: bpy.types.Scene, root: bpy.types.Object, wanted: set[str]) -> None:
    """Delete the builder's objects that the design no longer has, then its unused datablocks. Other
    objects parented to a deleted part move to the root, staying where they are in the world."""
    stale = [obj for obj in bl_scene.objects
             if obj.get(PART_KEY) not in (None, design_root.ROOT_PART) and obj[PART_KEY] not in wanted]
    for obj in stale:
        for child in obj.children:
            world = child.matrix_world.copy()
            child.parent = root
            child.matrix_world = world
        bpy.data.objects.remove(obj)
    for blocks in (bpy.data.meshes, bpy.data.materials, bpy.data.lights, bpy.data.worlds):
        for block in list(blocks):
            if block.get(PART_KEY) and block.users == 0:
                blocks.remove(block)

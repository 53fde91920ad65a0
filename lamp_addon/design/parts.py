"""What a lamp design is made of: its parts as meshes of given shapes, with materials and places.

Pure description, no Blender data read or written (``design.builder`` puts the parts into Blender):
each ``MeshPart`` names its part, the numbers its mesh is made from (``shape``, compared with the one a
mesh was built from, so an unchanged part is not remade), how to make that mesh (``convert.meshes``),
its material slots and its transform relative to the root. The meshes made last are kept in memory
(``shapes``), so undo, redo and dragging a value back make nothing again; ``make_lenses`` fills it from
Auto Build's worker thread.
"""

from __future__ import annotations

import dataclasses
import math
import threading
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial

import numpy as np
from mathutils import Matrix
from mathutils.geometry import tessellate_polygon

from ...core_tracer.scene import functions
from ...core_tracer.scene.derived import body_wraps, cut_sphere_radius, lamp_geometry, lens_cylinder
from ...core_tracer.scene.led_array import lit_arrays, uses_leds
from ...core_tracer.scene.outline import Outline
from ..convert import units
from ..convert.meshes import builder as mesh_builder
from ..convert.meshes import fisheye, flutes, prism_plate, wrap
from ..convert.meshes import lens as lens_meshes
from ..convert.meshes import light_guide as guide_meshes
from ..convert.meshes import parts as part_meshes
from . import materials

MM = units.BU_PER_MM
CHORD_TOLERANCE_MM = mesh_builder.CHORD_TOLERANCE_MM
# A preview lens has at most about this many cut-surface quads: a deep cut at full tolerance has up
# to ~190,000 faces and takes 1-4 s to make, its preview 0.03-0.25 s (benchmarks/bench_build.py).
PREVIEW_CUT_QUADS = 5000
CYLINDER_PREVIEW_QUADS = 2  # quads per cut cell side of a cylindrical lens's preview (0.2 s to make)


@dataclass
class Slot:
    part: str  # the material's lamp_part
    name: str  # its name when the builder makes it
    drive: Callable[..., list[str]]  # design.materials function with the design's values: drive(mat, new=...)


@dataclass
class MeshPart:
    part: str
    name: str
    shape: tuple  # the numbers the mesh is made from (the builder keeps them on the mesh)
    make: Callable[[], mesh_builder.MeshData]
    slots: list[Slot]
    matrix: Matrix  # where the design puts it, relative to the root


class Memo:
    """The last results of a slow function of hashable arguments, at most ``size`` of them weighing at
    most ``most`` together (shared with Auto Build's worker thread: the lock guards the table, not the
    making)."""

    def __init__(self, size: int, weight: Callable = lambda value: 1, most: float = math.inf):
        self.size, self.weight, self.most = size, weight, most
        self.items: OrderedDict = OrderedDict()
        self.lock = threading.Lock()

    def get(self, key, make: Callable):
        with self.lock:
            if key in self.items:
                self.items.move_to_end(key)
                return self.items[key]
        value = make()
        with self.lock:
            self.items[key] = value
            while len(self.items) > 1 and (len(self.items) > self.size or
                                           sum(map(self.weight, self.items.values())) > self.most):
                self.items.popitem(last=False)
        return value


# MeshData by shape, so that undo, redo and dragging back make nothing again. A face costs ~200 bytes
# of Python objects: 500,000 faces (under three deep-cut lenses of 190,000) are ~100 MB.
shapes = Memo(40, weight=lambda data: len(data.faces), most=500_000)
subdivisions = Memo(64)  # quads per cell side of a cut surface


def _translation(x_mm: float, y_mm: float, z_mm: float) -> Matrix:
    return Matrix.Translation((x_mm * MM, y_mm * MM, z_mm * MM))


def lamp_parts(i: int, lamp: dict, preview: bool, label: str) -> tuple[list[MeshPart], np.ndarray, tuple, bool]:
    """Lamp i's mesh parts, named after ``label`` ("Stop" makes "Stop Lens"), its rim polygon in scene
    [x, z] and its bore (for the body's opening), and whether its lens is a preview."""
    base = f"lamps[{i}]"
    tol = mesh_builder.chord_tolerance()  # Build's, or Convert to Free-form's finer (``mesh_builder.tolerances``)
    g = lamp_geometry(lamp)
    R = lamp["lens"]["radius"]
    outline = Outline.of_lens(lamp["lens"])
    f = lamp["reflector"]["focal_length"]
    prism = lamp.get("collection", "reflector") == "prism_plate"
    lens_outline, rim_local = R, None
    if prism:  # a round lens only (validation)
        n = mesh_builder.circle_segments(R)
        collecting = prism_plate_parts(base, label, lamp, n)
    elif outline.round:
        reflector_shape = ("reflector", R, f, g["vertex"], tol)
        reflector = shapes.get(reflector_shape,
                                lambda: part_meshes.reflector_mesh(lamp, mesh_builder.circle_segments(R),
                                                                   tol))
        n = ring_segments(reflector)  # the reflector may have refined the rim: lens and body follow it
    else:  # one rim polygon for the lens, the trimmed reflector and the body opening
        rim_local = mesh_builder.outline_rim(lamp, tol)
        lens_outline = ("rectangular", outline.half_w, outline.half_h, outline.corner, f, g["vertex"])
        reflector_shape = ("reflector", lens_outline, tol)
        reflector = shapes.get(reflector_shape,
                                lambda: part_meshes.trimmed_reflector_mesh(lamp, rim_local, tol))
        n = len(rim_local)
    if not prism:
        collecting = [MeshPart(f"{base}.reflector", f"{label} Reflector", reflector_shape, lambda: reflector,
                               [Slot(f"{base}.reflector", f"{label} Reflector",
                                     partial(materials.reflector, lamp=lamp))], None)]
    k, lighter = cut_quads(lamp, preview)
    cx, cz = lamp["center"]
    axis = _translation(cx, 0.0, cz)
    bx, by, bz = g["bulb_center"]
    rb, rs = lamp["bulb"]["radius"], lamp["socket"]["radius"]
    lens, cuts = lamp["lens"], lamp["cuts"]
    parts = [
        MeshPart(f"{base}.lens", f"{label} Lens",
                  # the cuts' own tolerances are part of the shape: a lens built before they changed is made again
                  ("lens", lens_outline, lens["thickness"], cuts["pitch"], _cut_shape(cuts), n, tol,
                   k, mesh_builder.cut_tolerance(), flutes.FLUTE_TOLERANCE_MM),
                  partial(lens_meshes.lens_mesh, lamp, n, tol, k, rim_local),
                  [Slot(f"{base}.lens", f"{label} Lens", partial(materials.lens_glass, lamp=lamp)),
                   _diffuse_slot(f"{base}.side_wall", f"{label} Side Wall", lens["side_wall_color"],
                                 "Side Wall BSDF")], axis),
        *(dataclasses.replace(part, matrix=axis) for part in collecting),
        MeshPart(f"{base}.bulb", f"{label} Bulb", ("sphere", rb, tol),
                  partial(part_meshes.sphere_mesh, rb),
                  [Slot(f"{base}.bulb", f"{label} Bulb", partial(materials.bulb, lamp=lamp))],
                  _translation(cx + bx, by, cz + bz)),
        MeshPart(f"{base}.socket", f"{label} Socket", ("socket", rs, g["vertex"], by, tol),
                  partial(part_meshes.socket_mesh, rs, g["vertex"], by),
                  [_diffuse_slot(f"{base}.socket", f"{label} Socket", lamp["socket"]["color"], "Socket BSDF")], axis),
    ]
    if uses_leds(lamp):  # the LED dies in place of bulb and socket
        parts[-2:] = [led_part(base, label, lamp, axis)]
    guide = lamp.get("light_guide")
    if guide and guide["enabled"]:
        parts.extend(light_guide_parts(base, label, lamp, axis))
    if lens_cylinder(lamp) is not None:
        if preview and k > CYLINDER_PREVIEW_QUADS:  # its mesh is made in Python: 1.5 s at 6 x 6 quads a cell
            k, lighter = CYLINDER_PREVIEW_QUADS, True
        rim = mesh_builder.rim_polygon(R, n) if outline.round else rim_local
        return _cylindrical(parts, lamp, rim, lens_outline, k, g, lighter)
    if outline.round:
        return parts, mesh_builder.rim_polygon(R, n) + np.array([cx, cz]), (g["plane_b"], g["rim"]), lighter
    # a rectangular lens's collar reaches the reflector's edge: the body's opening needs no bore
    return parts, rim_local + np.array([cx, cz]), (g["plane_b"], g["plane_b"]), lighter


def _cylindrical(parts: list[MeshPart], lamp: dict, rim: np.ndarray, lens_outline, k: int, g: dict,
                 lighter: bool) -> tuple[list[MeshPart], np.ndarray, tuple, bool]:
    """``lamp_parts`` for a cylindrical lens (docs/model.md, "the cylindrical lens"): the lens mesh on its
    cylinder, and the body's opening where its outer face meets its side wall."""
    lens, cuts = lamp["lens"], lamp["cuts"]
    key = ("cylindrical lens", lens_outline, lens["thickness"], cuts["pitch"], cuts["height"], len(rim),
           lens["wrap_radius"], lens["wrap_toward"], mesh_builder.chord_tolerance(), k)
    data = shapes.get(key, partial(wrap.cylindrical_lens_mesh, lamp, rim, k, mesh_builder.chord_tolerance()))
    old = parts[0]
    parts[0] = MeshPart(old.part, old.name, key, lambda: data, old.slots, old.matrix)
    opening = wrap.outer_rim(data, lamp) + np.array(lamp["center"])
    return parts, opening, (g["plane_b"], g["rim"]), lighter


def led_part(base: str, label: str, lamp: dict, axis: Matrix) -> MeshPart:
    """A lamp's LED dies as one object of flat rectangles facing their normal (``scene.led_array``),
    emitting on their front only (``materials.led_die``)."""
    led = lamp["led"]
    arrays = lit_arrays(lamp)  # a guide lit at both ends: the array and its mirror image, one object
    mirror = (tuple(arrays[-1].center), tuple(arrays[-1].normal)) if len(arrays) > 1 else ()
    shape = ("led", *(tuple(led[k]) for k in ("position", "normal", "die_size", "pitch")), led["columns"], led["rows"],
             mirror)
    return MeshPart(f"{base}.led", f"{label} LEDs", shape, partial(part_meshes.led_mesh, *arrays),
                    [Slot(f"{base}.led", f"{label} LEDs", partial(materials.led_die, lamp=lamp))], axis)


def prism_plate_parts(base: str, label: str, lamp: dict, segments: int) -> list[MeshPart]:
    """A prism-plate lamp's plate (glass) and housing (diffuse) in place of the reflector (docs/model.md, the
    prism plate); their matrices are set by ``lamp_parts``."""
    plate = lamp["prism_plate"]
    g, tol = lamp_geometry(lamp), mesh_builder.chord_tolerance()
    profile = (lamp["lens"]["radius"], plate["pitch"], plate["focal_length"], plate["ior"], g["plate_front"],
               g["plate_base"], segments, tol)
    return [
        MeshPart(f"{base}.prism_plate", f"{label} Prism Plate", ("prism_plate", *profile),
                  partial(prism_plate.prism_plate_mesh, lamp, segments),
                  [Slot(f"{base}.prism_plate", f"{label} Prism Plate",
                        partial(materials.prism_plate_glass, lamp=lamp))], None),
        MeshPart(f"{base}.housing", f"{label} Housing",
                  ("housing", lamp["lens"]["radius"], g["plate_front"], g["vertex"], segments, tol),
                  partial(prism_plate.housing_mesh, lamp, segments),
                  [_diffuse_slot(f"{base}.housing", f"{label} Housing", plate["housing_color"], "Housing BSDF")],
                  None),
    ]


def light_guide_parts(base: str, label: str, lamp: dict, axis: Matrix) -> list[MeshPart]:
    """A lamp's light guide (glass), docs/model.md §8.7a; its LEDs are the lamp's (``led_part``)."""
    guide = lamp["light_guide"]
    shape = tuple((key, tuple(value) if isinstance(value, list) else value) for key, value in sorted(guide.items())
                  if key not in ("glass_ior", "absorption"))
    return [
        MeshPart(f"{base}.light_guide", f"{label} Light Guide", ("light_guide", shape, mesh_builder.chord_tolerance()),
                  partial(guide_meshes.guide_mesh, lamp),
                  [Slot(f"{base}.light_guide", f"{label} Light Guide",
                        partial(materials.light_guide_glass, lamp=lamp))], axis),
    ]


def _diffuse_slot(part: str, name: str, color, node: str) -> Slot:
    return Slot(part, name, partial(materials.diffuse, color=color, node_name=node))


def _cut_shape(cuts: dict) -> float | tuple:
    """What the lens mesh depends on besides pitch: the fish-eye cut height, or the saw-tooth's
    type, tooth angle and orientation, or the flutes' height and orientation."""
    if cuts["type"] == "sawtooth":
        return ("sawtooth", cuts["tooth_angle"], cuts["orientation"])
    if cuts["type"] == "flutes":
        return ("flutes", cuts["height"], cuts["orientation"])
    return cuts["height"]


def cut_quads(lamp: dict, preview: bool) -> tuple[int, bool]:
    """Quads per side of one lenslet cell, and whether that is fewer than the tolerance needs (a preview).

    A preview has at most ``preview_subdivision`` quads per side; the search for the full count then
    stops just past that (a deep cut's full search measures cells of up to 48 x 48 quads). Saw-tooth
    facets are planar: one polygon each, exact, the same in a preview."""
    if lamp["cuts"]["type"] in ("sawtooth", "flutes"):  # bands along the ridges: few faces, no preview
        return 1, False
    t, p, h = lamp["lens"]["thickness"], lamp["cuts"]["pitch"], lamp["cuts"]["height"]
    outline = Outline.of_lens(lamp["lens"])
    area_radius = outline.half_w if outline.round else math.sqrt(outline.area / math.pi)  # same cell count
    light = preview_subdivision(area_radius, p) if preview else mesh_builder.MAX_CELL_SUBDIVISION
    most = light + 1 if preview else mesh_builder.MAX_CELL_SUBDIVISION
    tol = mesh_builder.chord_tolerance()  # Convert to Free-form's finer one needs more quads
    k = subdivisions.get((t, p, h, most, tol), partial(_cut_subdivision, t, p, h, most, tol))
    return min(k, light), k > light


def body_part(scene: dict, rims: list[np.ndarray], bores: list[tuple], sun: dict | None = None) -> MeshPart:
    """The body with its opening for each lens; ``sun`` lights its highlight in Cycles (``materials.body``)."""
    body = scene["body"]
    paint = [Slot("body", "Lamp Body", partial(materials.body, body=body, sun=sun))]
    shape = ("body", tuple(body["center"]), tuple(body["size"]), body["depth"],
             tuple(tuple(map(tuple, rim.round(9).tolist())) for rim in rims), tuple(bores))
    wraps = body_wraps(scene)
    if wraps:  # a front that curves round to the side (cylindrical lenses)
        return MeshPart("body", "Lamp Body", (*shape, tuple(wraps)),
                        partial(wrap.body_mesh_wrapped, scene, rims, bores, wraps, tessellate_polygon),
                        paint, Matrix.Identity(4))
    return MeshPart("body", "Lamp Body", shape, partial(part_meshes.body_mesh, scene, rims, bores, tessellate_polygon),
                    paint, Matrix.Identity(4))


def _cut_subdivision(thickness: float, pitch: float, height: float, most: int, tol: float) -> int:
    rho = None if height == 0 else cut_sphere_radius(pitch, height)
    return fisheye.cut_subdivision(fisheye.CutSurface(thickness, pitch, height, rho), tol, most=most)[0]


def preview_subdivision(radius: float, pitch: float) -> int:
    """Quads per cell side that keep a preview lens near ``PREVIEW_CUT_QUADS`` quads."""
    cells = math.pi * (radius / pitch + 0.5) ** 2
    return max(2, math.floor(math.sqrt(PREVIEW_CUT_QUADS / cells)))


def ring_segments(data: mesh_builder.MeshData) -> int:
    """Segments of the reflector's rim ring (its vertices at the largest radius)."""
    r = np.hypot(data.verts[:, 0], data.verts[:, 2])
    return int(np.count_nonzero(r > r.max() * (1 - 1e-9)))


def make_lenses(scene: dict) -> None:
    """Make the full-quality lenses of a normalised scene, into memory only: no Blender data is read or
    written, so Auto Build runs this in a worker thread, and the ``build_lamp`` that follows only
    copies the meshes into Blender (a deep cut's lens takes seconds to make, 0.3 s to copy)."""
    for i, lamp in enumerate(scene["lamps"]):
        lens = lamp_parts(i, lamp, False, functions.lamp_label(scene["lamps"], i))[0][0]
        shapes.get(lens.shape, lens.make)

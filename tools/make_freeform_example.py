"""Make the shipped free-form example: ``presets/freeform-sculpted-wrap-lamp.json`` and its ``.glb``.

    xvfb-run -a .venv/bin/python tools/make_freeform_example.py [--out presets]

A lamp whose lens is a real mesh, made with the project's own tools in Blender's Python module: the
wrap-around lamp of the "Wrap-around combination" preset alone in its body is built, converted to
free-form parts (*Convert to Free-form*: closed meshes with lamp roles), and the outer face of its
lens is sculpted: horizontal ribs pressed up to ``RIDGE_MM`` out of the face, the kind of styling a
parametric lens cannot hold. *Export Free-form Design* writes the pair. The result is listed by the
preset browser and renders with ``python -m core_tracer render`` and in Blender (F12).
"""

from __future__ import annotations

import argparse
import math
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
NAME = "freeform-sculpted-wrap-lamp"
RIDGE_MM = 2.5  # how far the sculpted ridges stand out of the lens's outer face
RIDGE_PITCH_MM = 20.0
SIZE = (320, 256)
SUBDIVISIONS = 3  # passes that split each triangle of the outer face into four, before it is sculpted


def design(core) -> dict:
    """The wrap-around lamp of the wrap-around combination, alone in a body that holds it, seen from the
    front right as that preset sees it."""
    scene = core.load_scene(os.path.join(ROOT, "presets", "wrap-around-combination.json"))
    lamp = scene["lamps"][2]
    scene["lamps"] = [lamp]
    scene["body"] = {**scene["body"], "center": [-15.0, 0.0], "size": [140.0, 110.0]}  # room left of the lens
    scene["name"] = "Free-form: sculpted wrap-around tail lamp"
    scene["author"] = "Lamp Styling (after Nishio et al. 1990)"
    scene["description"] = ("A tail lamp whose lens is a mesh: the wrap-around lens of the wrap-around combination, "
                            "converted to free-form parts and its outer face sculpted with horizontal ribs "
                            f"{RIDGE_MM:g} mm high (tools/make_freeform_example.py). Open it, edit the .glb in "
                            "Blender, export it again.")
    scene["tags"] = ["free-form", "wrap-around", "sculpted", "paper"]
    scene["image"] = {"width": SIZE[0], "height": SIZE[1], "samples": 1}
    return scene


def sculpt(bpy, lens, ridge_mm: float = RIDGE_MM) -> int:
    """Press horizontal ribs out of the lens's outer face (the faces whose normal faces the viewer, -y,
    in the lens's own space), subdivided first so the ribs have vertices to be made of; the rim of
    the face stays where it is, so the lens stays a closed solid. Returns how many vertices moved."""
    import bmesh

    to_mm = 1000.0
    bm = bmesh.new()
    bm.from_mesh(lens.data)
    print(f"  before: {sum(not e.is_manifold for e in bm.edges)} non-manifold edges, {len(bm.faces)} faces")
    bm.normal_update()
    for _ in range(SUBDIVISIONS):  # each pass splits every triangle of the face into four
        outer = [f for f in bm.faces if f.normal.y < -0.3]
        edges = list({e for f in outer for e in f.edges})
        bmesh.ops.subdivide_edges(bm, edges=edges, cuts=1, use_grid_fill=True)
        bmesh.ops.triangulate(bm, faces=bm.faces[:])
        bm.normal_update()
    print(f"  after: {sum(not e.is_manifold for e in bm.edges)} non-manifold edges, {len(bm.faces)} faces")
    bm.normal_update()
    moved = 0
    for v in bm.verts:
        if v.link_faces and all(f.normal.y < -0.3 for f in v.link_faces):  # inside the face, not on its rim
            x_mm, z_mm = v.co.x * to_mm, v.co.z * to_mm
            # Horizontal ribs across the face, fading out toward the wrapped side (+x) so the wrap stays smooth.
            fade = min(1.0, max(0.0, (40.0 - x_mm) / 30.0))
            bump = fade * ridge_mm * 0.5 * (1.0 + math.cos(2.0 * math.pi * z_mm / RIDGE_PITCH_MM))
            v.co = v.co + v.normal * (bump / to_mm)
            moved += 1
    bm.to_mesh(lens.data)
    bm.free()
    lens.data.update()
    return moved


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=os.path.join(ROOT, "presets"), help="folder to write into")
    parser.add_argument("--ridge", type=float, default=RIDGE_MM, help="ridge height, mm (0: the lens unsculpted)")
    args = parser.parse_args(argv)
    sys.path.insert(0, ROOT)
    from tools import dev_extension

    with dev_extension.blender_with_addon("lamp_freeform") as (bpy, addon, core):
        bpy.ops.wm.read_homefile(use_empty=True)
        bl_scene = bpy.context.scene
        addon.design.properties.scene_to_design(bl_scene, design(core))
        addon.design.lamp_camera.ensure_lamp_camera(bl_scene, frame=True)  # the preset's direction, on this body
        assert bpy.ops.lamp.build() == {"FINISHED"}
        assert bpy.ops.lamp.freeform_convert() == {"FINISHED"}
        lens = next(ob for ob in addon.freeform.properties.role_objects(bl_scene) if ob.lamp_role.role == "lens")
        print(f"sculpted {sculpt(bpy, lens, args.ridge)} vertices of {lens.name!r}")
        path = os.path.join(args.out, NAME + ".json")
        assert bpy.ops.lamp.freeform_export(filepath=path, replace=True) == {"FINISHED"}
    print(f"wrote {path} and {NAME}.glb ({os.path.getsize(os.path.join(args.out, NAME + '.glb'))} bytes)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

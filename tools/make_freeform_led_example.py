"""Make the free-form LED stop lamp: ``presets/led-stop-lamp-freeform-lens-photometric.json`` and its ``.glb``.

    xvfb-run -a .venv/bin/python tools/make_freeform_led_example.py [--out presets]

Convert to Free-form makes meshes of the lens, reflector, bulb and socket; a lamp's LED dies stay
its light source (``lamps[0].source: "led"``), found and lit beside the meshes exactly as the parametric
tracer finds and lights them (``core_tracer/freeform/leds.py``: opaque dies, L = Φ / (π A) toward the
front only, or a far-field file's pattern). So the LED stop lamp (``presets/led-stop-lamp.json``: nine
1 x 1 mm red dies) is built in Blender's Python module, converted, and its lens bowed into a dome
``RISE_MM`` high (its cuts following); behind each die a dark **socket** box is added (the LED
package, 1.6 x 1.6 x 0.6 mm). *Export Free-form Design* writes the pair.
"""

from __future__ import annotations

import argparse
import json
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

NAME = "led-stop-lamp-freeform-lens-photometric"
RISE_MM = 2.0  # how far the dome's top stands out toward the viewer from the flat lens
# Each die's flux (lm): a 1 x 1 mm red power die (about 625 nm) driven at 350-700 mA gives some 40-90 lm
# (LED makers' datasheets for that class of die). The dome tilts the fish-eye cells' beams outward
# (a 6 mm dome leaves 8.7 cd at H-V from 80 lm dies). Domed 2 mm, 50 lm dies gave 91 cd at H-V but 310 cd
# at 10U-10L, over S1's 260 cd maximum; 40 lm keeps every point of UN R148 S1 and FMVSS 108 stop
# (docs/measures/led-stop-lamp-freeform-lens-photometric; the intensities are proportional to the flux).
DIE_LM = 40.0
PACKAGE_MM = (1.6, 0.6)  # the LED package behind each die: its side and its depth along the die's normal
PACKAGE_GAP_MM = 0.02  # between the die and the package's front, so the two meshes do not touch


def dome(bpy, lens, rise_mm: float, radius_mm: float) -> int:
    """Bow the whole lens toward the viewer into a dome: every vertex within ``radius_mm`` of the lens's
    axis moves along -y by rise_mm (1 - r²/R²), so the rim stays where the body holds it and the
    cuts follow the dome. One smooth function of the place moves every vertex, so copies of a vertex
    stay together and the lens stays the closed solid it was. Returns how many vertices moved."""
    moved = 0
    to_mm = 1000.0
    for v in lens.data.vertices:
        r2 = (v.co.x * to_mm) ** 2 + (v.co.z * to_mm) ** 2
        if r2 < radius_mm * radius_mm:
            v.co.y -= rise_mm * (1.0 - r2 / (radius_mm * radius_mm)) / to_mm
            moved += 1
    lens.data.update()
    return moved


def design(core, rise_mm: float = RISE_MM, die_lm: float = DIE_LM) -> dict:
    """The LED stop lamp as the parametric preset has it, named and described as the free-form twin."""
    scene = core.load_scene(os.path.join(ROOT, "presets", "led-stop-lamp.json"))
    led = scene["lamps"][0]["led"]
    led["flux_lm"] = die_lm  # the dies are the lamp's LED section: traced beside the meshes
    count = led["columns"] * led["rows"]
    scene["name"] = "LED stop lamp behind a free-form lens (photometric)"
    scene["description"] = (
        f"The LED stop lamp's {count} red dies ({led['die_size'][0]:g} x {led['die_size'][1]:g} mm, "
        f"{led['flux_lm']:g} lm each, {led['pitch'][0]:g} mm pitch) behind a free-form lens: the red PMMA "
        f"fish-eye lens converted to a mesh and bowed, cuts and all, into a dome {rise_mm:g} mm high toward "
        "the viewer (tools/make_freeform_led_example.py). The dies are the lamp's LED source, traced beside "
        "the meshes as the parametric tracer traces them (opaque, lit toward the front, the red LED "
        "spectrum), with a dark package box behind each die. At night (3 lx), EV100 15, as the parametric "
        "LED stop lamp.")
    scene["tags"] = ["photometric", "stop", "LED", "free-form"]
    return scene


def package_mesh(bpy, dies, name: str):
    """A box behind each die rectangle of mesh ``dies`` (in its own space, metres): the LED package."""
    import bmesh
    from mathutils import Matrix

    side, depth = PACKAGE_MM[0] / 1000.0, PACKAGE_MM[1] / 1000.0
    bm = bmesh.new()
    for poly in dies.polygons:
        v = [dies.vertices[i].co for i in poly.vertices]
        across, up, normal = (v[1] - v[0]).normalized(), (v[3] - v[0]).normalized(), poly.normal
        centre = poly.center - normal * (PACKAGE_GAP_MM / 1000.0 + depth / 2.0)
        frame = Matrix((
            (*(across * side), 0.0), (*(up * side), 0.0), (*(normal * depth), 0.0), (*centre, 1.0))).transposed()
        bmesh.ops.create_cube(bm, size=1.0, matrix=frame)
    bmesh.ops.recalc_face_normals(bm, faces=bm.faces[:])
    mesh = bpy.data.meshes.new(name)
    bm.to_mesh(mesh)
    bm.free()
    return mesh


def add_led_parts(bpy, addon, bl_scene) -> list[str]:
    """The LED packages, a box behind each die of the built LED object, as a socket part in the
    free-form collection where Convert to Free-form put the other parts; the LED object itself is
    hidden (its dies are traced from the lamp's LED section). Returns the new object's name."""
    root = addon.design.root.find_root(bl_scene)
    leds = next(ob for ob in bl_scene.objects if ob.get(addon.design.root.PART_KEY, "").endswith(".led"))
    coll = bpy.data.collections[addon.freeform.conversion.COLLECTION_NAME]
    mesh = package_mesh(bpy, leds.data, "LED Packages")
    name = leds.name.replace(" LEDs", " LED Packages") + addon.freeform.conversion.SUFFIX
    mesh.name = name
    obj = bpy.data.objects.new(name, mesh)
    coll.objects.link(obj)
    obj.parent = root
    obj.matrix_world = leds.matrix_world
    addon.freeform.properties.set_role(obj, "socket", {"color": [0.04, 0.04, 0.04]})
    addon.freeform.materials.give_role_material(obj)
    leds.hide_set(True)
    leds.hide_render = True
    return [obj.name]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=os.path.join(ROOT, "presets"), help="folder to write into")
    parser.add_argument("--rise", type=float, default=RISE_MM, help="the dome's height, mm (0: the flat lens)")
    parser.add_argument("--die-lm", type=float, default=DIE_LM, help="each die's flux, lm")
    args = parser.parse_args(argv)
    from tools import dev_extension

    with dev_extension.blender_with_addon("lamp_freeform_led") as (bpy, addon, core):
        bpy.ops.wm.read_homefile(use_empty=True)
        bl_scene = bpy.context.scene
        scene = design(core, args.rise, args.die_lm)
        addon.design.properties.scene_to_design(bl_scene, scene)
        addon.design.lamp_camera.ensure_lamp_camera(bl_scene, frame=False)
        assert bpy.ops.lamp.build() == {"FINISHED"}
        assert bpy.ops.lamp.freeform_convert() == {"FINISHED"}
        print("LED parts:", add_led_parts(bpy, addon, bl_scene))
        lens = next(ob for ob in addon.freeform.properties.role_objects(bl_scene) if ob.lamp_role.role == "lens")
        radius = scene["lamps"][0]["lens"]["radius"]
        print(f"domed {dome(bpy, lens, args.rise, radius)} vertices of {lens.name!r}")
        path = os.path.join(args.out, NAME + ".json")
        assert bpy.ops.lamp.freeform_export(filepath=path, replace=True) == {"FINISHED"}
    with open(path, encoding="utf-8") as f:
        document = json.load(f)
    document["camera"] = scene["camera"]  # the parametric preset's view, for a side-by-side look
    with open(path, "w", encoding="utf-8") as f:
        json.dump(document, f, indent=2)
        f.write("\n")
    print(f"wrote {path} and {NAME}.glb ({os.path.getsize(os.path.join(args.out, NAME + '.glb'))} bytes)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Issue 24's walk, as a new user does it: the extension installed from its zip, Blender's startup file,
the add-on's operators only. Run by ``tools/make_issue24_images.py`` in a fresh process (its own
``BLENDER_USER_RESOURCES``, under ``xvfb-run`` for the Workbench and viewport pictures), once for the
add-on as it was when the issue was filed and once for this tree:

    python tools/issue24_walk.py ZIP OUT_DIR

It writes into ``OUT_DIR`` a PNG per picture (F12 renders, the 3D View's Solid and Rendered look, the
Lamp Compare image) and ``walk.json`` (the operators' reports and messages, object names, panel
words). It uses only what both versions have: ``bpy.ops.lamp.*`` and the design's properties by name.
"""

from __future__ import annotations

import json
import os
import sys
import tempfile

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="lamp-walk-"))

import bpy  # noqa: E402
from mathutils import Matrix  # noqa: E402

ZIP, OUT = sys.argv[1], sys.argv[2]
os.makedirs(OUT, exist_ok=True)
record: dict = {}


def captured(call):
    """(result, what Blender printed: the operator's reports) of ``call()``; a refusal's RuntimeError
    becomes its message."""
    sys.stdout.flush()
    saved = os.dup(1)
    with tempfile.TemporaryFile(mode="w+b") as out:
        os.dup2(out.fileno(), 1)
        try:
            result = call()
        except RuntimeError as e:
            result = f"refused: {e}"
        finally:
            sys.stdout.flush()
            os.dup2(saved, 1)
            os.close(saved)
        out.seek(0)
        text = out.read().decode("utf-8", "replace")
    return result, [line for line in text.splitlines() if line.strip()]


def startup() -> bpy.types.Scene:
    bpy.ops.wm.read_homefile(use_factory_startup=True)
    bpy.ops.lamp.preset_refresh()
    return bpy.context.scene


def apply(file_name: str):
    wm = bpy.context.window_manager
    wm.lamp_presets_index = next(i for i, item in enumerate(wm.lamp_presets) if item.file.endswith(file_name))
    return captured(bpy.ops.lamp.preset_apply)


def f12(name: str, percent: int = 50) -> None:
    """F12 as Blender shows it (the scene's view transform and exposure), as an 8-bit PNG."""
    scene = bpy.context.scene
    scene.render.resolution_percentage = percent
    result, lines = captured(bpy.ops.render.render)
    settings = scene.render.image_settings
    settings.file_format, settings.color_mode, settings.color_depth = "PNG", "RGB", "8"
    bpy.data.images["Render Result"].save_render(os.path.join(OUT, name + ".png"), scene=scene)
    record.setdefault("renders", {})[name] = {"size": [scene.render.resolution_x, scene.render.resolution_y],
                                              "exposure": scene.view_settings.exposure, "reports": lines}


def view_pictures(name: str) -> None:
    """What the startup Layout's 3D View shows: Solid (Workbench) and Rendered (the scene's engine), drawn
    from the view's own centre, rotation, distance and lens through a temporary camera."""
    scene = bpy.context.scene
    area = next(a for a in bpy.data.screens["Layout"].areas if a.type == "VIEW_3D")
    space = area.spaces.active
    view = space.region_3d
    region = next(r for r in area.regions if r.type == "WINDOW")
    eye = Matrix.Translation(view.view_location) @ view.view_rotation.to_matrix().to_4x4() \
        @ Matrix.Translation((0.0, 0.0, view.view_distance))
    data = bpy.data.cameras.new("Walk View")
    data.lens, data.sensor_width, data.sensor_fit = space.lens, 72.0, "AUTO"
    data.clip_start, data.clip_end = space.clip_start, space.clip_end
    cam = bpy.data.objects.new("Walk View", data)
    scene.collection.objects.link(cam)
    cam.matrix_world = eye
    kept = (scene.camera, scene.render.engine, scene.render.resolution_x, scene.render.resolution_y,
            scene.render.resolution_percentage)
    width = 480
    height = max(1, round(width * region.height / max(region.width, 1))) if region.width > 1 else 270
    scene.camera = cam
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = width, height, 100
    settings = scene.render.image_settings
    settings.file_format, settings.color_mode, settings.color_depth = "PNG", "RGB", "8"
    record.setdefault("views", {})[name] = {"region": [region.width, region.height],
                                            "location": list(view.view_location),
                                            "distance": view.view_distance}
    # The viewport leaves out what is hidden in it (H, Hide Other Objects); a render leaves out what is
    # hidden in renders: hidden in the view for the length of the pictures.
    hidden = [o for o in scene.objects if (o.hide_get() or o.hide_viewport) and not o.hide_render]
    for o in hidden:
        o.hide_render = True
    for shading, engine in (("solid", "BLENDER_WORKBENCH"), ("rendered", kept[1])):
        scene.render.engine = engine
        solid = engine == "BLENDER_WORKBENCH"
        if solid:  # Solid shading is drawn at exposure 0 on the theme's grey, whatever the scene's exposure
            look = (scene.view_settings.exposure, scene.view_settings.view_transform)
            scene.view_settings.exposure, scene.view_settings.view_transform = 0.0, "Standard"
            world = scene.world
            scene.world = bpy.data.worlds.new("Walk Grey")
            scene.world.color = (0.05, 0.05, 0.05)
        captured(bpy.ops.render.render)
        bpy.data.images["Render Result"].save_render(os.path.join(OUT, f"{name}-{shading}.png"), scene=scene)
        if solid:
            scene.view_settings.exposure, scene.view_settings.view_transform = look
            grey, scene.world = scene.world, world
            bpy.data.worlds.remove(grey)
    for o in hidden:
        o.hide_render = False
    scene.camera, scene.render.engine = kept[0], kept[1]
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = kept[2:]
    bpy.data.objects.remove(cam)


result, lines = captured(lambda: bpy.ops.extensions.package_install_files(
    filepath=ZIP, repo="user_default", enable_on_install=True))
record["install"] = lines[-3:]

# 2 and 5: the first look (Apply Preset, Build Lamp) and the first Apply Preset's report, from the
# startup file.
startup()
_, lines = apply("paper-baseline.json")
record["first_apply_reports"] = lines
record["first_build_reports"] = captured(bpy.ops.lamp.build)[1]  # the parts the Solid view shows
view_pictures("2-first-look")
if "hide_others" in dir(bpy.ops.lamp):  # the way the first report names to see the lamp in the Cube
    record["hide_others"] = captured(bpy.ops.lamp.hide_others)[1]
    view_pictures("2-first-look-others-hidden")

# 1: exposure. Lamp off first, then the round red tail lamp, then F12.
startup()
_, off = apply("paper-lamp-off.json")
_, tail = apply("paper-baseline.json")
record["exposure_reports"] = off + tail
f12("1-exposure-tail-after-lamp-off")
# ... and a stop lamp next after a tail lamp, built, under the view's exposure.
startup()
apply("square-tail-lamp.json")
captured(bpy.ops.lamp.build)
f12("1-exposure-tail", 40)
apply("sawtooth-stop-lamp.json")
captured(bpy.ops.lamp.build)
f12("1-exposure-stop", 40)
# Exposure from Design with every bulb off.
startup()
apply("paper-lamp-off.json")
record["exposure_from_design_all_off"] = captured(bpy.ops.lamp.exposure_from_design)[1]

# 3: one vocabulary. A cut height of 8 mm (more than a hemisphere), then F12 and Build.
startup()
apply("paper-baseline.json")
design = bpy.context.scene.lamp_design
design.lamps[0].cuts.height = 8.0
record["vocabulary"] = {"f12": captured(bpy.ops.render.render)[1], "build": captured(bpy.ops.lamp.build)[1]}
design.lamps[0].cuts.height = 2.0
design.lamps[0].lens.radius = 80.0
record["vocabulary"]["lens_radius_80_build"] = captured(bpy.ops.lamp.build)[1]

# 4: a function change renames. Stop -> Turn, Build; the next lamp's name.
startup()
apply("sawtooth-stop-lamp.json")
bpy.context.scene.lamp_design.lamps[0].function = "stop"
captured(bpy.ops.lamp.build)
before = sorted(o.name for o in bpy.context.scene.objects)
socket = next(o for o in bpy.context.scene.objects if o.name.endswith("Socket"))
socket.name = "My Socket"  # a part the user renamed keeps its name
bpy.context.scene.lamp_design.lamps[0].function = "turn"
captured(bpy.ops.lamp.build)
after = sorted(o.name for o in bpy.context.scene.objects)
captured(bpy.ops.lamp.lamp_add)
captured(bpy.ops.lamp.build)
record["renames"] = {"built": before, "after_turn": after,
                     "after_add": sorted(o.name for o in bpy.context.scene.objects)}

# 6: Compare gives a figure (a small render, few Cycles samples).
startup()
apply("paper-baseline.json")
scene = bpy.context.scene
scene.render.resolution_percentage = 40
_, lines = captured(lambda: bpy.ops.lamp.compare_cycles(samples=16))
record["compare_reports"] = lines
image = bpy.data.images.get("Lamp Compare")
if image is not None:
    settings = scene.render.image_settings
    settings.file_format, settings.color_mode, settings.color_depth = "PNG", "RGB", "8"
    image.save_render(os.path.join(OUT, "6-compare.png"), scene=scene)

# 7: framing. The four-lamp body, F12 as applied.
startup()
apply("four-lamp-rear-combination.json")
f12("7-framing-four-lamps", 40)

# ... and a new design: the first Build in the startup file, F12.
startup()
captured(bpy.ops.lamp.lamp_add)
captured(bpy.ops.lamp.build)
f12("7-framing-new-design")
apply("paper-baseline.json")

# 8: words. The design's fields as the panel and tooltips name them.
design = bpy.context.scene.lamp_design
words = {}
for group_name, group in (("light", design.light), ("lamp", design.lamps[0]), ("lens", design.lamps[0].lens),
                          ("bulb", design.lamps[0].bulb)):
    for prop in group.bl_rna.properties:
        if prop.identifier in ("rna_type", "name") or prop.type in ("POINTER", "COLLECTION"):
            continue
        words[f"{group_name}.{prop.identifier}"] = [prop.name, prop.description]
record["words"] = words

# The free-form example (when the zip ships it): F12 against the zip's own command line, pixel by pixel.
startup()
example = "freeform-sculpted-wrap-lamp.json"
listed = [item.file for item in bpy.context.window_manager.lamp_presets]
if any(f.endswith(example) for f in listed):
    import subprocess

    import numpy as np
    import OpenImageIO as oiio

    apply(example)
    scene = bpy.context.scene
    settings = scene.render.image_settings
    settings.file_format, settings.color_depth = "OPEN_EXR", "32"
    captured(bpy.ops.render.render)
    bpy.data.images["Render Result"].save_render(os.path.join(OUT, "f12.exr"), scene=scene)
    f12("10-freeform-f12", 100)
    preset = next(f for f in listed if f.endswith(example))
    installed = os.path.dirname(os.path.dirname(preset))  # the extension's folder: presets/ is in it
    subprocess.run([sys.executable, "-m", "core_tracer", "render", preset, "-o", os.path.join(OUT, "cli.exr")],
                   cwd=installed, check=True, capture_output=True)

    def exr(name):
        buf = oiio.ImageBuf(os.path.join(OUT, name))
        return np.asarray(buf.get_pixels(oiio.FLOAT))[..., :3]

    a, b = exr("f12.exr"), exr("cli.exr")
    record["freeform"] = {"equal": float((a == b).all(axis=2).mean()) if a.shape == b.shape else 0.0,
                          "largest": float(np.abs(a - b).max()) if a.shape == b.shape else None,
                          "size": list(a.shape[:2])}

with open(os.path.join(OUT, "walk.json"), "w", encoding="utf-8") as f:
    json.dump(record, f, indent=1)
print("walk done", OUT, flush=True)

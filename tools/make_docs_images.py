"""Make the pictures and the panel outline under docs/ that the README shows, as a new user gets them.

    xvfb-run -a .venv/bin/python tools/make_docs_images.py [--out docs] [--samples 32]

Everything starts from Blender's factory startup file (Cube, Camera, Light) with the add-on enabled
from this source tree, and goes through the add-on's own operators and draw path:

- ``viewport-preview-agx.png``: the four-lamp preset, Build Lamp (which sets the scene up: Lamp
  Camera, Lamp Tracer, the design's exposure), then the 3D Viewport's Rendered shading orbited to the
  front left: the engine's viewport draw path into a GPU offscreen, shown through the scene's colour
  management (Filmic, the lamp view the first Build sets, at the design's exposure) as Blender shows it.
- ``compare-startup-four-lamps.png``: Compare with Cycles after that Build, as the operator writes it
  (both halves at one automatic exposure through the scene's view transform).
- ``study-ior-cut-height.png``: a 2 x 2 study of the paper baseline (lens IOR x cut height, cells
  framed on the lamp: the body's aspect) from the command line, which shares the display pipeline.
- ``panel.txt``: the Lamp tab of the sidebar after that Build, as its draw code lays it out (headless
  Blender draws no interface: the panels' draw calls are recorded and written as an outline).

Needs a display for the GPU (``xvfb-run -a``) and the bpy wheel; the timings are printed.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from types import SimpleNamespace

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
VIEWPORT_SIZE = (480, 300)
COMPARE_SIZE = (320, 200)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=os.path.join(ROOT, "docs"), help="folder to write into (default docs/)")
    parser.add_argument("--samples", type=int, default=32, help="Cycles samples of the Compare picture")
    parser.add_argument("--panel-only", action="store_true",
                        help="write docs/panel.txt only (no GPU, a few seconds; tests/addon/test_addon_panel_doc.py "
                             "checks that the file is what this writes)")
    args = parser.parse_args(argv)
    os.makedirs(args.out, exist_ok=True)
    sys.path.insert(0, ROOT)
    from tools import dev_extension

    with dev_extension.blender_with_addon("lamp_docs") as (bpy, addon, core):
        bl_scene = startup_with_preset(bpy, core, addon)
        write_panel_outline(bpy, addon, bl_scene, os.path.join(args.out, "panel.txt"))
        if args.panel_only:
            return 0
        compare_picture(bpy, addon, bl_scene, os.path.join(args.out, "compare-startup-four-lamps.png"), args.samples)
        viewport_picture(bpy, addon, bl_scene, os.path.join(args.out, "viewport-preview-agx.png"))
    study_picture(os.path.join(args.out, "study-ior-cut-height.png"))
    return 0


def _timed(what: str, started: float) -> None:
    print(f"{what}: {time.perf_counter() - started:.2f} s")


def startup_with_preset(bpy, core, addon):
    """The factory startup file, the four-lamp preset applied, Build Lamp pressed once."""
    bpy.ops.wm.read_homefile(use_factory_startup=True)
    bl_scene = bpy.context.scene
    scene = core.load_scene(os.path.join(ROOT, "presets", "four-lamp-rear-combination.json"))
    scene["image"] = {"width": COMPARE_SIZE[0], "height": COMPARE_SIZE[1]}
    started = time.perf_counter()
    addon.design.properties.scene_to_design(bl_scene, scene)
    assert bpy.ops.lamp.build() == {"FINISHED"}
    _timed(f"Build in the startup file (exposure {bl_scene.view_settings.exposure:+.1f} EV, engine "
           f"{bl_scene.render.engine}, camera {bl_scene.camera.name})", started)
    return bl_scene


def compare_picture(bpy, addon, bl_scene, path: str, samples: int) -> None:
    started = time.perf_counter()
    assert bpy.ops.lamp.compare_cycles(samples=samples, filepath=path) == {"FINISHED"}
    _timed(f"Compare ({samples} spp) -> {path}", started)


def viewport_picture(bpy, addon, bl_scene, path: str) -> None:
    """The viewport's draw path from a three-quarter view into an offscreen, shown as Blender shows it."""
    import numpy as np
    from mathutils import Vector

    width, height = VIEWPORT_SIZE
    root = addon.design.root.find_root(bl_scene)
    centre = root.matrix_world @ Vector((0.0425, 0.04, 0.0))  # the four-lamp body's centre, in metres
    eye = centre + Vector((-0.33, -0.48, 0.19))
    view = bpy.data.cameras.new("Docs View")
    view.lens, view.sensor_fit = 30.0, "HORIZONTAL"
    ob = bpy.data.objects.new("Docs View", view)
    ob.location = eye
    ob.rotation_euler = (centre - eye).to_track_quat("-Z", "Y").to_euler()
    bl_scene.collection.objects.link(ob)
    bl_scene.view_layers[0].update()
    window = ob.calc_matrix_camera(bpy.context.evaluated_depsgraph_get(), x=width, y=height)
    started = time.perf_counter()
    rgba = draw_viewport(bpy, addon, bl_scene, width, height, window, ob.matrix_world.inverted())["pixels"]
    _timed("viewport draw path (coarse + full stages)", started)
    bpy.data.objects.remove(ob)
    bpy.data.cameras.remove(view)
    image = bpy.data.images.new("Docs viewport", width, height, float_buffer=True, alpha=True)
    image.pixels.foreach_set(np.ascontiguousarray(rgba, np.float32).ravel())
    settings = bl_scene.render.image_settings
    settings.file_format, settings.color_mode, settings.color_depth = "PNG", "RGB", "8"
    image.save_render(path, scene=bl_scene)  # through the scene's view transform and exposure
    bpy.data.images.remove(image)
    print(f"viewport ({bl_scene.view_settings.view_transform}, {bl_scene.view_settings.exposure:+.1f} EV) -> {path}")


def draw_viewport(bpy, addon, bl_scene, width: int, height: int, window, view) -> dict:
    """What the Lamp Tracer's ``view_draw`` draws for this view: ``pixels`` read back (bottom row
    first, RGBA), the viewport's ``status`` line and the ``scene`` the tracer rendered.

    Blender makes engine instances only to render, so a probe engine draws from ``render()``: the
    viewport session as ``view_draw`` drives it, both stages, then ``draw_frame`` into an offscreen.
    The probe is a plain ``RenderEngine``: a registered subclass of the Lamp Tracer's class, once
    unregistered, leaves Blender without the Lamp Tracer's Python class for later renders. The scene's
    camera, engine and size are put back afterwards (the tests and this tool share it)."""
    import gpu
    import numpy as np
    from mathutils import Matrix

    _start_gpu(bpy, bl_scene)
    offscreen = gpu.types.GPUOffScreen(width, height, format="RGBA32F")
    out = {}

    class DocsDrawProbe(bpy.types.RenderEngine):
        bl_idname = "LAMP_DOCS_DRAW_PROBE"
        bl_label = "Lamp Tracer docs probe"

        def render(self, depsgraph):
            scene = depsgraph.scene
            session = addon.render.viewport.ViewportSession(self, in_background=False)
            session.update(scene)
            session.sync(scene, width, height, [list(r) for r in window], [list(r) for r in view])
            while session.preview.step():
                pass
            with offscreen.bind():
                gpu.state.active_framebuffer_get().clear(color=(0.0, 0.0, 0.0, 0.0))
                with gpu.matrix.push_pop(), gpu.matrix.push_pop_projection():
                    gpu.matrix.load_matrix(Matrix.Identity(4))
                    gpu.matrix.load_projection_matrix(Matrix.Identity(4))
                    gpu.matrix.translate((-1.0, -1.0))
                    gpu.matrix.scale((2.0 / width, 2.0 / height))
                    session.draw_frame(self, scene, width, height)
                out["pixels"] = np.array(offscreen.texture_color.read().to_list(), np.float32)
            out["status"] = session.status()
            out["scene"] = session.scene

    render = bl_scene.render
    kept = bl_scene.camera, render.engine, render.resolution_x, render.resolution_y
    addon.design.view_link.pause_link(bl_scene)  # the probe's tiny render is not the user's size
    bpy.utils.register_class(DocsDrawProbe)
    stand_in = None
    try:
        if bl_scene.camera is None:  # a render needs a camera, even one that draws nothing of it
            stand_in = bpy.data.objects.new("Probe Camera", bpy.data.cameras.new("Probe Camera"))
            bl_scene.collection.objects.link(stand_in)
            bl_scene.camera = stand_in
        render.engine = DocsDrawProbe.bl_idname
        render.resolution_x = render.resolution_y = 4
        bpy.ops.render.render()
    finally:
        bl_scene.camera, render.engine, render.resolution_x, render.resolution_y = kept
        if stand_in is not None:
            camera_data = stand_in.data
            bpy.data.objects.remove(stand_in)
            bpy.data.cameras.remove(camera_data)
        bpy.utils.unregister_class(DocsDrawProbe)
        addon.design.view_link.resume_link(bl_scene)
        offscreen.free()
    return out


def _start_gpu(bpy, bl_scene) -> None:
    """The bpy module makes its GPU context at the first draw-engine render: a Workbench render of 4 px."""
    import gpu

    try:
        gpu.types.GPUOffScreen(4, 4).free()
        return
    except SystemError:
        pass
    render = bl_scene.render
    kept = render.engine, render.resolution_x, render.resolution_y
    bl_scene.render.engine = "BLENDER_WORKBENCH"
    render.resolution_x = render.resolution_y = 4
    try:
        bpy.ops.render.render()
    finally:
        render.engine, render.resolution_x, render.resolution_y = kept
    gpu.types.GPUOffScreen(4, 4).free()  # raises when there is no display: run under xvfb-run -a


def study_picture(path: str) -> None:
    started = time.perf_counter()
    subprocess.run([sys.executable, "-m", "core_tracer", "study", os.path.join(ROOT, "presets", "paper-baseline.json"),
                    "--vary", "lens.ior=1.45,1.6", "--vary", "cuts.height=0.5,2",
                    "--title", "IOR x cut height", "-o", path], cwd=ROOT, check=True)
    _timed(f"study 2 x 2 -> {path}", started)


# ---------------------------------------------------------------------------------------------
# The panel as an outline


class _Outline:
    """The ``UILayout`` calls the Lamp panels make, written as indented lines."""

    def __init__(self, lines: list[str], depth: int = 0):
        self.lines, self.depth = lines, depth
        self.use_property_split = self.use_property_decorate = False
        self.enabled = self.active = True
        self.alert = False
        self.alignment = "EXPAND"

    def _add(self, text: str) -> None:
        self.lines.append("  " * self.depth + text + ("   [highlighted]" if self.alert else ""))

    def _child(self, **_kw):
        child = _Outline(self.lines, self.depth)
        child.alert = self.alert
        return child

    row = column = split = box = _child

    def separator(self, **_kw):
        pass

    def label(self, *, text="", icon="NONE", **_kw):
        self._add(f"{text}" + (f"  ({icon})" if icon not in ("NONE", "") else ""))

    def prop(self, data, prop, text=None, index=-1, **_kw):
        rna = data.bl_rna.properties[prop]
        name = text if text else rna.name  # an icon-only toggle ("") by its property's name
        value = getattr(data, prop)
        if index >= 0:
            value = round(value[index], 4) if isinstance(value[index], float) else value[index]
        elif rna.type == "FLOAT" and getattr(rna, "array_length", 0):
            value = tuple(round(v, 3) for v in value)
        elif isinstance(value, float):
            value = round(value, 3)
        self._add(f"{name}: {value}" if name else f"{value}")

    def operator(self, idname, text=None, **_kw):
        import bpy

        module, name = idname.split(".")
        label = text if text else getattr(getattr(bpy.ops, module), name).get_rna_type().name
        self._add(f"[{label}]" if label else f"[{idname}]")
        return SimpleNamespace()

    def template_list(self, listtype, _list_id, data, propname, active_data, active_prop, **_kw):
        import bpy

        ui_list = getattr(bpy.types, listtype)
        active = getattr(active_data, active_prop)
        for i, item in enumerate(getattr(data, propname)):  # each row as the list's own draw_item draws it
            row = _Outline(self.lines, self.depth)
            ui_list.draw_item(None, None, row, data, item, 0, active_data, active_prop, index=i)
            if i == active:
                self.lines[-1] += "   <- selected"

    def template_icon(self, **_kw):
        pass

    def template_icon_view(self, data, prop, **_kw):
        self._add(f"thumbnails of {data.bl_rna.properties[prop].name}")

    def menu(self, menu, text="", **_kw):
        self._add(f"menu {text or menu}")

    def prop_search(self, data, prop, *_a, **_kw):
        self.prop(data, prop)

    def __getattr__(self, name):
        def call(*_a, **_kw):
            self._add(f"<{name}>")
            return self._child()
        return call


class _PanelProxy:
    """Stands in for the panel instance: ``layout`` plus the class's own attributes and methods."""

    def __init__(self, cls, layout):
        self._cls, self.layout = cls, layout

    def __getattr__(self, name):
        return getattr(self._cls, name)


PANEL_HEADER = ("The Lamp tab of the 3D Viewport's sidebar (N), after Build Lamp with the four-lamp preset in\n"
                "Blender's startup file; written by tools/make_docs_images.py from the panels' draw calls\n"
                "(--panel-only rewrites just this file; a test checks it is up to date).\n\n")


def panel_outline(bpy, addon, bl_scene) -> str:
    """The Lamp tab's panels in Blender's order (parents first, then children by ``bl_order``), as text.
    The preset list is read first (synchronously), so the outline is the same on every run."""
    addon.presets.library.sync(bpy.context)
    panels = [cls for cls in bpy.types.Panel.__subclasses__()
              if getattr(cls, "bl_category", "") == "Lamp" and getattr(cls, "bl_space_type", "") == "VIEW_3D"]
    context = SimpleNamespace(scene=bl_scene, window_manager=bpy.context.window_manager, mode="OBJECT",
                              engine=bl_scene.render.engine, view_layer=bl_scene.view_layers[0],
                              region_data=None, area=None, region=None, space_data=None,
                              preferences=bpy.context.preferences)
    lines: list[str] = []

    def walk(parent: str, depth: int) -> None:
        children = sorted((c for c in panels if getattr(c, "bl_parent_id", "") == parent),
                          key=lambda c: getattr(c, "bl_order", 0))
        for cls in children:
            if hasattr(cls, "poll") and not cls.poll(context):
                continue
            closed = "DEFAULT_CLOSED" in getattr(cls, "bl_options", set())
            lines.append("  " * depth + f"▸ {cls.bl_label}" + ("  (closed at first)" if closed else ""))
            if hasattr(cls, "draw_header"):  # a switch in the header (Glare's On)
                header: list[str] = []
                cls.draw_header(_PanelProxy(cls, _Outline(header, 0)), context)
                lines[-1] += "".join(f"   [header: {h.strip()}]" for h in header)
            proxy = _PanelProxy(cls, _Outline(lines, depth + 1))
            try:
                cls.draw(proxy, context)
            except (AttributeError, TypeError) as e:  # a draw call the outline does not know
                lines.append("  " * (depth + 1) + f"(not outlined: {e})")
            walk(cls.__name__, depth + 1)

    walk("", 0)
    return PANEL_HEADER + "\n".join(lines) + "\n"


def write_panel_outline(bpy, addon, bl_scene, path: str) -> None:
    text = panel_outline(bpy, addon, bl_scene)
    with open(path, "w", encoding="utf-8") as f:
        f.write(text)
    print(f"panel outline ({text.count(chr(10))} lines) -> {path}")


if __name__ == "__main__":
    sys.exit(main())

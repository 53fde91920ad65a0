"""Draw the Measures section of the Lamp tab as its draw code lays it out: docs/measures-panel.png.

    .venv/bin/python tools/make_measures_panel_image.py [--out docs/measures-panel.png]

Headless Blender draws no interface, so the panel's ``UILayout`` calls are recorded (rows side by
side, columns and boxes one under another) and drawn with matplotlib in the colours of Blender's
dark theme. The design is the four-lamp night preset (photometric) and the table is that of its
committed report, docs/measures/four-lamp-night-lit-photometric/measures.json (what Measure Design
writes), so the picture shows a failing function.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
REPORT = os.path.join(ROOT, "docs", "measures", "four-lamp-night-lit-photometric")


class _Recorder:
    """``UILayout`` calls as lines: a row's items side by side, a column's or box's one under another."""

    def __init__(self, lines: list, depth: int = 0, in_row: list | None = None):
        self.lines, self.depth, self.in_row = lines, depth, in_row
        self.use_property_split = self.use_property_decorate = False
        self.enabled = self.active = True
        self.alert = False

    def _item(self, kind: str, text: str, icon: str = "NONE") -> None:
        if self.in_row is not None:
            self.in_row.append((kind, text, icon))
        else:
            self.lines.append((self.depth, [(kind, text, icon)]))

    def row(self, **_kw):
        items: list = []
        self.lines.append((self.depth, items))
        return _Recorder(self.lines, self.depth, items)

    def column(self, **_kw):
        return _Recorder(self.lines, self.depth)

    def box(self):
        self.lines.append((self.depth + 1, "box"))
        return _Recorder(self.lines, self.depth + 1)

    def separator(self, **_kw):
        pass

    def label(self, *, text="", icon="NONE", **_kw):
        self._item("label", text, icon)

    def prop(self, data, prop, text=None, **_kw):
        rna = data.bl_rna.properties[prop]
        value = getattr(data, prop)
        self._item("toggle" if rna.type == "BOOLEAN" else "prop", f"{text or rna.name}" +
                   ("" if rna.type == "BOOLEAN" else f": {value}"), "CHECKBOX_HLT" if value is True else "NONE")

    def operator(self, idname, text=None, icon="NONE", **_kw):
        import bpy

        module, name = idname.split(".")
        self._item("button", text or getattr(getattr(bpy.ops, module), name).get_rna_type().name, icon)


def draw_panel(lines: list, title: str, path: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import FancyBboxPatch

    rows = [line for line in lines if line[1] != "box"]
    height = 0.36 * (len(rows) + 2) + 0.1
    fig = plt.figure(figsize=(10.5, height), dpi=110)
    fig.patch.set_facecolor("#303030")
    ax = fig.add_axes([0, 0, 1, 1])
    ax.set_xlim(0, 10.5)
    ax.set_ylim(height, 0)
    ax.axis("off")
    ax.text(0.2, 0.25, f"▾ {title}", color="#e6e6e6", fontsize=10, va="center", weight="bold")
    y = 0.65
    box_top = None
    for depth, items in lines:
        if items == "box":
            box_top = y - 0.05
            y += 0.1
            continue
        x0 = 0.25 + 0.2 * depth
        width = (10.5 - x0 - 0.25) / max(1, len(items))
        for k, (kind, text, icon) in enumerate(items):
            x = x0 + k * width
            colour = "#e6e6e6"
            if kind == "button":
                ax.add_patch(FancyBboxPatch((x, y - 0.14), width - 0.08, 0.28, fc="#545454", ec="#3d3d3d",
                                            boxstyle="round,pad=0.0,rounding_size=0.05"))
                ax.text(x + (width - 0.08) / 2, y, text, color=colour, fontsize=8.5, ha="center", va="center")
                continue
            mark = {"CHECKMARK": "✓ ", "ERROR": "⚠ ", "CANCEL": "✗ ", "INFO": "ⓘ ", "CHECKBOX_HLT": "☑ "}.get(icon, "")
            if kind == "toggle" and not mark:
                mark = "☐ "
            if icon in ("ERROR", "CANCEL"):
                colour = "#ff8a80"
            elif icon == "CHECKMARK":
                colour = "#a5d6a7"
            ax.text(x, y, mark + text, color=colour, fontsize=8.5, va="center", family="DejaVu Sans")
        y += 0.36
    if box_top is not None:
        ax.add_patch(FancyBboxPatch((0.3, box_top), 9.95, y - box_top - 0.15, boxstyle="round,pad=0.02",
                                    fc="none", ec="#4a4a4a", lw=1.0))
    fig.savefig(path, dpi=110, facecolor=fig.get_facecolor())
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=os.path.join(ROOT, "docs", "measures-panel.png"))
    args = parser.parse_args(argv)
    os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="lamp-docs-"))
    sys.path.insert(0, ROOT)
    import bpy

    from tools import dev_extension

    with dev_extension.enabled_from_source(bpy, "lamp_docs") as package:
        addon = sys.modules[f"{package}.lamp_addon"]
        core = sys.modules[f"{package}.core_tracer"]
        bl_scene = bpy.context.scene
        scene = core.load_scene(os.path.join(ROOT, "presets", "four-lamp-night-lit-photometric.json"))
        addon.design.properties.scene_to_design(bl_scene, scene)
        bl_scene.lamp_measures.folder = REPORT
        lines: list = []
        layout = _Recorder(lines)

        class Proxy:
            pass

        proxy = Proxy()
        proxy.layout = layout
        bpy.types.LAMP_PT_measures.draw(proxy, bpy.context)
        draw_panel(lines, "Measures", args.out)
    print(f"{len(lines)} lines -> {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""The add-on's modules import each other in one direction: no import circles (settings modules sit
below the panels and operators that use them)."""


import pytest
from helpers import ROOT, package_imports

ADDON = ROOT / "lamp_addon"


def _graph() -> dict[str, set[str]]:
    return package_imports(ADDON)


def _circle(graph: dict[str, set[str]]) -> list[str] | None:
    state: dict[str, int] = {}  # 1: on the current path, 2: done

    def visit(node, path):
        state[node] = 1
        for nxt in sorted(graph[node]):
            if state.get(nxt) == 1:
                return path[path.index(nxt):] + [node, nxt] if nxt in path else [node, nxt]
            if nxt not in state and (found := visit(nxt, path + [node])):
                return found
        state[node] = 2
        return None

    for start in sorted(graph):
        if start not in state and (found := visit(start, [])):
            return found
    return None


def test_the_circle_finder_finds_a_circle():
    assert _circle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) is not None
    assert _circle({"a": {"b"}, "b": {"c"}, "c": set()}) is None


@pytest.mark.slow
def test_no_import_circles_in_the_addon():
    graph = _graph()
    assert {"preferences", "presets.library", "study.ops", "study.panel", "study.settings"} <= set(graph)
    assert _circle(graph) is None, " -> ".join(_circle(graph))
    assert "presets.library" not in graph["preferences"]
    assert "study.ops" not in graph["study.panel"] and "study.panel" not in graph["study.ops"]


def test_library_folders_changed_marks_the_listing_stale(addon, lamp_addon):
    import bpy

    listing = lamp_addon.presets.library.listing()
    listing.stale = False
    prefs = bpy.context.preferences.addons[addon].preferences
    item = prefs.library_folders.add()
    try:
        item.directory = "/nonexistent-lamp-folder"
        assert listing.stale  # the preferences told the library through its listener
    finally:
        prefs.library_folders.remove(len(prefs.library_folders) - 1)


@pytest.mark.slow
def test_the_render_side_does_not_depend_on_a_panel():
    """The render engine, its camera and the operators reach no sidebar panel module, directly or
    through another module: the actions area's registry (``actions``) sits below both."""
    graph = _graph()

    def reached(start: str) -> set[str]:
        seen, todo = set(), [start]
        while todo:
            for nxt in graph[todo.pop()] - seen:
                seen.add(nxt)
                todo.append(nxt)
        return seen

    panels = {name for name in graph if name.rpartition(".")[2] in ("panel", "panels")}
    for module in ("render.engine", "design.camera", "design.lamp_camera", "design.view_link", "render.camera_sync",
                   "render.camera_ops", "render.ops", "compare.ops", "render.exposure"):
        assert not reached(module) & panels, (module, reached(module) & panels)


def _registered_classes(lamp_addon) -> list[type]:
    """The classes the add-on's modules list, through each sub-package's ``modules()``."""
    out = []
    for room in lamp_addon.modules():
        for module in room.modules() if hasattr(room, "modules") else (room,):
            out += getattr(module, "classes", ())
    return out


@pytest.mark.slow
def test_every_sub_package_lists_what_it_registers_and_registering_repeats(lamp_addon, bl_scene):
    """``lamp_addon.register`` hands over to the sub-packages, each registering the modules of its
    ``modules()``; unregistering takes all of it away and registering again, twice, brings back the
    same classes, the same handlers and the action buttons in their order."""
    import bpy

    classes = _registered_classes(lamp_addon)
    assert len(classes) >= 20 and all(cls.is_registered for cls in classes)
    watched = ("depsgraph_update_post", "load_post", "render_complete", "render_cancel")

    def state():
        return ({name: len(getattr(bpy.app.handlers, name)) for name in watched},
                list(lamp_addon.actions.ACTION_OPERATORS), [cls.is_registered for cls in classes])

    before = state()
    assert [idname for idname, _, _ in before[1]][:len(lamp_addon.actions.ORDER)] == list(lamp_addon.actions.ORDER)
    for _ in range(2):
        lamp_addon.unregister()
        assert not [cls for cls in classes if cls.is_registered]
        assert [idname for idname, _, _ in lamp_addon.actions.ACTION_OPERATORS] == ["lamp.build"]
        lamp_addon.register()
        assert state() == before
    assert hasattr(bl_scene, "lamp_design") and bpy.ops.lamp.lamp_add.poll()

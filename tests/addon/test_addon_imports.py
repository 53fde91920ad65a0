"""The add-on's modules import each other in one direction: no import circles (settings modules sit
below the panels and operators that use them)."""


from helpers import ROOT, sibling_imports

ADDON = ROOT / "lamp_addon"


def _graph() -> dict[str, set[str]]:
    modules = {p.stem: p for p in ADDON.glob("*.py") if p.stem != "__init__"}
    modules.update({p.name: p / "__init__.py" for p in ADDON.iterdir() if (p / "__init__.py").exists()})
    return {name: sibling_imports(path) & set(modules) for name, path in modules.items()}


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


def test_no_import_circles_in_the_addon():
    graph = _graph()
    assert {"preferences", "preset_library", "study_ops", "study_panel", "study_settings"} <= set(graph)
    assert _circle(graph) is None, " -> ".join(_circle(graph))
    assert "preset_library" not in graph["preferences"]
    assert "study_ops" not in graph["study_panel"] and "study_panel" not in graph["study_ops"]


def test_library_folders_changed_marks_the_listing_stale(addon, lamp_addon):
    import bpy

    listing = lamp_addon.preset_library.listing()
    listing.stale = False
    prefs = bpy.context.preferences.addons[addon].preferences
    item = prefs.library_folders.add()
    try:
        item.directory = "/nonexistent-lamp-folder"
        assert listing.stale  # the preferences told the library through its listener
    finally:
        prefs.library_folders.remove(len(prefs.library_folders) - 1)


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

    panels = {name for name in graph if name.endswith("_panel") or name.endswith("_panels")}
    for module in ("render_engine", "render_camera", "render_ops", "compare_ops", "display_ops"):
        assert not reached(module) & panels, (module, reached(module) & panels)

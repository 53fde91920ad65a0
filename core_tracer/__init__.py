"""The lamp renderer of Nishio, Yasuda, Yokoi and Toriwaki (IPSJ 1990), in numpy.

Never imports bpy: the Blender add-on (``lamp_addon``) depends on this package, not the reverse.

The names below load on first use (PEP 562): importing the package costs nothing, so the command
line (``python -m core_tracer``) handles a signal from its first moments, before numpy loads.
"""

from __future__ import annotations

import importlib

# The tool's version: the extension's (blender_manifest.toml) and the package's (pyproject.toml), which a
# test keeps equal; ``--version`` prints it and measures.json records it.
__version__ = "0.1.0"

_EXPORTS = {
    "PASS_NAMES": ".raytrace.engine", "RenderCancelled": ".raytrace.engine", "RenderResult": ".raytrace.engine",
    "render": ".raytrace.engine", "render_passes": ".raytrace.engine",
    "SceneError": ".scene.reading", "scene_to_json": ".scene.reading",
    "load_scene": ".scene.validate", "normalize": ".scene.validate", "parse_scene": ".scene.validate",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(module, __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_EXPORTS))

"""What the Free-form Parts panel says above its list: whether free-form rendering works here, what
the Lamp Tracer renders, and the first problem of the parts (a role value out of range, a mesh the
tracer cannot use), naming the object and what to change.

Embree's absence is said once, in words (``core_tracer.freeform.available``); everything else of the
add-on works without it. Mesh problems are found when the geometry is made (a render, a viewport
redraw, an export) and kept here per scene until the next success (``note_mesh_problem``).
"""

from __future__ import annotations

import textwrap
from dataclasses import dataclass

import bpy

from ...core_tracer.scene.reading import SceneError
from ..design import builder as design_builder
from ..design import properties as design_properties
from . import parametric, properties
from . import scene as freeform_scene

WRAP = 44  # characters per label line in the sidebar

_mesh_problems: dict[str, str] = {}  # scene name -> the last mesh problem a render met
_available: list = []  # (bool, reason), asked once


@dataclass(frozen=True)
class Line:
    text: str
    icon: str = "NONE"


def available() -> tuple[bool, str]:
    if not _available:
        from ...core_tracer import freeform

        _available.append(freeform.available())
    return _available[0]


def note_mesh_problem(bl_scene: bpy.types.Scene, message: str | None) -> None:
    if message is None:
        _mesh_problems.pop(bl_scene.name, None)
    else:
        _mesh_problems[bl_scene.name] = message


def forget_mesh_problems() -> None:
    """A new file: the mesh problems renders met were of the old file's scenes (their names come again)."""
    _mesh_problems.clear()


def part_problem(bl_scene: bpy.types.Scene) -> str | None:
    """The first problem of the scene's parts in one line, or None."""
    objects = properties.role_objects(bl_scene)
    if not objects:
        return None
    try:
        scene = design_properties.design_to_scene(bl_scene)
    except SceneError:
        return None  # the design's own error is the top of the Lamp panel's to show
    try:
        freeform_scene.with_freeform(scene, objects)
    except SceneError as e:
        return part_error_text(e, objects)
    return _mesh_problems.get(bl_scene.name)


def part_error_text(error: SceneError, objects) -> str:
    """A ``freeform.parts[i]...`` error in the designer's words: the object's name first."""
    path = error.path
    prefix = "freeform.parts["
    if path.startswith(prefix):
        index, _, rest = path[len(prefix):].partition("]")
        if index.isdigit() and int(index) < len(objects):
            field = rest.lstrip(".")
            return f'"{objects[int(index)].name}" {field}: {error.message}'
    return str(error)


def panel_lines(bl_scene: bpy.types.Scene) -> list[Line]:
    ok, reason = available()
    lines: list[Line] = []
    if not ok:
        return [Line(text, "ERROR" if i == 0 else "NONE") for i, text in enumerate(textwrap.wrap(reason, WRAP))]
    if properties.role_objects(bl_scene):
        lines += [Line(text, "INFO" if i == 0 else "NONE")
                  for i, text in enumerate(textwrap.wrap(rendered_text(bl_scene), WRAP))]
    problem = part_problem(bl_scene)
    if problem is not None:
        lines += [Line(text, "ERROR" if i == 0 else "NONE") for i, text in enumerate(textwrap.wrap(problem, WRAP))]
    return lines


# What the Lamp Tracer renders when parts have roles (freeform.render.prepare): the parts, with the
# parametric lamps the design still uses as meshes (freeform.parametric); a lamp that is not built at
# its current design is left out, and Build Lamp brings it in.
MIXED_TEXT = "The Lamp Tracer renders these parts with the parametric lamps"
PARTS_ONLY_TEXT = "The Lamp Tracer renders these parts only (no parametric lamp is built and shown)"
NOT_BUILT_TEXT = ("The Lamp Tracer renders these parts only: the parametric lamps are not built at "
                  "their current design (Build Lamp)")


def rendered_text(bl_scene: bpy.types.Scene) -> str:
    """What the Lamp Tracer renders of a scene with parts."""
    if parametric.built_parts(bl_scene, None):
        return MIXED_TEXT
    status = design_builder.build_status(bl_scene)
    never_built = status == design_builder.NOT_BUILT and len(bl_scene.lamp_design.lamps) > 0
    stale = status not in (design_builder.UP_TO_DATE, design_builder.PREVIEW)
    if stale and (never_built or parametric.used_parts(bl_scene, None)):
        return NOT_BUILT_TEXT
    return PARTS_ONLY_TEXT

"""What is compared: the design, whatever else is in the file. Cycles renders what the tracer
renders: the lamp's objects (built when out of date) and the free-form parts; every other object
(the startup Cube and Light, a car body around the lamp ...) is left out of the Cycles half.
"""

from __future__ import annotations

from ..design import builder as design_builder
from ..design.root import PART_KEY
from ..freeform.properties import has_role


def needs_build(bl_scene) -> bool:
    """Whether Compare must build the lamp before rendering, so that Cycles renders what the tracer
    renders: when the objects are not up to date with the design (not built, out of date, a preview
    lens, a part deleted). Objects that are up to date are rendered as they are, with the
    designer's edits."""
    return not design_builder.is_up_to_date(bl_scene)


def _in_design(ob) -> bool:
    """Objects the builder made carry the part key; what the designer parented under the root is
    part of the lamp too, and so is every free-form part (a mesh with a lamp role)."""
    if has_role(ob):
        return True
    while ob is not None:
        if ob.get(PART_KEY):
            return True
        ob = ob.parent
    return False


def objects_outside_design(bl_scene) -> list:
    """Objects that Cycles would render and that are not part of the design: the startup Cube and
    Light, a car body around the lamp ... Cameras, plain empties and what is already out of the
    render (hidden, in a collection hidden from render or excluded from every rendered view layer)
    are not listed."""
    rendered = {ob.as_pointer(): ob for layer in bl_scene.view_layers if layer.use for ob in layer.objects}
    out = []
    for ob in sorted(rendered.values(), key=lambda o: o.name):
        if ob.hide_render or _in_design(ob) or ob.type == "CAMERA":
            continue
        if ob.type == "EMPTY" and ob.instance_type == "NONE":
            continue
        if all(c.hide_render for c in ob.users_collection):
            continue
        out.append(ob)
    return out


def left_out_text(names: list[str], limit: int = 6) -> str:
    """"left out of the Cycles half: Cube, Light" (at most ``limit`` names, then how many more)."""
    shown = ", ".join(names[:limit]) + (f" and {len(names) - limit} more" if len(names) > limit else "")
    return f"left out of the Cycles half: {shown}"

"""The paper's reflector scatter (eq. 3) in a Cycles reflector material, as the paper states it.

Eq. 3 adds w I0 (cos beta)^n at every reflector hit of a path from the eye, beta between the normal
and the half vector of the direction to the bulb and the direction to the viewer (docs/model.md §5.2).
It is unnormalised and does not depend on how large the bulb looks from the reflector, so a Glossy
BSDF lit by the bulb does not reproduce it (on the paper's baseline such a lobe returns about a fifth
of it). Here it is an Emission whose strength shader nodes compute at each shading point:

    strength = w max(I0) max(0, N . normalize(normalize(bulb - P) + I))^n,  colour I0 / max(I0)

with P, N and I (Incoming, toward the viewer) from the Geometry node, and the bulb's centre given in
the reflector object's own frame and carried to the world by a Vector Transform, so a moved lamp keeps
it. The sun's **phantom light** (``light.phantom``, ``raytrace.sunlight``) is a second Emission of the
same form with the sun's direction, of colour s S T_sun (T_sun the lens as a flat plate), where the
normal faces the sun and the line from the point toward the sun crosses the lens's apex plane inside
its outline (the rounded rectangle of ``scene.outline``: |max(|x, z| - core, 0)| <= corner).

Both are hidden from diffuse rays (Light Path's Is Diffuse Ray picks an empty shader), and the
reflector material's emission sampling is off (``design.materials.reflector``), so they light
nothing: eq. 3 is a glow toward the eye, not a light. Like every node the builder drives, they are
found by name; ``add_nodes`` adds them to a reflector built before they existed.
"""

from __future__ import annotations

import bpy

from ..convert import cycles, units

GLOW = "Reflector Eq. 3"
PHANTOM = "Reflector Phantom"


def new_node(tree, kind: str, name: str, location: tuple[float, float], **props):
    node = tree.nodes.new(kind)
    node.name = node.label = name
    node.location = location
    for key, value in props.items():
        setattr(node, key, value)
    return node


def vector_math(tree, name: str, operation: str, location, a, b=None):
    made = new_node(tree, "ShaderNodeVectorMath", name, location, operation=operation)
    tree.links.new(a, made.inputs[0])
    if b is not None:
        tree.links.new(b, made.inputs[1])
    return made


def math_node(tree, name: str, operation: str, location, a, b=None, value: float = 0.0):
    """A Math node: ``a`` (socket) into its first input, ``b`` (socket) or ``value`` into its second."""
    made = new_node(tree, "ShaderNodeMath", name, location, operation=operation)
    tree.links.new(a, made.inputs[0])
    if b is not None:
        tree.links.new(b, made.inputs[1])
    else:
        made.inputs[1].default_value = value
    return made


def to_world(tree, name: str, kind: str, location, source):
    made = new_node(tree, "ShaderNodeVectorTransform", name, location, vector_type=kind, convert_from="OBJECT",
                 convert_to="WORLD")
    tree.links.new(source, made.inputs["Vector"])
    return made


def blinn(tree, prefix: str, y: float, geometry, toward) -> bpy.types.Node:
    """max(0, N . normalize(toward + I))^n (n in the node "<prefix> Shininess", input 1)."""
    both = vector_math(tree, f"{prefix} Light + View", "ADD", (-800, y), toward, geometry.outputs["Incoming"])
    half = vector_math(tree, f"{prefix} Half Vector", "NORMALIZE", (-650, y), both.outputs["Vector"])
    cos_beta = vector_math(tree, f"{prefix} cos beta", "DOT_PRODUCT", (-500, y), geometry.outputs["Normal"],
                            half.outputs["Vector"])
    facing = math_node(tree, f"{prefix} cos beta >= 0", "MAXIMUM", (-350, y), cos_beta.outputs["Value"])
    return math_node(tree, f"{prefix} Shininess", "POWER", (-200, y), facing.outputs["Value"], value=20.0)


def emission(tree, name: str, y: float, strength, path, out_socket, *, seen_by: str = "") -> bpy.types.Node:
    """An Emission of ``strength`` (a socket, or None: the node's own Strength) added to what feeds
    ``out_socket``, hidden from diffuse rays, or (``seen_by`` "Is Camera Ray") seen by camera rays alone."""
    glow = new_node(tree, "ShaderNodeEmission", name, (250, y))
    if strength is not None:
        tree.links.new(strength, glow.inputs["Strength"])
    if seen_by:
        gate = new_node(tree, "ShaderNodeMixShader", f"{name} For Camera Rays Only", (450, y))
        tree.links.new(path.outputs[seen_by], gate.inputs[0])
        tree.links.new(glow.outputs["Emission"], gate.inputs[2])  # the first shader left empty: nothing
    else:
        gate = new_node(tree, "ShaderNodeMixShader", f"{name} Not For Diffuse Rays", (450, y))
        tree.links.new(path.outputs["Is Diffuse Ray"], gate.inputs[0])
        tree.links.new(glow.outputs["Emission"], gate.inputs[1])  # second shader left empty: nothing
    total = new_node(tree, "ShaderNodeAddShader", f"+ {name}", (700, y))
    if out_socket.links:
        tree.links.new(out_socket.links[0].from_socket, total.inputs[0])
    tree.links.new(gate.outputs["Shader"], total.inputs[1])
    tree.links.new(total.outputs["Shader"], out_socket)
    return glow


def add_nodes(tree) -> None:
    """Add the eq. 3 and phantom emissions (module docstring) to a reflector tree that lacks them,
    between what feeds the Output's Surface and the Output. A tree without the builder's Output and
    Light Path nodes (the designer rebuilt it) is left alone; the build reports the nodes it misses."""
    out, path = tree.nodes.get("Output"), tree.nodes.get("Light Path")
    if out is None or path is None:
        return
    out.location = (950, -200)
    geometry = tree.nodes.get("Eq. 3 Geometry") or new_node(tree, "ShaderNodeNewGeometry", "Eq. 3 Geometry",
                                                         (-1500, -900))
    if tree.nodes.get(GLOW) is None:
        y = -800
        centre = new_node(tree, "ShaderNodeCombineXYZ", "Eq. 3 Bulb Centre", (-1500, y - 300))
        bulb = to_world(tree, "Eq. 3 Bulb Centre In World", "POINT", (-1300, y - 300), centre.outputs["Vector"])
        gap = vector_math(tree, "Eq. 3 To Bulb", "SUBTRACT", (-1100, y), bulb.outputs["Vector"],
                           geometry.outputs["Position"])
        to_bulb = vector_math(tree, "Eq. 3 Bulb Direction", "NORMALIZE", (-950, y), gap.outputs["Vector"])
        powered = blinn(tree, "Eq. 3", y, geometry, to_bulb.outputs["Vector"])
        weight = math_node(tree, "Eq. 3 Weight", "MULTIPLY", (-50, y), powered.outputs["Value"])
        emission(tree, GLOW, y, weight.outputs["Value"], path, out.inputs["Surface"])
    if tree.nodes.get(PHANTOM) is None:
        _add_phantom(tree, geometry, path, out)


def _add_phantom(tree, geometry, path, out) -> None:
    y = -1600
    sun = new_node(tree, "ShaderNodeCombineXYZ", "Phantom Sun Direction", (-1700, y - 300))  # the lamp's frame
    sun_world = to_world(tree, "Phantom Sun Direction In World", "VECTOR", (-1500, y), sun.outputs["Vector"])
    to_sun = vector_math(tree, "Phantom Sun", "NORMALIZE", (-950, y), sun_world.outputs["Vector"])
    powered = blinn(tree, "Phantom", y, geometry, to_sun.outputs["Vector"])
    facing = vector_math(tree, "Phantom N . Sun", "DOT_PRODUCT", (-500, y - 200), geometry.outputs["Normal"],
                          to_sun.outputs["Vector"])
    lit = math_node(tree, "Phantom Faces The Sun", "GREATER_THAN", (-350, y - 200), facing.outputs["Value"])
    # Where the line toward the sun crosses the apex plane (the lamp's frame): P + t L, t = (y_B - P_y) / L_y.
    local = new_node(tree, "ShaderNodeVectorTransform", "Phantom Point In Lamp", (-1700, y - 600), vector_type="POINT",
                  convert_from="WORLD", convert_to="OBJECT")
    tree.links.new(geometry.outputs["Position"], local.inputs["Vector"])
    split = new_node(tree, "ShaderNodeSeparateXYZ", "Phantom Point Y", (-1500, y - 600))
    tree.links.new(local.outputs["Vector"], split.inputs["Vector"])
    rise = new_node(tree, "ShaderNodeMath", "Phantom Apex Plane", (-1300, y - 600), operation="SUBTRACT")
    tree.links.new(split.outputs["Y"], rise.inputs[1])
    t = math_node(tree, "Phantom Sun Y", "DIVIDE", (-1100, y - 600), rise.outputs["Value"], value=-1.0)
    along = new_node(tree, "ShaderNodeVectorMath", "Phantom Along The Sun", (-950, y - 600), operation="SCALE")
    tree.links.new(sun.outputs["Vector"], along.inputs[0])
    tree.links.new(t.outputs["Value"], along.inputs["Scale"])
    cross = vector_math(tree, "Phantom Crossing", "ADD", (-800, y - 600), local.outputs["Vector"],
                         along.outputs["Vector"])
    flat = vector_math(tree, "Phantom Crossing x, z", "MULTIPLY", (-650, y - 600), cross.outputs["Vector"])
    flat.inputs[1].default_value = (1.0, 0.0, 1.0)
    size = vector_math(tree, "Phantom |x, z|", "ABSOLUTE", (-500, y - 600), flat.outputs["Vector"])
    beyond = vector_math(tree, "Phantom Outline Core", "SUBTRACT", (-350, y - 600), size.outputs["Vector"])
    past = vector_math(tree, "Phantom Past The Core", "MAXIMUM", (-200, y - 600), beyond.outputs["Vector"])
    past.inputs[1].default_value = (0.0, 0.0, 0.0)
    reach = vector_math(tree, "Phantom Past The Core, Length", "LENGTH", (-50, y - 600), past.outputs["Vector"])
    inside = math_node(tree, "Phantom Outline Corner", "LESS_THAN", (100, y - 600), reach.outputs["Value"])
    gates = math_node(tree, "Phantom Lit And Inside", "MULTIPLY", (100, y - 300), lit.outputs["Value"],
                  inside.outputs["Value"])
    seen = math_node(tree, "Phantom Seen", "MULTIPLY", (-50, y), powered.outputs["Value"], gates.outputs["Value"])
    weight = math_node(tree, "Phantom Weight", "MULTIPLY", (100, y), seen.outputs["Value"])
    emission(tree, PHANTOM, y, weight.outputs["Value"], path, out.inputs["Surface"])


def drive(tree, lamp: dict, bulb_center, as_lobe: bool, drive_node, drive_input, missing: list[str]) -> None:
    """Write the design's values into the eq. 3 and phantom nodes (``design.materials.reflector``
    passes its ``_drive`` and ``_drive_input``); both emit nothing where the glow is the lobe."""
    r = lamp["reflector"]
    peak, color = (0.0, (1.0, 1.0, 1.0)) if as_lobe else cycles.emission_of(lamp["bulb"]["intensity"],
                                                                          lamp["bulb"]["on"])
    if bulb_center is not None:
        x, y, z = (units.BU_PER_MM * float(c) for c in bulb_center)
        drive_node(tree, "Eq. 3 Bulb Centre", missing, X=x, Y=y, Z=z)
    drive_input(tree, "Eq. 3 Shininess", 1, float(r["shininess"]), missing)
    drive_input(tree, "Eq. 3 Weight", 1, float(r["scatter"]) * peak, missing)
    drive_node(tree, GLOW, missing, Color=(*color, 1.0))
    phantom = None if as_lobe else lamp.get(cycles.PHANTOM)
    light = phantom["light"] if phantom else (0.0, 0.0, 0.0)
    peak, color = cycles.emission_of(list(light))
    drive_input(tree, "Phantom Weight", 1, float(r["scatter"]) * peak, missing)
    drive_node(tree, PHANTOM, missing, Color=(*color, 1.0))
    drive_input(tree, "Phantom Shininess", 1, float(r["shininess"]), missing)
    if phantom:
        sx, sy, sz = phantom["direction"]
        drive_node(tree, "Phantom Sun Direction", missing, X=sx, Y=sy, Z=sz)
        drive_input(tree, "Phantom Apex Plane", 0, units.BU_PER_MM * phantom["plane_b"], missing)
        drive_input(tree, "Phantom Sun Y", 1, sy if sy != 0.0 else -1e-9, missing)
        core_x, core_z = (units.BU_PER_MM * c for c in phantom["core"])
        drive_input(tree, "Phantom Outline Core", 1, (core_x, 0.0, core_z), missing)
        # LESS_THAN is strict: a hair more than the corner keeps a sharp rectangle's (corner 0) inside.
        drive_input(tree, "Phantom Outline Corner", 1, units.BU_PER_MM * phantom["corner"] + 1e-9, missing)

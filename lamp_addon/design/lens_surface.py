"""The surface terms of eq. 1 that Cycles' BSDFs cannot make, as the tracer adds them: the lens's own
term, and the body's highlight (``add_body_nodes``: the body's Diffuse BSDF makes the rest of eq. 1 under
Cycles' sun and world, but a delta sun makes no Phong highlight).

Where an eye ray meets a lens's outer face the tracer adds r × eq. (1) with the lens's colours
(docs/model.md §4 and §5.2, ``Lighting.lens_surface``): r the Fresnel reflectance there, and

    [d + (1 - d) s S cos theta] C0 + s w (cos beta)^n C1     (w = 0 where cos theta <= 0)

under the sun (direction L, strength s, colour S, highlight colour C1; ambient d, not added where
surroundings light the lamp). Cycles' glass reflects the world by its mirror, as the tracer's
reflected share does, but a delta sun never meets a mirror, and glass has no diffuse colour: so this
term is an Emission on the lens seen by camera rays alone (the tracer adds it for eye rays only), of
colour Fresnel(n) × the term above, computed by shader nodes from the Geometry node's normal and
Incoming and the sun's direction in the lens object's frame (carried to the world by a Vector
Transform). A lens without a sun's values (a free-form part, a photometric design, whose lens
colour is black) emits nothing.
"""

from __future__ import annotations

from ..convert import cycles
from .reflector_glow import blinn, emission, math_node, new_node, to_world, vector_math

SURFACE = "Lens Eq. 1"
BODY = "Body Eq. 1 Highlight"


def _sun_nodes(tree, prefix: str, y: float):
    """The nodes eq. 1 needs at a shading point, in the part's object frame carried to the world: the
    Geometry, the Light Path, the unit vector toward the sun (node "<prefix> Sun Direction", the lamp's
    frame), (cos beta)^n (``blinn``) and cos theta with its sign test."""
    geometry = new_node(tree, "ShaderNodeNewGeometry", f"{prefix} Geometry", (-1500, y))
    path = (tree.nodes.get(f"{prefix} Light Path")
            or new_node(tree, "ShaderNodeLightPath", f"{prefix} Light Path", (0, y - 500)))
    sun = new_node(tree, "ShaderNodeCombineXYZ", f"{prefix} Sun Direction", (-1700, y - 300))  # the lamp's frame
    sun_world = to_world(tree, f"{prefix} Sun Direction In World", "VECTOR", (-1500, y - 300), sun.outputs["Vector"])
    to_sun = vector_math(tree, f"{prefix} Sun", "NORMALIZE", (-1300, y - 300), sun_world.outputs["Vector"])
    powered = blinn(tree, prefix, y, geometry, to_sun.outputs["Vector"])
    cos_theta = vector_math(tree, f"{prefix} N . Sun", "DOT_PRODUCT", (-1100, y - 300), geometry.outputs["Normal"],
                            to_sun.outputs["Vector"])
    in_sun = math_node(tree, f"{prefix} Faces The Sun", "GREATER_THAN", (-800, y - 400), cos_theta.outputs["Value"])
    # s w (cos beta)^n C1 where cos theta > 0
    shown = math_node(tree, f"{prefix} Highlight Where Lit", "MULTIPLY", (-50, y), powered.outputs["Value"],
                      in_sun.outputs["Value"])
    highlight = new_node(tree, "ShaderNodeVectorMath", f"{prefix} Highlight", (100, y), operation="SCALE")
    tree.links.new(shown.outputs["Value"], highlight.inputs["Scale"])
    return path, cos_theta, highlight


def add_nodes(tree) -> None:
    """Add the lens's eq. 1 emission (module docstring) between what feeds the Output's Surface and the
    Output; a tree without the builder's Output node is left alone (the build reports what it misses)."""
    out = tree.nodes.get("Output")
    if out is None or tree.nodes.get(SURFACE) is not None:
        return
    y = -700
    path, cos_theta, highlight = _sun_nodes(tree, "Lens", y)
    lit = math_node(tree, "Lens cos theta", "MAXIMUM", (-950, y - 300), cos_theta.outputs["Value"])
    # [d + (1 - d) s S cos theta] C0
    sunlit = new_node(tree, "ShaderNodeVectorMath", "Lens Sun Light", (-650, y - 300), operation="SCALE")
    tree.links.new(lit.outputs["Value"], sunlit.inputs["Scale"])
    ambient = vector_math(tree, "Lens Ambient", "ADD", (-500, y - 300), sunlit.outputs["Vector"])
    diffuse = vector_math(tree, "Lens Diffuse Colour", "MULTIPLY", (-350, y - 300), ambient.outputs["Vector"])
    both = vector_math(tree, "Lens Eq. 1 Sum", "ADD", (250, y - 200), diffuse.outputs["Vector"],
                       highlight.outputs["Vector"])
    fresnel = new_node(tree, "ShaderNodeFresnel", "Lens Fresnel", (250, y - 400))
    reflected = new_node(tree, "ShaderNodeVectorMath", "Lens Reflected Share", (400, y - 300), operation="SCALE")
    tree.links.new(both.outputs["Vector"], reflected.inputs[0])
    tree.links.new(fresnel.outputs["Fac"], reflected.inputs["Scale"])
    glow = emission(tree, SURFACE, y - 900, None, path, out.inputs["Surface"], seen_by="Is Camera Ray")
    glow.inputs["Strength"].default_value = 1.0
    tree.links.new(reflected.outputs["Vector"], glow.inputs["Color"])


def add_body_nodes(tree) -> None:
    """Add the body's highlight of eq. 1, s w (cos beta)^n C1 where the sun lights it, as an Emission seen
    by camera rays alone (its diffuse part is the Diffuse BSDF under Cycles' sun and world); a tree
    without the builder's Output node, or that has it already, is left alone."""
    out = tree.nodes.get("Output")
    if out is None or tree.nodes.get(BODY) is not None:
        return
    y = -400
    path, _, highlight = _sun_nodes(tree, "Body", y)
    glow = emission(tree, BODY, y - 900, None, path, out.inputs["Surface"], seen_by="Is Camera Ray")
    glow.inputs["Strength"].default_value = 1.0
    tree.links.new(highlight.outputs["Vector"], glow.inputs["Color"])


def _no_sun() -> dict:
    return {"direction": (0.0, -1.0, 0.0), "light": (0.0, 0.0, 0.0), "ambient": 0.0, "highlight": (0.0, 0.0, 0.0)}


def drive_body(tree, sun: dict | None, body: dict, drive_node, drive_input, missing: list[str]) -> None:
    """Write the body's highlight colour and shininess and the sun (``cycles.lens_sun``; None: no highlight)."""
    sun = sun or _no_sun()
    x, y, z = sun["direction"]
    drive_node(tree, "Body Sun Direction", missing, X=x, Y=y, Z=z)
    drive_input(tree, "Body Highlight", 0, tuple(float(body["specular"]) * c for c in sun["highlight"]), missing)
    drive_input(tree, "Body Shininess", 1, float(body["shininess"]), missing)


def drive(tree, lamp: dict, drive_node, drive_input, missing: list[str]) -> None:
    """Write the lens's colours and the sun (``lamp[cycles.LENS_SUN]``, from ``cycles.lens_suns``) into
    the nodes; without a sun every term is 0."""
    sun = lamp.get(cycles.LENS_SUN)
    lens = lamp["lens"]
    if sun is None:
        sun = _no_sun()
    x, y, z = sun["direction"]
    drive_node(tree, "Lens Sun Direction", missing, X=x, Y=y, Z=z)
    drive_input(tree, "Lens Sun Light", 0, tuple(sun["light"]), missing)  # (1 - d) s S
    drive_input(tree, "Lens Ambient", 1, (sun["ambient"],) * 3, missing)  # d, where it is seen
    drive_input(tree, "Lens Diffuse Colour", 1, tuple(float(c) for c in lens["diffuse_color"]), missing)
    drive_input(tree, "Lens Highlight", 0, tuple(float(lens["specular"]) * c for c in sun["highlight"]), missing)
    drive_input(tree, "Lens Shininess", 1, float(lens["shininess"]), missing)
    drive_input(tree, "Lens Fresnel", 0, float(lens["ior"]), missing)

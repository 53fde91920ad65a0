"""Cycles materials, sun and world equivalent to the paper's parameters (BLENDER-NOTES "Cycles equivalents").

The mapping, part by part (A per mm; 1 mm = 0.001 Blender units):

- **Lens glass**: Principled BSDF, Transmission Weight 1, Roughness 0, Base Color white, IOR = n; plus a
  Volume Absorption node on the Volume output. Cycles absorbs ``Density * (1 - Color)`` per Blender unit,
  so ``Density = D = 1000 * max(A)`` and ``Color = 1 - 1000 * A / D`` give exactly A per mm (eq. 2).
  A clear lens (A = 0) gets Density 0. ``Color`` is written unclamped (the socket accepts any value).
- **Bulb**: Emission; a camera sees ``Strength * Color``, so ``Strength = max(I0)`` and
  ``Color = I0 / max(I0)`` show exactly I0. A bulb that is off has Strength 0.
- **Reflector**: the sum of (a) a sharp mirror (Glossy, GGX, Roughness 0) of colour = reflectance, the
  paper's recursive mirror ray; (b) the Blinn scatter lobe of eq. 3 as a Glossy BSDF with the Beckmann
  distribution, colour = scatter w and ``Roughness = (2 / (n + 2)) ** 0.25``: Walter et al. (2007) match
  a Blinn-Phong exponent n with the Beckmann slope alpha = sqrt(2 / (n + 2)), and Cycles' Glossy node
  squares its Roughness input into alpha; (c) the constant colour C of the first reflector hit as an
  Emission of colour C, seen by every ray but diffuse ones (so it lights nothing). Approximations: the
  Beckmann lobe is normalised where the paper's term is not, and Cycles adds C on every hit, the paper on
  the first of each branch.
- **Body, socket, lens side wall**: Diffuse BSDF of their colour. The paper's body adds the specular term
  of eq. 1 and treats socket and side wall as constant colours; only the diffuse part is reproduced.
- **Light** (the diffuse part of eq. 1, ``[d + (1 - d) cos theta] R0``): a sun of strength ``pi (1 - d)``
  shining along ``-light.direction`` (a Diffuse BSDF of albedo R0 then shows ``R0 (1 - d) cos theta``), and
  a world of colour d seen by diffuse rays only (adds ``R0 d``). Every other ray that leaves the scene sees
  the scene's ``background`` colour (black in the paper), so the camera sees a black background.
"""

from __future__ import annotations

import math

import bpy

from ..core_tracer.scene import validate as lamp_scene
from .convert import units

MM_PER_BU = units.MM_PER_BU


# ---------------------------------------------------------------------------------------------
# The numbers


def absorption_volume(absorption: list[float]) -> tuple[float, tuple[float, float, float]]:
    """(Density, Color) of a Volume Absorption node absorbing ``absorption`` per mm."""
    density = MM_PER_BU * max(absorption)
    if density <= 0.0:
        return 0.0, (1.0, 1.0, 1.0)
    return density, tuple(1.0 - MM_PER_BU * a / density for a in absorption)


def emission_of(intensity: list[float], on: bool = True) -> tuple[float, tuple[float, float, float]]:
    """(Strength, Color) of an Emission node that shows ``intensity`` to the camera."""
    peak = max(intensity)
    if peak <= 0.0:
        return 0.0, (1.0, 1.0, 1.0)
    return (peak if on else 0.0), tuple(c / peak for c in intensity)


def blinn_roughness(shininess: float) -> float:
    """Glossy Roughness input (Beckmann) matching a Blinn exponent n: alpha = sqrt(2/(n+2)), r = sqrt(alpha)."""
    return (2.0 / (shininess + 2.0)) ** 0.25


def sun_strength(ambient: float) -> float:
    """Sun strength giving a Diffuse BSDF of albedo R0 the value R0 (1 - d) cos theta (eq. 1)."""
    return math.pi * (1.0 - ambient)


# ---------------------------------------------------------------------------------------------
# Node trees


def _fresh_tree(idblock) -> bpy.types.NodeTree:
    if idblock.node_tree is None:  # Blender < 5.0 creates materials and worlds without nodes
        idblock.use_nodes = True
    tree = idblock.node_tree
    tree.nodes.clear()
    return tree


def _node(tree, kind: str, name: str, location: tuple[float, float], **inputs):
    node = tree.nodes.new(kind)
    node.name = node.label = name
    node.location = location
    for key, value in inputs.items():
        node.inputs[key.replace("_", " ")].default_value = value
    return node


def _rgba(color) -> tuple[float, float, float, float]:
    return (float(color[0]), float(color[1]), float(color[2]), 1.0)


def lens_glass(mat: bpy.types.Material, lamp: dict) -> None:
    lens = lamp["lens"]
    tree = _fresh_tree(mat)
    out = _node(tree, "ShaderNodeOutputMaterial", "Output", (300, 0))
    bsdf = _node(tree, "ShaderNodeBsdfPrincipled", "Lens BSDF", (0, 100), Base_Color=(1, 1, 1, 1),
                 Metallic=0.0, Roughness=0.0, IOR=lens["ior"], Transmission_Weight=1.0)
    a = lamp_scene.lens_absorption(lens)
    density, color = absorption_volume(a)
    vol = _node(tree, "ShaderNodeVolumeAbsorption", "Lens Absorption", (0, -300), Color=(*color, 1.0),
                Density=density)
    tree.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
    tree.links.new(vol.outputs["Volume"], out.inputs["Volume"])
    t = lens["thickness"]
    mat.diffuse_color = (*(math.exp(-x * t) for x in a), 0.5)  # solid view: the colour through the lens


def diffuse(mat: bpy.types.Material, color, name: str) -> None:
    tree = _fresh_tree(mat)
    out = _node(tree, "ShaderNodeOutputMaterial", "Output", (300, 0))
    bsdf = _node(tree, "ShaderNodeBsdfDiffuse", name, (0, 0), Color=_rgba(color), Roughness=0.0)
    tree.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
    mat.diffuse_color = _rgba(color)


def bulb(mat: bpy.types.Material, lamp: dict) -> None:
    b = lamp["bulb"]
    tree = _fresh_tree(mat)
    out = _node(tree, "ShaderNodeOutputMaterial", "Output", (300, 0))
    strength, color = emission_of(b["intensity"], b["on"])
    em = _node(tree, "ShaderNodeEmission", "Bulb Emission", (0, 0), Color=(*color, 1.0), Strength=strength)
    tree.links.new(em.outputs["Emission"], out.inputs["Surface"])
    mat.diffuse_color = (*color, 1.0) if b["on"] else (0.05, 0.05, 0.05, 1.0)


def reflector(mat: bpy.types.Material, lamp: dict) -> None:
    r = lamp["reflector"]
    tree = _fresh_tree(mat)
    out = _node(tree, "ShaderNodeOutputMaterial", "Output", (900, 0))
    grey = (r["reflectance"],) * 3 + (1.0,)
    mirror = _node(tree, "ShaderNodeBsdfGlossy", "Reflector Mirror", (0, 300), Color=grey, Roughness=0.0)
    mirror.distribution = "GGX"
    w = (r["scatter"],) * 3 + (1.0,)
    scatter = _node(tree, "ShaderNodeBsdfGlossy", "Reflector Scatter", (0, 50), Color=w,
                    Roughness=blinn_roughness(r["shininess"]))
    scatter.distribution = "BECKMANN"
    constant = _node(tree, "ShaderNodeEmission", "Reflector Constant", (0, -200), Color=_rgba(r["color"]),
                     Strength=1.0)
    path = _node(tree, "ShaderNodeLightPath", "Light Path", (0, -400))
    gate = _node(tree, "ShaderNodeMixShader", "Constant Not For Diffuse Rays", (300, -250))
    tree.links.new(path.outputs["Is Diffuse Ray"], gate.inputs[0])
    tree.links.new(constant.outputs["Emission"], gate.inputs[1])  # second shader left empty: nothing
    add1 = _node(tree, "ShaderNodeAddShader", "Mirror + Scatter", (300, 150))
    tree.links.new(mirror.outputs["BSDF"], add1.inputs[0])
    tree.links.new(scatter.outputs["BSDF"], add1.inputs[1])
    add2 = _node(tree, "ShaderNodeAddShader", "Reflector", (600, 0))
    tree.links.new(add1.outputs["Shader"], add2.inputs[0])
    tree.links.new(gate.outputs["Shader"], add2.inputs[1])
    tree.links.new(add2.outputs["Shader"], out.inputs["Surface"])
    mat.diffuse_color = (0.8, 0.8, 0.82, 1.0)
    mat.metallic = 1.0
    mat.roughness = 0.1


def world(wld: bpy.types.World, scene: dict) -> None:
    """Background ``d`` for diffuse rays (ambient of eq. 1), the scene's background colour for all others."""
    d = scene["light"]["ambient"]
    tree = _fresh_tree(wld)
    out = _node(tree, "ShaderNodeOutputWorld", "Output", (600, 0))
    seen = _node(tree, "ShaderNodeBackground", "Background", (0, 150), Color=_rgba(scene["background"]),
                 Strength=1.0)
    ambient = _node(tree, "ShaderNodeBackground", "Ambient", (0, -50), Color=(d, d, d, 1.0), Strength=1.0)
    path = _node(tree, "ShaderNodeLightPath", "Light Path", (0, 400))
    mix = _node(tree, "ShaderNodeMixShader", "Ambient For Diffuse Rays", (300, 0))
    tree.links.new(path.outputs["Is Diffuse Ray"], mix.inputs[0])
    tree.links.new(seen.outputs["Background"], mix.inputs[1])
    tree.links.new(ambient.outputs["Background"], mix.inputs[2])
    tree.links.new(mix.outputs["Shader"], out.inputs["Surface"])
    wld.color = tuple(float(c) for c in scene["background"])


def sun(light: bpy.types.SunLight, scene: dict) -> None:
    light.energy = sun_strength(scene["light"]["ambient"])
    light.color = (1.0, 1.0, 1.0)  # eq. 1's diffuse part carries no light colour
    light.angle = 0.0  # a directional light, as in the paper

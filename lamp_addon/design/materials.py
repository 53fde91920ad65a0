"""Cycles materials, sun and world equivalent to the paper's parameters (BLENDER-NOTES "Cycles equivalents").

The numbers come from ``convert.cycles``; this module puts them into node trees. The mapping, part by
part:

- **Lens glass**: Principled BSDF (Transmission Weight 1, Roughness 0, Base Color white, IOR = n) and a
  Volume Absorption node on the Volume output absorbing A per mm (eq. 2); the lens's own surface term
  of eq. 1 (its diffuse colour and highlight under the sun, times the Fresnel reflectance) as an
  Emission seen by camera rays alone (``lens_surface``).
- **Bulb**: Emission showing exactly I0 to the camera; a bulb that is off has Strength 0.
- **Reflector**: the sum of (a) a sharp mirror (Glossy, GGX, Roughness 0) of colour = reflectance, the
  paper's recursive mirror ray; (b) the paper's scatter of eq. 3, w I0 (cos beta)^n, as an Emission
  ("Reflector Eq. 3") whose strength shader nodes compute at every shading point, and the sun's
  phantom light in the same form (``reflector_glow``); seen on every reflector hit of a path from the
  eye, as in the model, never by diffuse rays, with the material's emission sampling off, so they light
  nothing (eq. 3 is a glow toward the eye, not a light); (c) the constant colour C of the first reflector hit as an
  Emission of colour C, seen only by rays that have not yet made a glossy bounce (Light Path's Glossy
  Depth 0: the reflector's own mirror is a glossy bounce, so a path sees C at its first reflector hit,
  as in docs/model.md §5.2) and never by diffuse rays. A Glossy BSDF ("Reflector Scatter", Beckmann,
  ``cycles.blinn_roughness``) is there too, of colour 0 in the paper's mode: eq. 3 is unnormalised and
  does not depend on the bulb's solid angle, so a lobe lit by the bulb returns about a fifth of it on
  the paper's baseline (docs/model.md §5.2). The photometric mode, whose glow is physical, uses that
  lobe (colour = its glow share) and no eq. 3 emission (``convert.cycles.SCATTER_AS_LOBE``,
  set by ``convert.photometric_cycles``). A reflector without a bulb to aim at (a free-form part whose bulb
  is not known) keeps the lobe. Approximations: a path that reflected inside the lens before its first
  reflector hit does not see C in Cycles (about r², 0.2 % of it; on the cut lenses of the evening preset
  Cycles' C stayed within 1 % of the tracer's).
- **Body, socket, lens side wall**: Diffuse BSDF of their colour. The body's specular term of eq. 1,
  s w (cos beta)^n C1 under the sun, is an Emission seen by camera rays alone (``lens_surface``), as the
  tracer adds it for eye rays only. The paper treats socket and side wall as constant colours; Cycles
  shades them diffuse (the lamp-off preset's +2.3 % on the lens, benchmarks/RESULTS.md).
- **Light** (the diffuse part of eq. 1, ``[d + (1 - d) cos theta] R0``): a sun of strength ``pi (1 - d)``
  shining along ``-light.direction`` and a world of colour d seen by diffuse rays only (adds ``R0 d``).
  Every other ray that leaves the scene sees the scene's ``background`` colour (black in the paper).
  The sun's ``strength`` s and ``sun_color`` S make it strength ``pi (1 - d) s`` of colour S (the
  environment sun's colour when ``follow_environment_color`` is on, as in the tracer).
- **Surroundings** (``environment``): the image in an Environment Texture (Linear, equirectangular) after
  a Mapping node turning it about Z, into a Background of the environment's strength, seen by every ray
  and added to the ambient for diffuse rays (the tracer's C0 E(n) / pi), the ambient then 0 (the
  surroundings take its place, docs/model.md §8.18); switched by two Mix Shaders, so a design without
  surroundings keeps the paper's world exactly. Where the sun follows the environment's, the image is
  the tracer's copy without its sun (``world_file.shown_file``).

A designer may edit these materials. So a tree is laid out once, when the builder makes the material
(``new=True``); every later build only writes the sockets a design parameter drives, on the nodes it
finds by their names (``"Lens BSDF"``, ...). Nodes the designer added, links they changed and the
inputs no parameter drives (a Roughness they raised, say) are left as they are. A driven node the
designer deleted is not brought back: each function returns the names of such nodes, and the build
reports them.
"""

from __future__ import annotations

import math

import bpy

from ...core_tracer.raytrace import sunlight
from ...core_tracer.scene.derived import lamp_geometry, lens_absorption
from ...core_tracer.scene.reading import SceneError
from ..convert import cycles
from . import lens_surface, reflector_glow


def _tree(idblock, new: bool) -> bpy.types.NodeTree | None:
    """The node tree of a material or world; emptied when the builder has just made ``idblock``."""
    if new:
        if idblock.node_tree is None:  # Blender < 5.0 creates materials and worlds without nodes
            idblock.use_nodes = True
        idblock.node_tree.nodes.clear()
    return idblock.node_tree


def _node(tree, kind: str, name: str, location: tuple[float, float], **inputs):
    node = tree.nodes.new(kind)
    node.name = node.label = name
    node.location = location
    for key, value in inputs.items():
        node.inputs[key.replace("_", " ")].default_value = value
    return node


def _drive(tree, name: str, missing: list[str], **inputs) -> None:
    """Set the driven ``inputs`` of the node called ``name`` (only those that differ, so an unchanged
    design does not make the renderers recompile the shader); note the node if it is gone."""
    node = tree.nodes.get(name) if tree is not None else None
    if node is None:
        missing.append(name)
        return
    for key, value in inputs.items():
        socket = node.inputs.get(key.replace("_", " "))
        if socket is None:
            missing.append(f"{name}: {key.replace('_', ' ')}")
            continue
        if not _same(socket.default_value, value):
            socket.default_value = value


def _same(stored, value) -> bool:
    """Whether a socket already holds ``value`` (Blender keeps 32-bit floats)."""
    stored = list(stored) if hasattr(stored, "__len__") else [stored]
    value = list(value) if hasattr(value, "__len__") else [value]
    if len(stored) != len(value):
        return False
    return all(abs(a - b) <= 1e-6 * max(1.0, abs(b)) for a, b in zip(stored, value, strict=True))


def _rgba(color) -> tuple[float, float, float, float]:
    return (float(color[0]), float(color[1]), float(color[2]), 1.0)


def _grey(value: float) -> tuple[float, float, float, float]:
    return (value, value, value, 1.0)


# ---------------------------------------------------------------------------------------------
# Lens glass


def lens_glass(mat: bpy.types.Material, lamp: dict, *, new: bool) -> list[str]:
    """The lens: clear glass absorbing as eq. 2 (``_glass``) and its own surface term of eq. 1 for eye
    rays (``lens_surface``)."""
    lens = lamp["lens"]
    a = lens_absorption(lens)
    missing = _glass(mat, new, "Lens", lens["ior"], a)
    tree = mat.node_tree
    if tree is not None:
        lens_surface.add_nodes(tree)  # new, or a lens built before the term was
        lens_surface.drive(tree, lamp, _drive, _drive_input, missing)
    if hasattr(mat, "cycles"):  # a term toward the eye, not a light
        mat.cycles.emission_sampling = "NONE"
    mat.diffuse_color = (*cycles.transmitted_color(a, lens["thickness"]), 0.5)  # solid view: seen through
    return missing


def prism_plate_glass(mat: bpy.types.Material, lamp: dict, *, new: bool) -> list[str]:
    """The prism plate: glass like the lens's (Principled BSDF transmitting, IOR = the plate's n) with
    its own Volume Absorption (eq. 2, docs/model.md: the prism plate)."""
    plate = lamp["prism_plate"]
    # photometric: the material's n_d refracts, the plate's own ior shaped its rings (convert.photometric_cycles)
    missing = _glass(mat, new, "Prism Plate", plate.get("glass_ior", plate["ior"]), plate["absorption"])
    mat.diffuse_color = (*cycles.transmitted_color(plate["absorption"], plate["thickness"]), 0.3)
    return missing


def light_guide_glass(mat: bpy.types.Material, lamp: dict, *, new: bool) -> list[str]:
    """The light guide (docs/model.md §8.7a): glass like the lens's, its material's n_d, its filter's
    absorption under its LEDs (``convert.photometric_cycles.equivalent``; clear before that)."""
    guide = lamp["light_guide"]
    absorption = guide.get("absorption", [0.0, 0.0, 0.0])
    missing = _glass(mat, new, "Light Guide", guide.get("glass_ior", spectral_index(guide)), absorption)
    arc = guide.get("path", "straight") == "arc"  # the viewport's colour: seen along the rod's whole length
    length = guide["arc_radius"] * math.radians(guide["arc_sweep"]) if arc else guide["length"]
    mat.diffuse_color = (*cycles.transmitted_color(absorption, length), 0.3)
    return missing


def spectral_index(part: dict) -> float:
    """n_d of a photometric part's material (``raytrace.spectral.index_of``)."""
    from ...core_tracer.raytrace.spectral import index_of

    return index_of(part)[0]


def _glass(mat: bpy.types.Material, new: bool, label: str, ior: float, absorption) -> list[str]:
    """A clear dielectric (Principled BSDF transmitting, "<label> BSDF") with a Volume Absorption of
    eq. (2)'s coefficients ("<label> Absorption"); the nodes are made only in a new material."""
    tree = _tree(mat, new)
    if new:
        out = _node(tree, "ShaderNodeOutputMaterial", "Output", (300, 0))
        bsdf = _node(tree, "ShaderNodeBsdfPrincipled", f"{label} BSDF", (0, 100), Base_Color=(1, 1, 1, 1),
                     Metallic=0.0, Roughness=0.0, Transmission_Weight=1.0)
        vol = _node(tree, "ShaderNodeVolumeAbsorption", f"{label} Absorption", (0, -300))
        tree.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
        tree.links.new(vol.outputs["Volume"], out.inputs["Volume"])
    density, color = cycles.absorption_volume(absorption)
    missing: list[str] = []
    _drive(tree, f"{label} BSDF", missing, IOR=ior)
    _drive(tree, f"{label} Absorption", missing, Color=(*color, 1.0), Density=density)
    return missing


# ---------------------------------------------------------------------------------------------
# Body, socket, side wall


def diffuse(mat: bpy.types.Material, color, node_name: str, *, new: bool) -> list[str]:
    tree = _tree(mat, new)
    if new:
        out = _node(tree, "ShaderNodeOutputMaterial", "Output", (300, 0))
        bsdf = _node(tree, "ShaderNodeBsdfDiffuse", node_name, (0, 0), Roughness=0.0)
        tree.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
    missing: list[str] = []
    _drive(tree, node_name, missing, Color=_rgba(color))
    mat.diffuse_color = _rgba(color)
    return missing


def body(mat: bpy.types.Material, body: dict, sun: dict | None, *, new: bool) -> list[str]:
    """The body's paint: ``diffuse`` and its highlight of eq. 1 (``lens_surface.add_body_nodes``) under
    ``sun`` (``cycles.lens_sun``; None: a photometric design, whose paint is Lambertian)."""
    missing = diffuse(mat, body["color"], "Body BSDF", new=new)
    tree = _tree(mat, False)
    if tree is not None:
        lens_surface.add_body_nodes(tree)  # new, or a body built before the highlight was
        lens_surface.drive_body(tree, sun, body, _drive, _drive_input, missing)
    return missing


# ---------------------------------------------------------------------------------------------
# Bulb


def bulb(mat: bpy.types.Material, lamp: dict, *, new: bool) -> list[str]:
    tree = _tree(mat, new)
    if new:
        out = _node(tree, "ShaderNodeOutputMaterial", "Output", (300, 0))
        em = _node(tree, "ShaderNodeEmission", "Bulb Emission", (0, 0))
        tree.links.new(em.outputs["Emission"], out.inputs["Surface"])
    return _bulb_emission(mat, tree, lamp)


def _bulb_emission(mat: bpy.types.Material, tree, lamp: dict) -> list[str]:
    """The "Bulb Emission" node driven by the bulb's intensity and switch (the bulb's, or the LEDs')."""
    b = lamp["bulb"]
    strength, color = cycles.emission_of(b["intensity"], b["on"])
    missing: list[str] = []
    _drive(tree, "Bulb Emission", missing, Color=(*color, 1.0), Strength=strength)
    mat.diffuse_color = (*color, 1.0) if b["on"] else (0.05, 0.05, 0.05, 1.0)
    return missing


def led_die(mat: bpy.types.Material, lamp: dict, *, new: bool) -> list[str]:
    """The LED dies: the bulb's emission (its intensity, or in the photometric mode the dies' radiance
    that ``convert.photometric_cycles`` puts there) on their front, black on their back (a die is
    opaque and emits into the half space it faces). Lambertian in Cycles: a far-field file is the
    tracer's only (docs/photometric.md)."""
    tree = _tree(mat, new)
    if new:
        out = _node(tree, "ShaderNodeOutputMaterial", "Output", (500, 0))
        em = _node(tree, "ShaderNodeEmission", "Bulb Emission", (0, 100))
        back = _node(tree, "ShaderNodeBsdfDiffuse", "Die Back", (0, -100))
        back.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
        facing = _node(tree, "ShaderNodeNewGeometry", "Geometry", (0, 300))
        mix = _node(tree, "ShaderNodeMixShader", "Die Sides", (250, 0))
        tree.links.new(facing.outputs["Backfacing"], mix.inputs["Fac"])
        tree.links.new(em.outputs["Emission"], mix.inputs[1])
        tree.links.new(back.outputs["BSDF"], mix.inputs[2])
        tree.links.new(mix.outputs["Shader"], out.inputs["Surface"])
    return _bulb_emission(mat, tree, lamp)


# ---------------------------------------------------------------------------------------------
# Reflector


EQ3_NODES = ("Eq. 3 Bulb Centre", "Eq. 3 Shininess", "Eq. 3 Weight", "Reflector Eq. 3")


def reflector(mat: bpy.types.Material, lamp: dict, *, new: bool, bulb_center=None) -> list[str]:
    """The reflector's material (module docstring). ``bulb_center``: the centre (mm) of the bulb eq. 3
    scatters toward, in the reflector object's own frame; by default the lamp's bulb (``lamp_geometry``),
    whose reflector is placed on the lamp's axis. ``lamp["bulb"]`` gives I0."""
    tree = _tree(mat, new)
    if new:
        _lay_out_reflector(tree)
        mat.diffuse_color = (0.8, 0.8, 0.82, 1.0)
        mat.metallic = 1.0
        mat.roughness = 0.1
    elif tree is not None:
        _gate_constant_to_first_hit(tree)  # a reflector built when C was seen on every hit
    if tree is not None and not all(tree.nodes.get(name) for name in (reflector_glow.GLOW, reflector_glow.PHANTOM)):
        reflector_glow.add_nodes(tree)  # new, or a reflector built when eq. 3 was a lobe
    if hasattr(mat, "cycles"):  # the emissions are glows toward the eye: never sampled as lights
        mat.cycles.emission_sampling = "NONE"
    r = lamp["reflector"]
    if bulb_center is None and "lens" in lamp:
        bulb_center = lamp_geometry(lamp)["bulb_center"]
    lobe = bool(r.get(cycles.SCATTER_AS_LOBE)) or bulb_center is None or "bulb" not in lamp
    missing: list[str] = []
    _drive(tree, "Reflector Mirror", missing, Color=_grey(r["reflectance"]))
    _drive(tree, "Reflector Scatter", missing, Color=_grey(r["scatter"] if lobe else 0.0),
           Roughness=cycles.blinn_roughness(r["shininess"]))
    _drive(tree, "Reflector Constant", missing, Color=_rgba(r["color"]))
    reflector_glow.drive(tree, lamp, bulb_center, lobe, _drive, _drive_input, missing)
    return missing


def _drive_input(tree, name: str, index: int, value, missing: list[str]) -> None:
    """``_drive`` for a Math node, whose two inputs share one name: input ``index`` of node ``name``."""
    node = tree.nodes.get(name) if tree is not None else None
    if node is None:
        missing.append(name)
    elif not _same(node.inputs[index].default_value, value):
        node.inputs[index].default_value = value


def _lay_out_reflector(tree) -> None:
    out = _node(tree, "ShaderNodeOutputMaterial", "Output", (900, 0))
    mirror = _node(tree, "ShaderNodeBsdfGlossy", "Reflector Mirror", (0, 300), Roughness=0.0)
    mirror.distribution = "GGX"
    scatter = _node(tree, "ShaderNodeBsdfGlossy", "Reflector Scatter", (0, 50))
    scatter.distribution = "BECKMANN"
    constant = _node(tree, "ShaderNodeEmission", "Reflector Constant", (0, -200), Strength=1.0)
    path = _node(tree, "ShaderNodeLightPath", "Light Path", (0, -400))
    gate = _node(tree, "ShaderNodeMixShader", "Constant Not For Diffuse Rays", (300, -250))
    tree.links.new(path.outputs["Is Diffuse Ray"], gate.inputs[0])
    tree.links.new(constant.outputs["Emission"], gate.inputs[1])  # second shader left empty: nothing
    _gate_constant_to_first_hit(tree)
    add1 = _node(tree, "ShaderNodeAddShader", "Mirror + Scatter", (300, 150))
    tree.links.new(mirror.outputs["BSDF"], add1.inputs[0])
    tree.links.new(scatter.outputs["BSDF"], add1.inputs[1])
    add2 = _node(tree, "ShaderNodeAddShader", "Reflector", (600, 0))
    tree.links.new(add1.outputs["Shader"], add2.inputs[0])
    tree.links.new(gate.outputs["Shader"], add2.inputs[1])
    tree.links.new(add2.outputs["Shader"], out.inputs["Surface"])


CONSTANT_GATE = "Constant Only On First Reflector Hit"


def _gate_constant_to_first_hit(tree) -> None:
    """Hide the constant C from rays after a glossy bounce as well as from diffuse rays: gate factor
    max(Is Diffuse Ray, Glossy Depth > 0), 1 picking the gate's empty shader. docs/model.md §5.2 adds C on the
    first reflector hit of a path from the eye; seen on every hit, an oblique view of a mirror of
    reflectance 0.8 showed 33 % more C than the model (tests/addon/test_addon_cycles_reflector.py).
    Inserted only where the gate is still fed by Light Path's Is Diffuse Ray as the builder laid it out
    (a designer's own link is left alone)."""
    gate, path = tree.nodes.get("Constant Not For Diffuse Rays"), tree.nodes.get("Light Path")
    if gate is None or path is None or tree.nodes.get(CONSTANT_GATE) is not None:
        return
    links = gate.inputs[0].links
    if not links or links[0].from_socket != path.outputs["Is Diffuse Ray"]:
        return
    bounced = tree.nodes.new("ShaderNodeMath")
    bounced.name = bounced.label = "After A Glossy Bounce"
    bounced.operation = "GREATER_THAN"
    bounced.inputs[1].default_value = 0.5
    bounced.location = (0, -600)
    either = tree.nodes.new("ShaderNodeMath")
    either.name = either.label = CONSTANT_GATE
    either.operation = "MAXIMUM"
    either.location = (150, -450)
    tree.links.new(path.outputs["Glossy Depth"], bounced.inputs[0])
    tree.links.new(path.outputs["Is Diffuse Ray"], either.inputs[0])
    tree.links.new(bounced.outputs["Value"], either.inputs[1])
    tree.links.new(either.outputs["Value"], gate.inputs[0])


# ---------------------------------------------------------------------------------------------
# Light: world and sun


def world(wld: bpy.types.World, scene: dict, *, new: bool, image_path: str | None = None) -> list[str]:
    """Background ``d`` for diffuse rays (ambient of eq. 1), the scene's background colour for all others;
    with surroundings (``image_path``, ``environment``) their image is the world for every ray, as the
    tracer sees it: Environment Texture (Linear) after a Mapping node turning about Z, into a Background of
    the environment's strength, seen by all rays and added to the ambient for diffuse rays."""
    tree = _tree(wld, new)
    if new:
        out = _node(tree, "ShaderNodeOutputWorld", "Output", (600, 0))
        seen = _node(tree, "ShaderNodeBackground", "Background", (0, 150), Strength=1.0)
        ambient = _node(tree, "ShaderNodeBackground", "Ambient", (0, -50), Strength=1.0)
        path = _node(tree, "ShaderNodeLightPath", "Light Path", (0, 400))
        mix = _node(tree, "ShaderNodeMixShader", "Ambient For Diffuse Rays", (300, 0))
        tree.links.new(path.outputs["Is Diffuse Ray"], mix.inputs[0])
        tree.links.new(seen.outputs["Background"], mix.inputs[1])
        tree.links.new(ambient.outputs["Background"], mix.inputs[2])
        tree.links.new(mix.outputs["Shader"], out.inputs["Surface"])
    if tree is not None and image_path is not None and tree.nodes.get("Surroundings") is None:
        _add_surroundings(tree)  # a world built before surroundings existed, or a new one
    missing: list[str] = []
    _drive(tree, "Background", missing, Color=_rgba(scene["background"]))
    # The surroundings take the place of eq. (1)'s ambient where they are shown (docs/model.md §8.18).
    _drive(tree, "Ambient", missing, Color=_grey(0.0 if image_path is not None else scene["light"]["ambient"]))
    if tree is not None and tree.nodes.get("Surroundings") is not None:
        env = scene["environment"]
        on = 1.0 if image_path is not None else 0.0
        _drive(tree, "Surroundings", missing, Strength=float(env["strength"]))
        _drive(tree, "Background Or Surroundings", missing, Fac=on)
        _drive(tree, "Ambient Or Ambient And Surroundings", missing, Fac=on)
        mapping = tree.nodes.get("Environment Mapping")
        if mapping is not None:
            _drive(tree, "Environment Mapping", missing, Rotation=(0.0, 0.0, math.radians(env["rotation_deg"])))
        texture = tree.nodes.get("Environment")
        if texture is None:
            missing.append("Environment")
        elif image_path is not None and (texture.image is None
                                         or bpy.path.abspath(texture.image.filepath) != image_path):
            texture.image = bpy.data.images.load(image_path, check_existing=True)
    wld.color = tuple(float(c) for c in scene["background"])
    return missing


def _add_surroundings(tree) -> None:
    """The environment's nodes, put between the background and ambient and the diffuse-ray mix."""
    coords = _node(tree, "ShaderNodeTexCoord", "Texture Coordinate", (-900, 700))
    mapping = _node(tree, "ShaderNodeMapping", "Environment Mapping", (-700, 700))
    mapping.vector_type = "POINT"
    texture = _node(tree, "ShaderNodeTexEnvironment", "Environment", (-500, 700))
    texture.interpolation = "Linear"
    texture.projection = "EQUIRECTANGULAR"
    surroundings = _node(tree, "ShaderNodeBackground", "Surroundings", (-200, 700), Strength=1.0)
    tree.links.new(coords.outputs["Generated"], mapping.inputs["Vector"])
    tree.links.new(mapping.outputs["Vector"], texture.inputs["Vector"])
    tree.links.new(texture.outputs["Color"], surroundings.inputs["Color"])
    pick = _node(tree, "ShaderNodeMixShader", "Background Or Surroundings", (150, 500), Fac=0.0)
    both = _node(tree, "ShaderNodeAddShader", "Ambient And Surroundings", (150, 300))
    pick_diffuse = _node(tree, "ShaderNodeMixShader", "Ambient Or Ambient And Surroundings", (150, -250), Fac=0.0)
    seen, ambient = tree.nodes.get("Background"), tree.nodes.get("Ambient")
    mix = tree.nodes.get("Ambient For Diffuse Rays")
    if seen is not None:
        tree.links.new(seen.outputs["Background"], pick.inputs[1])
    tree.links.new(surroundings.outputs["Background"], pick.inputs[2])
    if ambient is not None:
        tree.links.new(ambient.outputs["Background"], both.inputs[0])
        tree.links.new(ambient.outputs["Background"], pick_diffuse.inputs[1])
    tree.links.new(surroundings.outputs["Background"], both.inputs[1])
    tree.links.new(both.outputs["Shader"], pick_diffuse.inputs[2])
    if mix is not None:
        tree.links.new(pick.outputs["Shader"], mix.inputs[1])
        tree.links.new(pick_diffuse.outputs["Shader"], mix.inputs[2])


def sun(light: bpy.types.SunLight, scene: dict, *, new: bool) -> list[str]:
    """The sun of eq. (1): strength pi (1 - d) s (``cycles.sun_strength``) and colour S, the tracer's
    (``sunlight.sun_color``: the environment sun's when the light follows its colour)."""
    if new:
        light.angle = 0.0  # a directional light, as in the paper
    try:
        color = tuple(float(c) for c in sunlight.sun_color(scene))
    except SceneError:  # an environment image that cannot be read: the builder reports it with the direction
        color = tuple(float(c) for c in scene["light"].get("sun_color", (1.0, 1.0, 1.0)))
    if not _same(light.color, color):
        light.color = color
    energy = cycles.sun_strength(scene["light"]["ambient"]) * scene["light"].get("strength", 1.0)
    if not _same(light.energy, energy):
        light.energy = energy
    return []

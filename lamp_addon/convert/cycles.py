"""Cycles material numbers equivalent to the paper's parameters (BLENDER-NOTES "Cycles equivalents").

Pure arithmetic on the design's values; ``design.materials`` writes the results into node sockets.
Absorption A is per mm; Cycles works per Blender unit (1 mm = 0.001 Blender units, ``units``).
"""

from __future__ import annotations

import math

from . import units

# A reflector key (set by ``photometric_cycles.equivalent``): its glow is built as a Glossy lobe lit by the
# bulb (physical), not as the paper's eq. 3 emission (``design.materials.reflector``).
SCATTER_AS_LOBE = "cycles_scatter_as_lobe"
# Lamp keys (set by ``design.builder``): what the reflector's phantom emission needs (``phantoms``), and
# the sun of the lens's own eq. 1 term (``lens_sun``).
PHANTOM = "cycles_phantom"
LENS_SUN = "cycles_lens_sun"


def absorption_volume(absorption: list[float]) -> tuple[float, tuple[float, float, float]]:
    """(Density, Color) of a Volume Absorption node absorbing ``absorption`` per mm (eq. 2).

    Cycles absorbs ``Density * (1 - Color)`` per Blender unit, so ``Density = 1000 * max(A)`` and
    ``Color = 1 - 1000 * A / Density``; a clear lens (A = 0) gets Density 0. Color is unclamped."""
    density = units.MM_PER_BU * max(absorption)
    if density <= 0.0:
        return 0.0, (1.0, 1.0, 1.0)
    return density, tuple(1.0 - units.MM_PER_BU * a / density for a in absorption)


def emission_of(intensity: list[float], on: bool = True) -> tuple[float, tuple[float, float, float]]:
    """(Strength, Color) of an Emission node that shows ``intensity`` I0 to the camera: a camera sees
    ``Strength * Color``, so Strength = max(I0) and Color = I0 / max(I0); a bulb that is off has
    Strength 0 (its colour is kept, so switching it on again shows the same light)."""
    peak = max(intensity)
    if peak <= 0.0:
        return 0.0, (1.0, 1.0, 1.0)
    return (peak if on else 0.0), tuple(c / peak for c in intensity)


def blinn_roughness(shininess: float) -> float:
    """Glossy Roughness input (Beckmann) matching a Blinn exponent n (eq. 3): Walter et al. (2007) give
    the Beckmann slope alpha = sqrt(2 / (n + 2)), and Cycles squares Roughness into alpha."""
    return (2.0 / (shininess + 2.0)) ** 0.25


def sun_strength(ambient: float) -> float:
    """Sun strength giving a Diffuse BSDF of albedo R0 the value R0 (1 - d) cos theta (eq. 1)."""
    return math.pi * (1.0 - ambient)


def transmitted_color(absorption: list[float], thickness: float) -> tuple[float, float, float]:
    """The colour seen through ``thickness`` mm of glass absorbing ``absorption`` per mm (eq. 2)."""
    return tuple(math.exp(-a * thickness) for a in absorption)


def phantoms(scene: dict) -> list[dict | None]:
    """Per lamp of a normalised paper scene, what Cycles' phantom emission needs (``design.reflector_glow``):
    ``direction`` toward the sun (the lamp's frame = the scene's axes), ``light`` s S T_sun (RGB, the lens as
    a flat plate, ``raytrace.sunlight``), the apex plane ``plane_b`` (mm) and the lens outline's ``core``
    half sizes and ``corner`` radius (mm); None for every lamp where the design has no phantom light, or
    where the sun lets none into that lamp. Reads the environment image when the sun follows it."""
    from ...core_tracer.raytrace import sunlight
    from ...core_tracer.raytrace.lamp_table import LampTable

    if not scene["light"].get("phantom", False) or scene.get("light_model") == "photometric":
        return [None] * len(scene["lamps"])
    sun = sunlight.from_scene(scene, sunlight.sun_direction(scene))
    lamps = LampTable.from_scene(scene)
    per_lamp = sunlight.PhantomLamps.of(sun, lamps)
    light = sun.light
    return [{"direction": [float(c) for c in sun.direction],
             "light": [float(c) for c in light * per_lamp.transmit[i]],
             "plane_b": float(lamps.plane_b[i]),
             "core": (float(per_lamp.core_x[i]), float(per_lamp.core_z[i])),
             "corner": float(lamps.corner[i])} if per_lamp.lets_in[i] else None
            for i in range(len(scene["lamps"]))]


def lens_sun(scene: dict) -> dict | None:
    """The sun as the lens's eq. 1 term sees it (``design.lens_surface``), as the tracer's ``Lighting``
    makes it: ``direction`` toward it (the scene's axes), ``light`` (1 - d) s S, ``ambient`` d where it is
    added (not under surroundings), ``highlight`` s C1; None for a photometric design (its lens colour is
    black). Reads the environment image when the sun follows it."""
    from ...core_tracer.raytrace.lighting import Lighting

    if scene.get("light_model") == "photometric":
        return None
    sun = Lighting(scene).sun
    return {"direction": [float(c) for c in sun.direction],
            "light": [float((1.0 - sun.ambient) * sun.strength * c) for c in sun.color],
            "ambient": float(sun.ambient) if sun.ambient_seen else 0.0,
            "highlight": [float(sun.strength * c) for c in sun.highlight]}

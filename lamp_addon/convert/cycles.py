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

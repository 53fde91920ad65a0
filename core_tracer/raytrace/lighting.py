"""What lights a lamp and what a ray leaving it sees, shared by the parametric tracer and the
free-form one so that both apply one model (docs/model.md: surroundings, the sun, phantom light).

Without surroundings and with the paper's light this is exactly eq. (1) and the background colour
(``sunlight``: strength 1 and white go through ``optics.phong`` itself).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from . import environment, optics, spectral, spectral_bands, sunlight


class Lighting:
    """The surroundings (``environment``; None for the paper's background colour), the sun, the
    background, and whether eye rays that miss show the world (False: a transparent film).

    ``channels`` are the colour columns the rays carry: R, G, B in the paper mode, the wavelength
    bands in the photometric one (``photometric``, ``spectral.Photometric``; None in the paper
    mode), whose environment is scaled to cd/m² and whose background is black. The passes hold
    ``pass_channels``: R, G, B, or X, Y, Z, each leaf's bands turned to XYZ as it is added."""

    def __init__(self, scene: dict, bands: int | None = None):
        self.environment = environment.from_scene(scene)
        following = self.environment is not None and scene["light"].get("follow_environment", False)
        self.sun = sunlight.from_scene(scene, self.environment.sun_direction() if following else None)
        if self.environment is not None:  # its light takes the place of eq. (1)'s ambient
            self.sun = self.sun.under_surroundings()
        self.background = np.asarray(scene["background"], dtype=np.float64)
        self.channels = 3  # R, G, B
        self.pass_channels = 3  # what the passes hold: R, G, B; photometric: X, Y, Z (``Band.add``)
        self.photometric = None
        if scene.get("light_model", "paper") == "photometric":
            self.photometric = spectral.setup(scene, spectral_bands.render_bands(scene, bands), self.sun.direction)
            self.channels = self.photometric.channels
            self.sun = self.photometric.sun
            self.background = np.zeros(self.channels)
            if self.environment is not None:  # its pixels times this are cd/m²
                scale = spectral.environment_scale(scene, self.environment.pixels)
                self.environment = replace(self.environment, strength=scale)
        # adding a black background adds exactly 0
        self.background_seen = bool(self.background.any()) or self.environment is not None
        self.world_seen = True

    @property
    def to_xyz(self) -> np.ndarray | None:
        """(K, 3) from the carried bands to CIE XYZ in cd/m²; None in the paper mode (RGB as carried)."""
        return None if self.photometric is None else self.photometric.to_xyz

    def sky(self, d: np.ndarray) -> np.ndarray:
        """What a ray leaving the scene along unit ``d`` (N, 3) sees: the environment or the background."""
        if self.environment is not None:
            if self.photometric is not None:
                return self.photometric.light(self.environment.radiance(d))
            return self.environment.radiance(d)
        return np.broadcast_to(self.background, (len(d), self.channels))

    def sky_seen(self, d: np.ndarray) -> np.ndarray:
        """``sky(d)`` as a pass holds it (``Band.in_pass``), for eye rays that see the world: the
        photometric environment straight to X, Y, Z, its bands never needed."""
        if self.environment is not None and self.photometric is not None:
            return self.photometric.light_xyz(self.environment.radiance(d))
        if self.photometric is not None:
            return self.sky(d) @ self.photometric.to_xyz
        return self.sky(d)

    def lens_surface(self, normal: np.ndarray, d: np.ndarray, diffuse: np.ndarray, specular, shininess) -> np.ndarray:
        """What the reflected share of eye rays ``d`` at a lens's outer face of ``normal`` sees (its
        Fresnel weight applied by the caller): eq. (1) with the lens's colour (docs/model.md §4), and
        with surroundings the sky in the mirror direction (§8.10). The sky reaches that share by the
        mirror alone: the lens colour is not lit by the environment too, nor by the ambient it
        replaces (§8.18); the sun, which the sky does not hold (masked where the sun follows it),
        lights it by eq. (1)."""
        if self.environment is None:
            return self.shade(normal, -d, diffuse, specular, shininess)
        surface = self.sun.shade(normal, -d, diffuse, specular, shininess)
        surface += self.sky(optics.reflect(d, normal))
        return surface

    def shade(self, normal: np.ndarray, view: np.ndarray, diffuse: np.ndarray, specular, shininess) -> np.ndarray:
        """Equation (1) under the sun, plus the environment's light on a Lambertian surface in
        place of the ambient (docs/model.md §8.18)."""
        out = self.sun.shade(normal, view, diffuse, specular, shininess)
        if self.environment is not None:
            lambert = self.environment.irradiance(normal)  # + diffuse E / pi, in place
            if self.photometric is not None:
                lambert = self.photometric.light(lambert)
            np.multiply(lambert, diffuse, out=lambert)
            lambert /= np.pi
            out += lambert
        return out

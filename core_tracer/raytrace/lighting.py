"""What lights a lamp and what a ray leaving it sees, shared by the parametric tracer and the
free-form one so that both apply one model (docs/model.md: surroundings, the sun, phantom light).

Without surroundings and with the paper's light this is exactly eq. (1) and the background colour
(``sunlight``: strength 1 and white go through ``optics.phong`` itself).
"""

from __future__ import annotations

import numpy as np

from . import environment, sunlight


class Lighting:
    """The surroundings (``environment``; None for the paper's background colour), the sun, the
    background, and whether eye rays that miss show the world (False: a transparent film)."""

    def __init__(self, scene: dict):
        self.environment = environment.from_scene(scene)
        following = self.environment is not None and scene["light"].get("follow_environment", False)
        self.sun = sunlight.from_scene(scene, self.environment.sun_direction() if following else None)
        self.background = np.asarray(scene["background"], dtype=np.float64)
        # adding a black background adds exactly 0
        self.background_seen = bool(self.background.any()) or self.environment is not None
        self.world_seen = True
        self.channels = 3  # R, G, B
        self.photometric = None

    def sky(self, d: np.ndarray) -> np.ndarray:
        """What a ray leaving the scene along unit ``d`` (N, 3) sees: the environment or the background."""
        if self.environment is not None:
            return self.environment.radiance(d)
        return np.broadcast_to(self.background, (len(d), 3))

    def shade(self, normal: np.ndarray, view: np.ndarray, diffuse: np.ndarray, specular, shininess) -> np.ndarray:
        """Equation (1) under the sun, plus the environment's light on a Lambertian surface."""
        out = self.sun.shade(normal, view, diffuse, specular, shininess)
        if self.environment is not None:
            lambert = self.environment.irradiance(normal)  # + diffuse E / pi, in place
            np.multiply(lambert, diffuse, out=lambert)
            lambert /= np.pi
            out += lambert
        return out

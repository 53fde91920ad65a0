"""LED dies beside a free-form design's meshes (docs/photometric.md, "LED sources"; docs/model.md,
"Free-form designs").

Convert to Free-form makes meshes of a lamp's lens, reflector, bulb and socket; its LED dies stay the
design's source: the dies of every lamp of the design whose ``source`` is ``"led"`` (``lamps[i].led``)
are found and lit exactly as the parametric tracer's (``raytrace.parts.led_die``): a ray meets the
array's plane once, and the one die whose cell holds that point is tested; a die is opaque and shows
the luminance L₀(λ) f(θ, φ) toward the front only (Φ / (π A) per die for a Lambertian one, a far-field
file's pattern otherwise). What differs from the parametric lamp is only how the other surfaces are
found: the meshes, through Embree (``hits``). A ray in air ends on a die when the die is nearer than
the nearest triangle.

The arrays are in each lamp's frame (``scene.led_array``), which is the world's moved by the lamp's
centre (x, 0, z) (as the parametric tracer's ``engine.eyes`` moves eye rays into a lamp). A design
with no LED lamp has no ``Dies`` (None): it renders as before.
"""

from __future__ import annotations

import math

import numpy as np

from ..raytrace import spectral
from ..raytrace.lamp_table import LampTable
from ..raytrace.optics import cosine_directions
from ..raytrace.parts import led_die
from ..scene.led_array import uses_leds


class Dies:
    """The LED arrays of a design's lamps: their values per lamp (``LampTable``; photometric: the
    spectral radiance per band and the far-field patterns, ``spectral.photometric_lamps``)."""

    def __init__(self, scene: dict, photometric: spectral.Photometric | None):
        lamps = LampTable.from_scene(scene)
        if photometric is not None:
            lamps = spectral.photometric_lamps(lamps, scene, photometric.bands)
        self.lamps = lamps
        self.lit = [int(i) for i in np.nonzero(lamps.led_columns > 0)[0]]
        self.offset = np.stack([lamps.center[:, 0], np.zeros(len(lamps.center)), lamps.center[:, 1]], axis=1)

    @classmethod
    def of(cls, scene: dict, photometric: spectral.Photometric | None) -> Dies | None:
        """The design's dies, None when no lamp is lit by LEDs."""
        if not any(uses_leds(lamp) for lamp in scene.get("lamps", ())):
            return None
        return cls(scene, photometric)

    def hit(self, o: np.ndarray, d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(distance, lamp) of each world ray's (``o``, unit ``d``, mm) nearest die, (inf, -1) for none."""
        t = np.full(len(o), np.inf)
        lamp = np.full(len(o), -1, np.int64)
        for i in self.lit:
            index = np.full(len(o), i, np.int64)
            ti = led_die.hit_dies(o - self.offset[i], d, self.lamps, index)
            nearer = ti < t
            t[nearer], lamp[nearer] = ti[nearer], i
        return t, lamp

    def emitted(self, lamp: np.ndarray, d: np.ndarray, at: np.ndarray) -> np.ndarray:
        """(N, channels) the luminance of the dies of ``lamp`` at world points ``at`` seen along the eye
        ray's ``d`` (``led_die.emitted``: 0 from behind)."""
        return led_die.emitted(self.lamps, lamp, d, at - self.offset[lamp])

    def photons(self, lamp: int, n: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``n`` photons of lamp ``lamp``'s dies (world points, directions, flux per band W/nm), as
        ``measures.light_tracing.led_photons`` samples them: a uniform point of a uniformly chosen die,
        a cosine-distributed direction about its normal, carrying π L₀(λ) f(θ, φ) A / N."""
        lamps = self.lamps
        columns, rows = int(lamps.led_columns[lamp]), int(lamps.led_rows[lamp])
        half, pitch = lamps.led_half[lamp], lamps.led_pitch[lamp]
        a = (rng.integers(0, columns, n) - (columns - 1) / 2.0) * pitch[0] + rng.uniform(-half[0], half[0], n)
        b = (rng.integers(0, rows, n) - (rows - 1) / 2.0) * pitch[1] + rng.uniform(-half[1], half[1], n)
        o = lamps.led_center[lamp] + a[:, None] * lamps.led_across[lamp] + b[:, None] * lamps.led_up[lamp]
        d = cosine_directions(np.broadcast_to(lamps.led_normal[lamp], (n, 3)), rng)
        area = columns * rows * 4.0 * half[0] * half[1] * 1e-6  # m²
        radiance = led_die.emitted(lamps, np.full(n, lamp, np.int64), -d)  # seen looking back along the light
        return o + self.offset[lamp], d, radiance * (math.pi * area / n)

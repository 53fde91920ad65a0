"""The sun: the light of equation (1) with a strength and a colour, and its phantom light.

Equation (1) with the sun's strength s and colour S (the paper's light is s = 1, S = white):

    [d + (1 - d) s S cos theta] C0 + s w (cos beta)^n C1

computed by ``optics.phong`` itself when s = 1 and S = white, so that a scene an earlier version
wrote renders bit for bit as before. S is ``sun_color``, or, where the light follows the
environment's colour, the colour of the environment's sun at luminance 1 (``followed_color``).
Where an environment surrounds the lamp, the surfaces of eq. (1) are lit by it as Lambertian
surfaces, C0 E(n) / pi (``environment``), in place of the ambient d C0 (``Sun.under_surroundings``).

**Phantom light** (where the paper is silent): sunlight that enters through the lens and is
scattered back by the reflector. At every reflector hit of an eye path the reflector's scatter of
eq. (3) is added with the sun as the light: k w (cos beta_sun)^n I_sun T_sun, with I_sun = s S,
beta_sun between the normal and the half vector of the sun and view directions, and T_sun the
sun's transmittance into the lamp: the lens taken as a flat plate of its mean thickness
(t + h / 2), so the sun's direction inside is the same as outside, with Fresnel transmission at
both faces and absorption (eq. 2) along the refracted path, (1 - r)^2 exp(-A t_mean / cos theta_t).
A reflector point is lit only when the sun is in front of the lamp and the line from the point
toward the sun passes through the lens opening (its outline at the apex plane); the socket's and the
bulb's shadows are not modelled. The mirror paths of the reflector that leave the lamp through
the lens reach the sun where the environment image holds it (``environment``, path 10).
The free-form tracer uses the same plate (``plate_transmittance``) and scatter (``scattered``) with
its own test of the line to the sun on the meshes (``freeform.render``).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..scene import outline
from . import environment, optics
from .lamp_table import LampTable

FRONT = np.array([0.0, -1.0, 0.0])  # the outward normal of the lens's outer face (docs/model.md §2)


@dataclass(frozen=True)
class Sun:
    direction: np.ndarray  # unit, from the lamp toward the sun
    highlight: np.ndarray  # C1 of eq. (1)
    ambient: float
    strength: float
    color: np.ndarray  # S
    paper: bool  # s = 1 and S = white: eq. (1) exactly as the paper's light
    # Whether the ambient d C0 of eq. (1) is added: not where an environment lights the surfaces, whose
    # light takes its place (``under_surroundings``, docs/model.md §8.18).
    ambient_seen: bool = True
    cosine_weighted = False  # the phantom light as eq. (3): no cosine toward the sun (the photometric sun's has)

    def shade(self, normal: np.ndarray, view: np.ndarray, diffuse: np.ndarray, specular, shininess) -> np.ndarray:
        """Equation (1) under the sun (module docstring); ``view`` and the sun's direction point away
        from the surface. Returns (N, 3)."""
        if self.paper:
            return optics.phong(normal, view, self.direction, diffuse, self.highlight, self.ambient, specular,
                                shininess)
        L = self.direction
        # cos_theta = max(0, n0 L0 + n1 L1 + n2 L2), cos_beta = max(0, n . normalize(view + L)), in place
        cos_theta = normal[:, 0] * L[0]
        term = normal[:, 1] * L[1]
        cos_theta += term
        np.multiply(normal[:, 2], L[2], out=term)
        cos_theta += term
        np.maximum(0.0, cos_theta, out=cos_theta)
        cos_beta = optics.dot(normal, optics.normalize(view + L))
        np.maximum(0.0, cos_beta, out=cos_beta)
        spec = np.where(cos_theta > 0.0, self.strength * np.asarray(specular) * np.power(cos_beta, shininess), 0.0)
        # [a + (1 - a) s cos_theta S_c] C0_c + spec C1_c, a channel at a time: numpy broadcasts
        # (N, 1) over rows of 3 slowly.
        lit = (1.0 - self.ambient) * self.strength * cos_theta
        diffuse = np.broadcast_to(diffuse, (len(normal), 3))
        out = np.empty((len(normal), 3))
        for c in range(3):
            np.multiply(lit, self.color[c], out=term)
            if self.ambient_seen:
                term += self.ambient
            term *= diffuse[:, c]
            np.multiply(spec, self.highlight[c], out=out[:, c])
            out[:, c] += term
        return out

    @property
    def light(self) -> np.ndarray:
        """I_sun of the phantom light: s S."""
        return self.strength * self.color

    def under_surroundings(self) -> Sun:
        """This sun where an environment surrounds the lamp: eq. (1) without its ambient d C0, which
        stands for the light of the surroundings that the environment now gives (C0 E(n) / pi); the
        sun's own term keeps its (1 - d) s S cos theta, so adding surroundings changes no sunlit
        face by the sun's share (docs/model.md §8.18). A sun of ambient 0 is returned as it is."""
        if self.ambient == 0.0:
            return self
        return replace(self, paper=False, ambient_seen=False)


def from_scene(scene: dict, environment_sun: np.ndarray | None) -> Sun:
    """The sun of a normalised scene; ``environment_sun`` is the direction of the environment's sun
    when the light follows the environment. Its colour is ``sun_color``, or the environment sun's
    (``followed_color``) when the light follows the environment's colour."""
    light = scene["light"]
    if environment_sun is not None and light.get("follow_environment", False):
        direction = np.asarray(environment_sun, dtype=np.float64)
    else:
        direction = np.asarray(light["direction"], dtype=np.float64)
    direction = direction / np.linalg.norm(direction)
    strength = float(light.get("strength", 1.0))
    color = sun_color(scene)
    return Sun(direction, np.asarray(light["color"], dtype=np.float64), light["ambient"], strength, color,
               strength == 1.0 and bool((color == 1.0).all()))


def sun_transmittance(sun: Sun, lamps: LampTable, lamp: np.ndarray) -> np.ndarray:
    """T_sun (N, 3) of the lenses ``lamp`` (module docstring); 0 with the sun behind the lamp."""
    return plate_transmittance(sun, lamps.ior[lamp], lamps.absorption[lamp],
                               0.5 * (lamps.plane_a[lamp] + lamps.plane_b[lamp]))


def plate_transmittance(sun: Sun, ior: np.ndarray, absorption: np.ndarray, thickness: np.ndarray) -> np.ndarray:
    """T_sun (N, 3) of flat plates of index ``ior`` (N,), absorption (N, 3) and mean ``thickness``
    (N,) facing the viewer (module docstring); 0 with the sun behind the lamp."""
    cos_i = float(sun.direction @ FRONT)  # the angle of incidence on the outer face; > 0 in front
    if cos_i <= 0.0 or sun.strength == 0.0:
        return np.zeros((len(ior), absorption.shape[1]))
    r = optics.fresnel_reflectance(np.full(len(ior), cos_i), 1.0, ior)
    sin_t = np.sqrt(1.0 - cos_i * cos_i) / ior
    cos_t = np.sqrt(1.0 - sin_t * sin_t)
    return ((1.0 - r) ** 2)[:, None] * optics.absorption(absorption, thickness / cos_t)


@dataclass(frozen=True)
class PhantomLamps:
    """What the phantom light needs of each lamp of ``lamps`` (indexed by lamp number), gathered
    per point: T_sun, whether it lets any light in, and the core half sizes of the outline. A
    render makes it once (``of``)."""

    lamps: LampTable
    transmit: np.ndarray  # (L, 3)
    lets_in: np.ndarray  # (L,) bool
    core_x: np.ndarray
    core_z: np.ndarray

    @classmethod
    def of(cls, sun: Sun, lamps: LampTable) -> PhantomLamps:
        transmit = sun_transmittance(sun, lamps, np.arange(len(lamps.ior)))
        half, corner = lamps.half_size, lamps.corner
        return cls(lamps, transmit, transmit.any(axis=1), half[:, 0] - corner, half[:, 1] - corner)


def phantom(sun: Sun, per_lamp: PhantomLamps, lamp: np.ndarray, hit: np.ndarray, normal: np.ndarray,
            view: np.ndarray) -> np.ndarray:
    """The phantom light (N, 3) per unit accumulated attenuation at reflector points ``hit`` (local
    lamp coordinates) of lamps ``lamp`` of ``per_lamp.lamps``, of normal ``normal`` seen from
    ``view`` (module docstring)."""
    if not per_lamp.lets_in.take(lamp).any():
        return np.zeros((len(lamp), per_lamp.transmit.shape[1]))
    lamps = per_lamp.lamps
    # The line toward the sun crosses the apex plane inside the lens opening.
    toward = sun.direction
    to_plane = lamps.plane_b.take(lamp)
    to_plane -= hit[:, 1]
    to_plane /= toward[1]
    cross_x = to_plane * toward[0]
    cross_x += hit[:, 0]
    cross_z = to_plane * toward[2]
    cross_z += hit[:, 2]
    inside = outline.signed_distance(cross_x, cross_z, per_lamp.core_x.take(lamp), per_lamp.core_z.take(lamp),
                                     lamps.corner.take(lamp)) <= 0.0
    return _scattered(sun, normal, view, np.flatnonzero(inside), lamp, lamps.scatter, lamps.scatter_shininess,
                      per_lamp.transmit)


def scattered(sun: Sun, normal: np.ndarray, view: np.ndarray, scatter: np.ndarray, shininess: np.ndarray,
              transmit: np.ndarray, lit: np.ndarray) -> np.ndarray:
    """The reflector's scatter of eq. (3) with the sun as the light (module docstring), (N, 3): at
    points of ``normal`` seen from ``view`` whose line to the sun passes through the lens (``lit``),
    the lens letting ``transmit`` (N, 3) through."""
    return _scattered(sun, normal, view, np.flatnonzero(lit), None, scatter, shininess, transmit)


def _scattered(sun: Sun, normal: np.ndarray, view: np.ndarray, at: np.ndarray, of: np.ndarray | None,
               scatter: np.ndarray, shininess: np.ndarray, transmit: np.ndarray) -> np.ndarray:
    """``scattered`` at the points ``at`` only (the others stay 0), ``scatter``, ``shininess`` and
    ``transmit`` being rows ``of`` the points (per lamp), or of the points themselves (None)."""
    light = sun.light
    out = np.zeros((len(normal), len(light)))
    normal, view = normal.take(at, axis=0), view.take(at, axis=0)
    sun_dir = np.broadcast_to(sun.direction, normal.shape)
    # Lit on the side the eye ray came from only (the normal turned toward the viewer): turning
    # the normal turns the sign of its cosine to the sun, so the points are chosen first and only
    # their normals turned.
    turned = optics.dot(normal, view) < 0.0
    to_sun = optics.dot(normal, sun_dir)
    cos_sun = np.where(turned, -to_sun, to_sun)
    facing = np.flatnonzero(cos_sun > 0.0)
    if len(facing) < len(at):  # else every point faces the sun (the usual case): nothing to drop
        at, normal, view, turned = at.take(facing), normal.take(facing, axis=0), view.take(facing, axis=0), \
            turned.take(facing)
        cos_sun = cos_sun.take(facing)
    for j in range(3):
        np.negative(normal[:, j], out=normal[:, j], where=turned)
    rows = at if of is None else of.take(at)
    value = optics.blinn(normal, view, sun_dir[:len(at)], scatter.take(rows), shininess.take(rows))
    if sun.cosine_weighted:  # the irradiance on the reflector: E cos theta
        value *= cos_sun
    # value T_sun I_sun, a column at a time (numpy broadcasts (N, 1) over rows of 3 slowly)
    transmit, column = transmit.take(rows, axis=0), np.empty(len(at))
    for j in range(len(light)):
        np.multiply(value, transmit[:, j], out=column)
        column *= light[j]
        out[at, j] = column
    return out


def sun_direction(scene: dict) -> np.ndarray:
    """The unit direction toward the sun of a normalised scene: ``light.direction``, or the
    environment's sun when the light follows it (reads the environment image)."""
    env = environment.from_scene(scene) if scene["light"].get("follow_environment", False) else None
    return from_scene(scene, env.sun_direction() if env is not None else None).direction


def sun_color(scene: dict) -> np.ndarray:
    """The colour S of the sun of a normalised scene: ``light.sun_color``, or the colour of the
    environment's sun (``followed_color``) when ``light.follow_environment_color`` is on and the
    scene has surroundings (reads the environment image)."""
    light = scene["light"]
    if light.get("follow_environment_color", False):
        env = environment.from_scene(scene)  # the image is read only when the light follows it
        if env is not None:
            return followed_color(env)
    return np.asarray(light.get("sun_color", (1.0, 1.0, 1.0)), dtype=np.float64)


def followed_color(env: environment.Environment) -> np.ndarray:
    """The colour of the environment's sun at luminance 1 (Rec. 709), independent of the
    environment's strength and turn (where the paper is silent, docs/model.md "The sun").

    The sun is the pixels ``environment.sun_direction`` takes (at least ``SUN_FRACTION`` of the
    brightest luminance); its colour is that of their light, sum(L_c omega) over those pixels of
    radiance L and solid angle omega, divided by its luminance (``Environment.sun_color``, computed
    once per image)."""
    return env.sun_color()

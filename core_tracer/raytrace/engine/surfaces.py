"""What happens where a ray meets a surface: the lens's outer face seen from the eye (①), the
reflector (③ ④, eq. 3), and the faces of a dielectric (a lens or a prism plate) met from either
side, where one Fresnel split (MODEL.md §5) gives the reflected and the transmitted branch.

The free-form tracer (``freeform.render``) splits its meshes' lens faces with the same
``fresnel_split``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import optics, sunlight
from .. import paths as P
from ..lamp_table import LampTable
from ..parts import reflector
from ..parts.base import rows
from .context import Context
from .rays import (
    BACKGROUND_PASS,
    LENS_SURFACE,
    REFLECTOR_CONSTANT,
    REFLECTOR_SCATTER,
    UNRECORDED,
    Band,
    Rays,
    alive,
    branch_tags,
)


def into_lenses(ctx: Context, band: Band, s: np.ndarray, li: np.ndarray, ds: np.ndarray,
                 face_normal: np.ndarray, cos_i: np.ndarray, local: np.ndarray) -> Rays:
    """Eye rays ``s`` meeting the outer face of lamps ``li`` (①) at ``local`` (lamp frame) with the
    face's outward ``face_normal``: the Fresnel split, the reflected branch shaded by eq. (1) and
    mirroring the surroundings (§3.2.3), the transmitted rays into the lens."""
    L = ctx.lamps
    ior = L.ior[li]
    r = optics.fresnel_reflectance(cos_i, 1.0, ior)
    surface = ctx.shade(face_normal, -ds, L.lens_diffuse[li], L.lens_specular[li], L.lens_shininess[li])
    if ctx.environment is not None:  # the outer face mirrors the surroundings
        surface = surface + ctx.sky(optics.reflect(ds, face_normal))
    band.add(LENS_SURFACE, s, r[:, None] * surface)
    if ctx.background_seen and ctx.environment is None:
        band.add(BACKGROUND_PASS, s, r[:, None] * ctx.background)
    ones = np.ones(len(s), dtype=np.int8)
    band.note(s, ones, ones * P.REFLECTED, ones * P.LENS_OUTER_TO_OUTSIDE)

    k = np.repeat((1.0 - r)[:, None], 3, axis=1)
    d_in = optics.refract(ds, face_normal, 1.0 / ior)
    rays = Rays(pix=s, lamp=li, o=local, d=d_in, k=k, medium=np.full(len(s), P.IN_LENS, np.int8),
                src=np.full(len(s), P.OUTER, np.int8),
                parent=np.full(len(s), P.OUTSIDE_TO_LENS, np.int8) if ctx.record else UNRECORDED,
                branch=np.full(len(s), P.TRANSMITTED, np.int8) if ctx.record else UNRECORDED,
                seen_reflector=np.zeros(len(s), bool))
    return rays.take(alive(k))


def at_reflector(ctx: Context, band: Band, rays: Rays, m: np.ndarray, k: np.ndarray, d: np.ndarray,
                 hit: np.ndarray, cls: np.ndarray) -> Rays:
    """A reflector hit (③ ④): the first-hit constant, Blinn's scatter (eq. 3), then the mirror ray
    where it stays above the cut-off."""
    L = ctx.lamps
    li = rays.lamp.take(m)
    pix = rays.pix.take(m)
    first = np.nonzero(~rays.seen_reflector.take(m))[0]
    band.add(REFLECTOR_CONSTANT, pix.take(first), rows(k, first) * rows(L.reflector_color, li.take(first)))
    normal = reflector.reflector_normal(hit, L.focal.take(li))
    to_bulb = optics.normalize(rows(L.bulb_center, li) - hit)
    scatter = optics.blinn(normal, -d, to_bulb, L.scatter.take(li), L.scatter_shininess.take(li))
    band.add(REFLECTOR_SCATTER, pix, optics.scaled(k, scatter) * rows(L.bulb_intensity, li))
    if ctx.phantom:  # the sun's light scattered back out of the lamp (sunlight.phantom)
        band.add(REFLECTOR_SCATTER, pix, k * sunlight.phantom(ctx.sun, ctx.phantom_lamps, li, hit, normal, -d))
    k = optics.scaled(k, L.reflectance.take(li))
    go = np.nonzero(alive(k))[0]
    n = len(go)
    return Rays(pix=pix.take(go), lamp=li.take(go), o=rows(hit, go), d=optics.reflect(rows(d, go), rows(normal, go)),
                k=rows(k, go), medium=np.full(n, P.IN_AIR, np.int8), src=np.full(n, P.REFLECTOR, np.int8),
                parent=cls.take(go), branch=branch_tags(cls, P.REFLECTED, n), seen_reflector=np.ones(n, bool))


@dataclass
class Split:
    """The Fresnel split of rays at a face between two media (MODEL.md §5): the weights of the
    reflected and the transmitted branch, and what Snell's law needs for the transmitted one."""

    cos_i: np.ndarray  # -d·n, the normal turned toward the incident side
    eta: np.ndarray  # n1 / n2, from the incident medium into the other
    reflectance: np.ndarray  # R (Fresnel's equations; 1 at total internal reflection)
    reflected: np.ndarray  # k R, the reflected branch's accumulated attenuation
    transmitted: np.ndarray  # k (1 - R), the transmitted branch's


def fresnel_split(k: np.ndarray, d: np.ndarray, facing: np.ndarray, n1: np.ndarray, n2: np.ndarray) -> Split:
    """Rays ``d`` of accumulated attenuation ``k`` meeting a face whose unit normal ``facing`` points
    toward them, from a medium of index ``n1`` into one of ``n2``."""
    cos_i = -optics.dot(d, facing)
    reflectance = optics.fresnel_reflectance(np.clip(cos_i, 0.0, 1.0), n1, n2)
    return Split(cos_i, n1 / n2, reflectance, optics.scaled(k, reflectance), optics.scaled(k, 1.0 - reflectance))


@dataclass
class FaceHit:
    """Rays ``m`` of a generation at faces of a dielectric material (the lens, or a prism plate),
    split there: the reflected rays are made at once, the transmitted ones (``through``) where
    the caller sends them on."""

    pix: np.ndarray
    lamp: np.ndarray
    hit: np.ndarray  # where they meet the face
    d: np.ndarray
    facing: np.ndarray  # the face's normal toward the incident side
    medium: np.ndarray  # the medium they come from
    from_inside: np.ndarray  # met from inside the material
    material: int  # paths.IN_LENS or paths.IN_PLATE
    surface: np.ndarray  # the surface met: where the children start
    cls: np.ndarray  # the segments' path classes (UNRECORDED: not kept)
    seen_reflector: np.ndarray
    split: Split

    def reflected(self) -> Rays:
        """The mirror rays that stay above the cut-off, in the medium they came from."""
        go = np.nonzero(alive(self.split.reflected))[0]
        return Rays(pix=self.pix.take(go), lamp=self.lamp.take(go), o=rows(self.hit, go),
                    d=optics.reflect(rows(self.d, go), rows(self.facing, go)), k=rows(self.split.reflected, go),
                    medium=self.medium.take(go), src=self.surface.take(go), parent=self.cls.take(go),
                    branch=branch_tags(self.cls, P.REFLECTED, len(go)), seen_reflector=self.seen_reflector.take(go))

    def through(self, sel: np.ndarray) -> Rays:
        """The transmitted rays ``sel``: bent by Snell's law into the other medium."""
        split = self.split
        d_t = optics.refract(rows(self.d, sel), rows(self.facing, sel), split.eta.take(sel), split.cos_i.take(sel))
        medium = np.where(self.from_inside.take(sel), np.int8(P.IN_AIR), np.int8(self.material))
        return Rays(pix=self.pix.take(sel), lamp=self.lamp.take(sel), o=rows(self.hit, sel), d=d_t,
                    k=rows(split.transmitted, sel), medium=medium, src=self.surface.take(sel),
                    parent=self.cls.take(sel), branch=branch_tags(self.cls, P.TRANSMITTED, len(sel)),
                    seen_reflector=self.seen_reflector.take(sel))


def at_dielectric(rays: Rays, m: np.ndarray, k: np.ndarray, d: np.ndarray, hit: np.ndarray, cls: np.ndarray,
                  surface: np.ndarray, out_normal: np.ndarray, ior: np.ndarray, material: int) -> FaceHit:
    """The rays ``m`` (attenuation ``k``, directions ``d``) meeting faces of ``material`` (index
    ``ior`` per lamp) at ``hit``, ``out_normal`` pointing out of the material: the Fresnel split."""
    lamp = rays.lamp.take(m)
    medium = rays.medium.take(m)
    from_inside = medium == material
    # Toward the incident side: the normal negated for rays inside (a sign flip is exact).
    facing = optics.scaled(out_normal, np.where(from_inside, -1.0, 1.0))
    n_material = ior.take(lamp)
    n1 = np.where(from_inside, n_material, 1.0)
    n2 = np.where(from_inside, 1.0, n_material)
    return FaceHit(rays.pix.take(m), lamp, hit, d, facing, medium, from_inside, material, surface, cls,
                   rays.seen_reflector.take(m), fresnel_split(k, d, facing, n1, n2))


def at_lens_face(ctx: Context, band: Band, rays: Rays, m: np.ndarray, k: np.ndarray, d: np.ndarray,
                 hit: np.ndarray, cls: np.ndarray, surface: np.ndarray, out_normal: np.ndarray) -> list[Rays]:
    """A lens surface (the outer face or a cut) met from either side; ``out_normal`` points out of
    the lens material (-y on the outer face, the cap's on the cuts). Light transmitted out through
    the outer face leaves the lamp (⑩) and shows the background; every other branch goes on where
    above the cut-off."""
    face = at_dielectric(rays, m, k, d, hit, cls, surface, out_normal, ctx.lamps.ior, P.IN_LENS)
    split = face.split
    partial = split.reflectance < 1.0
    if ctx.background_seen or ctx.record:
        leaving = np.nonzero(partial & (surface == P.OUTER))[0]  # ⑩: out to the background (ends)
        if ctx.background_seen:
            d_out = rows(d, leaving)
            if ctx.environment is not None:  # the surroundings along the refracted ray
                d_out = optics.refract(d_out, rows(face.facing, leaving), split.eta.take(leaving))
            band.add(BACKGROUND_PASS, face.pix.take(leaving), rows(split.transmitted, leaving) * ctx.sky(d_out))
        if ctx.record:
            band.note(face.pix.take(leaving), cls.take(leaving), np.full(len(leaving), P.TRANSMITTED),
                      np.full(len(leaving), P.LENS_OUTER_TO_OUTSIDE))
    going_on = np.nonzero(partial & (surface != P.OUTER) & alive(split.transmitted))[0]
    return [face.reflected(), face.through(going_on)] if len(going_on) else [face.reflected()]


def at_plate_face(rays: Rays, m: np.ndarray, k: np.ndarray, d: np.ndarray, hit: np.ndarray, cls: np.ndarray,
                  surface: np.ndarray, out_normal: np.ndarray, L: LampTable) -> list[Rays]:
    """A prism-plate face met from either side (README, the prism plate): the lens's Fresnel split
    with the plate's index; ``out_normal`` points out of the plate material. Nothing leaves the lamp
    here, so both branches go on where above the cut-off."""
    face = at_dielectric(rays, m, k, d, hit, cls, surface, out_normal, L.plate_ior, P.IN_PLATE)
    split = face.split
    going_on = np.nonzero((split.reflectance < 1.0) & alive(split.transmitted))[0]
    return [face.reflected(), face.through(going_on)] if len(going_on) else [face.reflected()]

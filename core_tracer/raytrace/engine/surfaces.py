"""What happens where a ray meets a surface: the lens's outer face seen from the eye (①), the
reflector (③ ④, eq. 3), and the faces of a dielectric (a lens or a prism plate) met from either
side, where one Fresnel split (docs/model.md §5) gives the reflected and the transmitted branch.

The free-form tracer (``freeform.render``) splits its meshes' lens faces with the same
``split_at_face`` and lights its reflectors with the same ``sphere_irradiance``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import optics, sunlight
from .. import paths as P
from ..lamp_table import LampTable
from ..parts import reflector
from ..parts.base import put_rows, rows
from ..spectral import Throughput
from .context import Context
from .rays import (
    BACKGROUND_PASS,
    LENS_SURFACE,
    NOT_DEFERRED,
    REFLECTOR_CONSTANT,
    REFLECTOR_SCATTER,
    UNPOLARISED,
    UNRECORDED,
    Band,
    Rays,
    alive,
    branch_tags,
)


def into_lenses(ctx: Context, band: Band, pix: np.ndarray, lamp: np.ndarray, d: np.ndarray,
                face_normal: np.ndarray, local: np.ndarray) -> Rays:
    """Eye rays ``d`` of slots ``pix`` meeting the outer face of lamps ``lamp`` (①) at ``local``
    (lamp frame), where the face's outward normal is ``face_normal``: the Fresnel split from the
    air, the reflected branch shaded by eq. (1) and mirroring the surroundings (§3.2.3), the
    transmitted rays into the lens where above the cut-off."""
    lamps = ctx.lamps
    ior = lamps.ior[lamp]
    n = len(pix)
    throughput = ctx.throughput
    if throughput is None:
        split = fresnel_split(np.ones((n, ctx.channels)), d, face_normal, 1.0, ior)
        travelled = NOT_DEFERRED
        reflected = split.reflected
    else:  # unpolarised light, half of it s-polarised; Fresnel at the nodes (``spectral.Throughput``)
        nodes = len(throughput.nodes_nm)
        split = fresnel_split(np.ones((n, nodes)), d, face_normal, 1.0, ior, np.full((n, nodes), 0.5),
                              1.0, throughput.ior_nodes[lamp])
        travelled = np.zeros((n, Throughput.TRAVELLED))
        reflected = split.reflected @ throughput.to_bands  # nothing travelled yet
    surface = ctx.lens_surface(face_normal, d, lamps.lens_diffuse[lamp], lamps.lens_specular[lamp],
                               lamps.lens_shininess[lamp])
    band.add(LENS_SURFACE, pix, reflected * surface)
    if ctx.background_seen and ctx.environment is None:
        band.add(BACKGROUND_PASS, pix, reflected * ctx.background)
    ones = np.ones(len(pix), dtype=np.int8)
    band.note(pix, ones, ones * P.REFLECTED, ones * P.LENS_OUTER_TO_OUTSIDE)

    rays = Rays(pix=pix, lamp=lamp, o=local, d=optics.refract(d, face_normal, split.eta, split.cos_i),
                k=split.transmitted, medium=np.full(n, P.IN_LENS, np.int8), src=np.full(n, P.OUTER, np.int8),
                parent=np.full(n, P.OUTSIDE_TO_LENS, np.int8) if ctx.record else UNRECORDED,
                branch=np.full(n, P.TRANSMITTED, np.int8) if ctx.record else UNRECORDED,
                seen_reflector=np.zeros(n, bool), k_s=split.transmitted_s, travelled=travelled)
    return rays.take(alive(split.transmitted))


def at_reflector(ctx: Context, band: Band, rays: Rays, met: np.ndarray, k: np.ndarray, d: np.ndarray,
                 hit: np.ndarray, cls: np.ndarray) -> Rays:
    """A reflector hit (③ ④): the first-hit constant, Blinn's scatter toward the bulb (eq. 3), then
    the mirror ray, k × reflectance, where it stays above the cut-off."""
    lamps = ctx.lamps
    lamp = rays.lamp.take(met)
    pix = rays.pix.take(met)
    normal = reflector.reflector_normal(hit, lamps.focal.take(lamp))
    to_bulb = optics.normalize(rows(lamps.bulb_center, lamp) - hit)
    scatter = optics.blinn(normal, -d, to_bulb, lamps.scatter.take(lamp), lamps.scatter_shininess.take(lamp))
    k_s = rows(rays.k_s, met)
    throughput, travelled, deferred = ctx.throughput, NOT_DEFERRED, None
    if throughput is None:
        first = np.nonzero(~rays.seen_reflector.take(met))[0]
        band.add(REFLECTOR_CONSTANT, pix.take(first), rows(k, first) * rows(lamps.reflector_color, lamp.take(first)))
        band.add(REFLECTOR_SCATTER, pix, optics.scaled(k, scatter) * rows(lamps.bulb_radiance, lamp), lamp)
        k_bands = k
    else:  # no appearance constant; the finish's reflectance (one more reflection off it, deferred)
        # spread by the normalised lobe over the bulb's light
        travelled = rows(rays.travelled, met)
        travelled[:, Throughput.REFLECTIONS] += 1.0
        k_bands = throughput.bands(k, travelled, lamp)
        irradiance = bulb_irradiance(to_bulb, normal, hit, lamps, lamp)
        scattered = optics.scaled(k_bands, scatter * irradiance)
        band.add(REFLECTOR_SCATTER, pix, scattered * rows(lamps.bulb_radiance, lamp), lamp)
        deferred = (throughput, travelled, lamp)
    if ctx.phantom:  # the sun's light scattered back out of the lamp (sunlight.phantom)
        band.add(REFLECTOR_SCATTER, pix, k_bands * sunlight.phantom(ctx.sun, ctx.phantom_lamps, lamp, hit, normal, -d))
    mirror = lamps.reflectance.take(lamp)
    mirrored = optics.scaled(k, mirror)
    going_on = np.nonzero(alive(mirrored, deferred))[0]
    n = len(going_on)
    return Rays(pix=pix.take(going_on), lamp=lamp.take(going_on), o=rows(hit, going_on),
                d=optics.reflect(rows(d, going_on), rows(normal, going_on)), k=rows(mirrored, going_on),
                medium=np.full(n, P.IN_AIR, np.int8), src=np.full(n, P.REFLECTOR, np.int8),
                parent=cls.take(going_on), branch=branch_tags(cls, P.REFLECTED, n), seen_reflector=np.ones(n, bool),
                k_s=k_s if k_s is UNPOLARISED else rows(optics.scaled(k_s, mirror), going_on),
                travelled=rows(travelled, going_on))


def bulb_irradiance(to_bulb: np.ndarray, normal: np.ndarray, hit: np.ndarray, lamps: LampTable,
                    lamp: np.ndarray) -> np.ndarray:
    """Per unit of the bulb's radiance, the irradiance at reflector points ``hit`` of ``normal``
    from the bulb (a sphere of uniform radiance): its solid angle Ω = 2π (1 - √(1 - r²/D²)) at the
    distance D of its centre, times the cosine toward it (the whole bulb taken in the direction of
    its centre; neither the socket's shadow nor a part of the bulb below the horizon is taken)."""
    return sphere_irradiance(rows(lamps.bulb_center, lamp) - hit, lamps.bulb_radius.take(lamp), normal, to_bulb)


def sphere_irradiance(gap: np.ndarray, radius: np.ndarray, normal: np.ndarray, toward: np.ndarray) -> np.ndarray:
    """Per unit of radiance, the irradiance on surfaces of ``normal`` from spheres of uniform radiance
    of ``radius`` whose centres lie ``gap`` away (unit ``toward``: along ``gap``): the solid angle
    Ω = 2π (1 - √(1 - r²/D²)) times the cosine toward the centre."""
    ratio = np.minimum(1.0, radius**2 / optics.dot(gap, gap))
    solid_angle = 2.0 * np.pi * (1.0 - np.sqrt(1.0 - ratio))
    return solid_angle * np.maximum(0.0, optics.dot(normal, toward))


@dataclass
class Split:
    """The Fresnel split of rays at a face between two media (docs/model.md §5): the weights of the
    reflected and the transmitted branch, and what Snell's law needs for the transmitted one."""

    cos_i: np.ndarray  # -d·n, the normal turned toward the incident side
    eta: np.ndarray  # n1 / n2, from the incident medium into the other (the geometry's indices)
    reflectance: np.ndarray  # R (Fresnel's equations; 1 at total internal reflection); photometric: R_s
    reflected: np.ndarray  # k R, the reflected branch's accumulated attenuation
    transmitted: np.ndarray  # k (1 - R), the transmitted branch's
    partial: np.ndarray  # the rays some light crosses the face for (no total internal reflection)
    reflected_s: np.ndarray = UNPOLARISED  # photometric: the s-polarised shares of the two branches
    transmitted_s: np.ndarray = UNPOLARISED


def fresnel_split(k: np.ndarray, d: np.ndarray, facing: np.ndarray, n1: np.ndarray, n2: np.ndarray,
                  k_s: np.ndarray = UNPOLARISED, band_n1: np.ndarray | float = 1.0,
                  band_n2: np.ndarray | float = 1.0) -> Split:
    """Rays ``d`` of accumulated attenuation ``k`` meeting a face whose unit normal ``facing`` points
    toward them, from a medium of index ``n1`` into one of ``n2``.

    The paper mode splits k by the average of the s and p reflectances. The photometric mode
    carries the s-polarised share ``k_s`` of k along each branch and splits each share by its own
    reflectance, per band with the band's indices ``band_n1``, ``band_n2`` ((N, K) or scalars;
    ``n1``, ``n2`` are the indices the ray's direction follows, at n_d: dispersion in Fresnel only,
    docs/photometric.md). Where the geometry's indices give total internal reflection every band
    is reflected whole."""
    cos_i = -optics.dot(d, facing)
    if k_s is UNPOLARISED:
        reflectance = optics.fresnel_reflectance(np.clip(cos_i, 0.0, 1.0), n1, n2)
        return Split(cos_i, n1 / n2, reflectance, optics.scaled(k, reflectance), optics.scaled(k, 1.0 - reflectance),
                     reflectance < 1.0)
    cos_i_clipped = np.clip(cos_i, 0.0, 1.0)
    eta = n1 / n2
    partial = (1.0 - cos_i_clipped * cos_i_clipped) * (eta * eta) < 1.0  # Snell has a transmitted ray
    # Fresnel's equations only where some light crosses: total internal reflection reflects every band
    # whole (most of a light guide's segments), the same values as the equations' own TIR branch (R = 1:
    # k_s R_s + k_p R_p = k_s + k_p, and nothing transmitted), so only the crossing rows are multiplied
    r_s = np.ones(k.shape)
    k_p = k - k_s
    crossing = np.nonzero(partial)[0]
    if 2 * len(crossing) > len(k):  # mostly crossing (a lens's faces): the products on every row are cheaper
        r_p = np.ones(k.shape)
        r_s[crossing], r_p[crossing] = optics.fresnel_polarised(
            cos_i_clipped[crossing, None], _rows_of(band_n1, crossing), _rows_of(band_n2, crossing))
        reflected_s, transmitted_s = k_s * r_s, k_s * (1.0 - r_s)
        return Split(cos_i, eta, r_s, reflected_s + k_p * r_p, transmitted_s + k_p * (1.0 - r_p), partial,
                     reflected_s, transmitted_s)
    reflected_s, reflected = k_s.copy(), k_s + k_p
    transmitted_s, transmitted = np.zeros(k.shape), np.zeros(k.shape)
    if len(crossing):
        r_s_c, r_p_c = optics.fresnel_polarised(
            cos_i_clipped[crossing, None], _rows_of(band_n1, crossing), _rows_of(band_n2, crossing))
        k_s_c, k_p_c = rows(k_s, crossing), rows(k_p, crossing)
        put_rows(r_s, crossing, r_s_c)
        # R_s k_s + R_p k_p reflected, (1 − R_s) k_s + (1 − R_p) k_p transmitted, per band
        reflected_s_c, transmitted_s_c = k_s_c * r_s_c, k_s_c * (1.0 - r_s_c)
        put_rows(reflected_s, crossing, reflected_s_c)
        put_rows(reflected, crossing, reflected_s_c + k_p_c * r_p_c)
        put_rows(transmitted_s, crossing, transmitted_s_c)
        put_rows(transmitted, crossing, transmitted_s_c + k_p_c * (1.0 - r_p_c))
    return Split(cos_i, eta, r_s, reflected, transmitted, partial, reflected_s, transmitted_s)


def split_at_face(k: np.ndarray, k_s: np.ndarray, d: np.ndarray, facing: np.ndarray, from_inside: np.ndarray,
                  n_material: np.ndarray, band_n: np.ndarray | None = None) -> Split:
    """``fresnel_split`` of rays meeting a face of a material of index ``n_material`` (per ray) from
    inside it (``from_inside``) or from the air; photometric: with the s-polarised shares ``k_s`` and
    the material's index per column of k, ``band_n`` (None in the paper mode)."""
    n1 = np.where(from_inside, n_material, 1.0)
    n2 = np.where(from_inside, 1.0, n_material)
    if band_n is None:
        return fresnel_split(k, d, facing, n1, n2)
    inside = from_inside[:, None]
    return fresnel_split(k, d, facing, n1, n2, k_s, np.where(inside, band_n, 1.0), np.where(inside, 1.0, band_n))


def _rows_of(values: np.ndarray | float, sel: np.ndarray) -> np.ndarray | float:
    """The rows ``sel`` of per-ray values (N, K), or a value shared by all rays as it is."""
    return rows(values, sel) if isinstance(values, np.ndarray) and values.ndim == 2 else values


@dataclass
class FaceHit:
    """Rays of a generation at faces of a dielectric material (the lens, or a prism plate),
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
    travelled: np.ndarray = NOT_DEFERRED  # photometric: the rays' ``Rays.travelled``
    deferred: tuple | None = None  # photometric: what the cut-off test takes (``rays.alive``)

    def reflected(self) -> Rays:
        """The mirror rays that stay above the cut-off, in the medium they came from."""
        going_on = np.nonzero(alive(self.split.reflected, self.deferred))[0]
        return Rays(pix=self.pix.take(going_on), lamp=self.lamp.take(going_on), o=rows(self.hit, going_on),
                    d=optics.reflect(rows(self.d, going_on), rows(self.facing, going_on)),
                    k=rows(self.split.reflected, going_on), medium=self.medium.take(going_on),
                    src=self.surface.take(going_on), parent=self.cls.take(going_on),
                    branch=branch_tags(self.cls, P.REFLECTED, len(going_on)),
                    seen_reflector=self.seen_reflector.take(going_on), k_s=rows(self.split.reflected_s, going_on),
                    travelled=rows(self.travelled, going_on))

    def through(self, sel: np.ndarray) -> Rays:
        """The transmitted rays ``sel``: bent by Snell's law into the other medium."""
        split = self.split
        d_t = optics.refract(rows(self.d, sel), rows(self.facing, sel), split.eta.take(sel), split.cos_i.take(sel))
        medium = np.where(self.from_inside.take(sel), np.int8(P.IN_AIR), np.int8(self.material))
        return Rays(pix=self.pix.take(sel), lamp=self.lamp.take(sel), o=rows(self.hit, sel), d=d_t,
                    k=rows(split.transmitted, sel), medium=medium, src=self.surface.take(sel),
                    parent=self.cls.take(sel), branch=branch_tags(self.cls, P.TRANSMITTED, len(sel)),
                    seen_reflector=self.seen_reflector.take(sel), k_s=rows(split.transmitted_s, sel),
                    travelled=rows(self.travelled, sel))


def at_dielectric(rays: Rays, met: np.ndarray, k: np.ndarray, d: np.ndarray, hit: np.ndarray, cls: np.ndarray,
                  surface: np.ndarray, out_normal: np.ndarray, ior: np.ndarray, material: int,
                  band_ior: np.ndarray | None = None, throughput: Throughput | None = None) -> FaceHit:
    """The rays ``met`` (attenuation ``k``, directions ``d``) meeting faces of ``material`` (index
    ``ior`` per lamp; photometric: ``band_ior`` per lamp and column of k for Fresnel: per band, or
    per wavelength node with the deferred ``throughput``, whose bound the cut-off takes) at ``hit``,
    ``out_normal`` pointing out of the material: the Fresnel split."""
    lamp = rays.lamp.take(met)
    medium = rays.medium.take(met)
    from_inside = medium == material
    # Toward the incident side: the normal negated for rays inside (a sign flip is exact).
    facing = optics.scaled(out_normal, np.where(from_inside, -1.0, 1.0))
    split = split_at_face(k, rows(rays.k_s, met), d, facing, from_inside, ior.take(lamp),
                          None if band_ior is None else rows(band_ior, lamp))
    face = FaceHit(rays.pix.take(met), lamp, hit, d, facing, medium, from_inside, material, surface, cls,
                   rays.seen_reflector.take(met), split)
    if throughput is not None:
        face.travelled = rows(rays.travelled, met)
        face.deferred = (throughput, face.travelled, lamp)
    return face


def at_lens_face(ctx: Context, band: Band, rays: Rays, met: np.ndarray, k: np.ndarray, d: np.ndarray,
                 hit: np.ndarray, cls: np.ndarray, surface: np.ndarray, out_normal: np.ndarray) -> list[Rays]:
    """A lens surface (the outer face or a cut) met from either side; ``out_normal`` points out of
    the lens material (-y on the outer face, the cap's on the cuts). Light transmitted out through
    the outer face leaves the lamp (⑩) and shows the background; every other branch goes on where
    above the cut-off."""
    throughput = ctx.throughput
    face = at_dielectric(rays, met, k, d, hit, cls, surface, out_normal, ctx.lamps.ior, P.IN_LENS,
                         None if throughput is None else throughput.ior_nodes, throughput)
    split = face.split
    partial = split.partial
    if ctx.background_seen or ctx.record:
        leaving = np.nonzero(partial & (surface == P.OUTER))[0]  # ⑩: out to the background (ends)
        if ctx.background_seen:
            d_out = rows(d, leaving)
            if ctx.environment is not None:  # the surroundings along the refracted ray
                d_out = optics.refract(d_out, rows(face.facing, leaving), split.eta.take(leaving))
            transmitted = rows(split.transmitted, leaving)
            if throughput is not None:
                transmitted = throughput.bands(transmitted, rows(face.travelled, leaving), face.lamp.take(leaving))
            band.add(BACKGROUND_PASS, face.pix.take(leaving), transmitted * ctx.sky(d_out))
        if ctx.record:
            band.note(face.pix.take(leaving), cls.take(leaving), np.full(len(leaving), P.TRANSMITTED),
                      np.full(len(leaving), P.LENS_OUTER_TO_OUTSIDE))
    going_on = np.nonzero(partial & (surface != P.OUTER) & alive(split.transmitted, face.deferred))[0]
    return [face.reflected(), face.through(going_on)] if len(going_on) else [face.reflected()]


def at_plate_face(rays: Rays, met: np.ndarray, k: np.ndarray, d: np.ndarray, hit: np.ndarray, cls: np.ndarray,
                  surface: np.ndarray, out_normal: np.ndarray, lamps: LampTable,
                  throughput: Throughput | None = None) -> list[Rays]:
    """A prism-plate face met from either side (docs/model.md, the prism plate): the lens's Fresnel split
    with the plate's index (photometric: per band, or at the nodes of a deferred ``throughput``);
    ``out_normal`` points out of the plate material. Nothing leaves the lamp here, so both branches
    go on where above the cut-off."""
    face = at_dielectric(rays, met, k, d, hit, cls, surface, out_normal, lamps.plate_ior, P.IN_PLATE,
                         lamps.plate_ior_bands if throughput is None else throughput.plate_ior_nodes, throughput)
    split = face.split
    going_on = np.nonzero(split.partial & alive(split.transmitted, face.deferred))[0]
    return [face.reflected(), face.through(going_on)] if len(going_on) else [face.reflected()]

"""A light guide's flux tally (docs/photometric.md, light guides): light traced forward from a
guide's LED through the rod, counting the luminous flux that leaves through its far end face.

The LED is the renderer's (``raytrace.spectral.guide_led_radiance``): a Lambertian square die of
side a and radiance L(λ), flux Φ(λ) = π L a²; a photon starts at a uniform point of the die in a
cosine-distributed direction about the guide's axis, carrying Φ / N. The rod's optics are the
renderer's own: its intersections (``parts.light_guide``), the Fresnel split per band and
polarisation (``surfaces.at_dielectric``) and Beer–Lambert along the segments inside (eq. 2). Light
that leaves the rod anywhere else, or goes back to the die, is not counted; a branch below the
cut-off (``rays.CUTOFF``) is dropped, one alive at ``walk.GUIDE_MAX_DEPTH`` is counted in ``cut_at_depth``.

With no prisms every ray that enters the end face is trapped by total internal reflection (its
angle to the side walls is at least 90° − θ_c > θ_c for n > √2), so the flux out of the far end has
a closed form (tests/photometry/test_light_guide.py).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..raytrace import optics
from ..raytrace import paths as P
from ..raytrace.engine import make_context
from ..raytrace.engine.rays import UNRECORDED, Rays, concat
from ..raytrace.engine.surfaces import at_dielectric
from ..raytrace.engine.walk import GUIDE_MAX_DEPTH
from ..raytrace.parts import light_guide
from ..raytrace.parts.base import Segments, put_rows, rows
from .light_tracing import cosine_directions

START_GAP = 1e-4  # mm: photons start this far in front of the end face at least (the face itself is t = 0)


@dataclass(frozen=True)
class GuideFlux:
    emitted_lm: float  # the LED's flux
    out_lm: float  # the flux out of the far end face
    stderr_lm: float  # its standard error over the photons
    cut_at_depth: int  # branches still alive at the depth limit, ended there
    deepest: int  # the most segments a photon's branches took


def far_end_flux(scene: dict, lamp: int = 0, *, photons: int = 200_000, seed: int = 0,
                 bands: int | None = None) -> GuideFlux:
    """The luminous flux of lamp ``lamp``'s guide LED (at the first end) that leaves the far end face."""
    ctx = make_context(scene, 1, 1, bands=bands)
    lamps, guide = ctx.lamps, ctx.lamps.guide
    if guide is None or not guide.present[lamp]:
        raise ValueError(f"lamps[{lamp}] has no light guide")
    rng = np.random.default_rng(seed)
    half, gap = float(guide.led_half[lamp]), max(float(guide.led_gap[lamp]), START_GAP)
    axis, across, start = guide.axis[lamp], guide.across[lamp], guide.start[lamp]
    u, v = rng.uniform(-half, half, photons), rng.uniform(-half, half, photons)
    o = start - gap * axis + u[:, None] * across + v[:, None] * np.array([0.0, 1.0, 0.0])
    d = cosine_directions(np.broadcast_to(axis, (photons, 3)), rng)
    area = (2.0 * half * 1e-3) ** 2  # m²
    flux = math.pi * guide.led_radiance[lamp] * area / photons  # W/nm per photon per band
    lm_per_band = flux * ctx.photometric.to_xyz[:, 1]  # lm per photon per band of unit attenuation
    k = np.ones((photons, ctx.channels))
    rays = Rays(pix=np.arange(photons), lamp=np.full(photons, lamp), o=o, d=d, k=k,
                medium=np.full(photons, P.IN_AIR, np.int8), src=np.full(photons, P.GUIDE_LED, np.int8),
                parent=UNRECORDED, branch=UNRECORDED, seen_reflector=np.zeros(photons, bool), k_s=0.5 * k,
                travelled=UNRECORDED)  # unpolarised light: half of it s-polarised
    per_photon = np.zeros(photons)
    depth = 0
    length = float(guide.length[lamp])
    while len(rays) and depth < GUIDE_MAX_DEPTH:
        depth += 1
        seg = Segments(rays.o, rays.d, rays.lamp, rays.src, rays.medium)
        t, normal = light_guide.intersect(seg, lamps, np.full(len(rays), np.inf))
        rays = _absorbed(rays, t, lamps.plate_absorption)
        met = np.nonzero(np.isfinite(t))[0]  # the others leave (light that left the rod does not come back)
        if not len(met):
            rays = rays.take(met)
            break
        d = rows(rays.d, met)
        hit = rows(rays.o, met) + optics.scaled(d, t.take(met))
        face = at_dielectric(rays, met, rows(rays.k, met), d, hit, UNRECORDED, np.full(len(met), P.GUIDE, np.int8),
                             rows(normal, met), lamps.plate_ior, P.IN_GUIDE, lamps.plate_ior_bands)
        partial = face.split.partial
        s_hit = (hit - start) @ axis
        out = np.nonzero(partial & face.from_inside & (s_hit >= length - 1e-6))[0]
        if len(out):
            gone = face.through(out)
            np.add.at(per_photon, gone.pix, gone.k @ lm_per_band)
        entering = np.nonzero(partial & ~face.from_inside & (face.split.transmitted.max(axis=1) > 0))[0]
        children = [face.reflected()] + ([face.through(entering)] if len(entering) else [])
        children = [c for c in children if len(c)]
        rays = concat(children) if len(children) > 1 else (children[0] if children else rays.take(np.zeros(0, int)))
    total = float(per_photon.sum())
    stderr = float(np.sqrt(photons / max(photons - 1, 1) * ((per_photon**2).sum() - total**2 / photons)))
    return GuideFlux(float(flux @ ctx.photometric.to_xyz[:, 1]) * photons, total, stderr, len(rays), depth)


def _absorbed(rays: Rays, t: np.ndarray, coefficients: np.ndarray) -> Rays:
    """Beer–Lambert along the segments inside the rod (eq. 2), on k and its s share."""
    inside = np.nonzero((rays.medium == P.IN_GUIDE) & np.isfinite(t))[0]
    if not len(inside):
        return rays
    k, k_s = rays.k.copy(), rays.k_s.copy()
    transmittance = optics.absorption(rows(coefficients, rays.lamp.take(inside)), t.take(inside))
    put_rows(k, inside, rows(k, inside) * transmittance)
    put_rows(k_s, inside, rows(k_s, inside) * transmittance)
    return replace(rays, k=k, k_s=k_s)

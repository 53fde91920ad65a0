"""A light guide's flux tally (docs/photometric.md, light guides): light traced forward from a
guide's LED through the rod, counting the luminous flux that leaves through its far end face.

The light is the lamp's LED dies' (``light_tracing.led_photons``: a uniform point of a die, a
cosine-distributed direction about its normal, carrying Φ(λ) f(θ, φ) / N), placed by the design
facing the guide's first end face. The rod's optics are the
renderer's own: its intersections (``parts.light_guide``), the Fresnel split per band and
polarisation (``surfaces.at_dielectric``) and Beer–Lambert along the segments inside (eq. 2). The light
that leaves the rod through its first end face from inside is counted apart (``near_lm``); a guide
lit at both ends has a second array, the first's mirror image (``led_photons``), so by symmetry its
two end faces pass the same flux, each the one-end guide's far plus near flux. Light
that leaves the rod anywhere else is not counted; a branch below the
cut-off (``rays.CUTOFF``) is dropped, one alive at ``context.GUIDE_MAX_DEPTH`` is counted in ``cut_at_depth``.

With no prisms every ray that enters the end face is trapped by total internal reflection (its
angle to the side walls is at least 90° − θ_c > θ_c for n > √2), so the flux out of the far end has
a closed form (tests/photometry/test_light_guide.py).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..raytrace import optics
from ..raytrace import paths as P
from ..raytrace.engine import make_context
from ..raytrace.engine.context import GUIDE_MAX_DEPTH
from ..raytrace.engine.rays import UNRECORDED, Rays, concat
from ..raytrace.engine.surfaces import at_dielectric
from ..raytrace.parts import light_guide
from ..raytrace.parts.base import Segments, put_rows, rows
from .light_tracing import led_photons


@dataclass(frozen=True)
class GuideFlux:
    emitted_lm: float  # the LED's flux
    out_lm: float  # the flux out of the far end face
    stderr_lm: float  # its standard error over the photons
    near_lm: float  # the flux out of the first end face from inside the rod (lit at both ends: ≈ out_lm)
    cut_at_depth: int  # branches still alive at the depth limit, ended there
    deepest: int  # the most segments a photon's branches took


def far_end_flux(scene: dict, lamp: int = 0, *, photons: int = 200_000, seed: int = 0,
                 bands: int | None = None) -> GuideFlux:
    """The luminous flux of lamp ``lamp``'s LEDs that leaves its guide's far end face (and its first)."""
    ctx = make_context(scene, 1, 1, bands=bands)
    lamps, guide = ctx.lamps, ctx.lamps.guide
    if guide is None or not guide.present[lamp]:
        raise ValueError(f"lamps[{lamp}] has no light guide")
    rng = np.random.default_rng(seed)
    emitted = led_photons(ctx, lamp, photons, rng)
    if emitted is None:
        raise ValueError(f"lamps[{lamp}] has no LEDs to light its guide")
    rays, flux = emitted
    lm_per_photon = flux * ctx.photometric.to_xyz[:, 1]  # lm per photon and band at unit attenuation
    per_photon = np.zeros(photons)
    near = 0.0
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
        s_hit = guide.along(hit, np.full(len(hit), lamp))
        out = np.nonzero(partial & face.from_inside & (s_hit >= length - 1e-6))[0]
        if len(out):
            gone = face.through(out)
            np.add.at(per_photon, gone.pix, (gone.k * rows(lm_per_photon, gone.pix)).sum(axis=1))
        back = np.nonzero(partial & face.from_inside & (s_hit <= 1e-6))[0]
        if len(back):
            gone = face.through(back)
            near += float((gone.k * rows(lm_per_photon, gone.pix)).sum())
        entering = np.nonzero(partial & ~face.from_inside & (face.split.transmitted.max(axis=1) > 0))[0]
        children = [face.reflected()] + ([face.through(entering)] if len(entering) else [])
        children = [c for c in children if len(c)]
        rays = concat(children) if len(children) > 1 else (children[0] if children else rays.take(np.zeros(0, int)))
    total = float(per_photon.sum())
    stderr = float(np.sqrt(photons / max(photons - 1, 1) * ((per_photon**2).sum() - total**2 / photons)))
    return GuideFlux(float(lm_per_photon.sum()), total, stderr, near, len(rays), depth)


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

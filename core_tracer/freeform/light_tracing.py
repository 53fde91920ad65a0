"""Light traced forward through a free-form design's meshes: the sources and the transport of the
second intensity estimator (``measures.light_tracing``) for a design whose parts are meshes.

The sources are the photometric roles' (``roles``), each sampled by its own emission:

- each bulb part, a Lambertian emitter of radiance L(λ) over its mesh (``roles.emitter_radiance``):
  a photon starts at a uniform point of the mesh (triangles by area) in a cosine-distributed
  direction about the face's normal turned away from the bulb's centre, carrying π L A / N, A the
  mesh's area (the flux that leaves a convex emitter of that radiance);
- each reflector's glow toward its bulbs, the radiance the renderer adds at a reflector hit
  (``render._reflector``): L_g(x, ω) = ρ(λ) s (n + 8)/(8π) cos^n β · Ω_b(x) cos θ_b · L_b(λ), a
  photon at a uniform point of the reflector mesh in a cosine-distributed direction about its
  shading normal turned toward the bulb, carrying π A L_g(x, ω) / N;
- each LED lamp's dies (``leds``), as the parametric lamp's (``measures.light_tracing.led_photons``).

The light's transport is the renderer's own walk over the meshes (``render._step``: the nearest
triangle through Embree, Beer–Lambert inside a lens, the Fresnel split per band and polarisation,
the reflector's mirror (1 − s) ρ(λ); bulbs, sockets, side walls and bodies end a path), so both
estimators describe the same lamp; what it adds to the passes is thrown away. A branch that meets
nothing has left the lamp and is counted. Where light from outside meets a lens's outer face (①),
the walk keeps its transmitted branch only (the renderer shades the reflected one by eq. 1): light
leaving one lens and meeting another from outside loses its ~4 % reflection.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from ..raytrace import optics, pixel_filter
from ..raytrace import paths as P
from ..raytrace.camera import make_camera
from ..raytrace.engine.rays import NOT_DEFERRED, Band
from ..raytrace.engine.surfaces import sphere_irradiance
from ..raytrace.optics import cosine_directions
from .design import DesignMeshes
from .hits import nearest, shading_normal
from .render import MeshRays, _Context, _step, die_hits

Emit = Callable[[int, np.random.Generator], tuple[MeshRays, np.ndarray]]


def context(measured: dict, meshes: DesignMeshes, bands: int | None = None) -> _Context:
    """The walk's context of a measurement scene (``intensity.measurement_scene``) on its meshes."""
    geometry, embree, _built = meshes.cache.get(measured, meshes.meshes)
    return _Context(measured, make_camera(measured["camera"], 1, 1), geometry, embree, 1,
                    pixel_filter.DEFAULT_FILTER, False, bands)


def sources(ctx: _Context, scene: dict) -> list[Emit]:
    """Every source of ``scene`` (the context's): each lit bulb part, then each reflector's glow
    toward each of its bulbs (``roles.PartTable.bulbs_of``), then each LED lamp's dies."""
    parts = ctx.parts
    bulbs = [i for i, p in enumerate(scene["freeform"]["parts"]) if p["role"] == "bulb"]  # as PartTable numbers them
    out: list[Emit] = []
    for b, part in enumerate(bulbs):
        if parts.bulb_radiance[b].any():
            out.append(lambda n, rng, b=b, part=part: _bulb_photons(ctx, part, b, n, rng))
    for part in np.nonzero(parts.scatter > 0.0)[0]:
        for b in np.nonzero(parts.bulbs_of[part, :len(bulbs)])[0]:
            if parts.bulb_radiance[b].any():
                out.append(lambda n, rng, b=int(b), part=int(part): _glow_photons(ctx, part, b, n, rng))
    for lamp in [] if ctx.dies is None else ctx.dies.lit:
        if ctx.dies.lamps.led_radiance[lamp].any():
            out.append(lambda n, rng, lamp=lamp: _die_photons(ctx, lamp, n, rng))
    return out


def _die_photons(ctx: _Context, lamp: int, n: int, rng: np.random.Generator) -> tuple[MeshRays, np.ndarray]:
    o, d, flux = ctx.dies.photons(lamp, n, rng)
    return _rays(ctx, -1, np.full(n, -1, np.int64), o, d, P.LED), flux


def _points(ctx: _Context, part: int, n: int, rng: np.random.Generator
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """(triangles, barycentric uv, points, the mesh's area in m²) of ``n`` uniform points of a part."""
    g = ctx.geometry
    index = np.nonzero(g.part == part)[0]
    c = g.corners(index)
    area = 0.5 * np.linalg.norm(np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0]), axis=1)
    pick = rng.choice(len(index), size=n, p=area / area.sum())
    root, w = np.sqrt(rng.uniform(0.0, 1.0, n)), rng.uniform(0.0, 1.0, n)
    uv = np.stack([root * (1.0 - w), root * w], axis=1)  # uniform on a triangle
    corners = c[pick]
    x = corners[:, 0] + uv[:, :1] * (corners[:, 1] - corners[:, 0]) + uv[:, 1:] * (corners[:, 2] - corners[:, 0])
    return index[pick], uv, x, float(area.sum()) * 1e-6


def _rays(ctx: _Context, part: int, tri: np.ndarray, x: np.ndarray, d: np.ndarray, src: int) -> MeshRays:
    n = len(x)
    ones = np.ones((n, ctx.channels))
    return MeshRays(pix=np.arange(n), lamp=np.full(n, part, np.int64), o=x, d=d, k=ones,
                    medium=np.full(n, P.IN_AIR, np.int8), src=np.full(n, src, np.int8), parent=np.zeros(n, np.int8),
                    branch=np.zeros(n, np.int8), seen_reflector=np.full(n, src == P.REFLECTOR),
                    k_s=0.5 * ones, travelled=NOT_DEFERRED, triangle=tri)


def _bulb_photons(ctx: _Context, part: int, bulb: int, n: int, rng: np.random.Generator
                  ) -> tuple[MeshRays, np.ndarray]:
    tri, _uv, x, area = _points(ctx, part, n, rng)
    normal = ctx.geometry.normal[tri]
    outward = np.where((optics.dot(normal, x - ctx.parts.bulb_center[bulb]) < 0.0)[:, None], -normal, normal)
    flux = math.pi * area * ctx.parts.bulb_radiance[bulb] / n  # π L A / N per band
    return _rays(ctx, part, tri, x, cosine_directions(outward, rng), P.BULB), np.broadcast_to(flux, (n, ctx.channels))


def _glow_photons(ctx: _Context, part: int, bulb: int, n: int, rng: np.random.Generator
                  ) -> tuple[MeshRays, np.ndarray]:
    parts = ctx.parts
    tri, uv, x, area = _points(ctx, part, n, rng)
    normal = shading_normal(ctx.geometry, tri, uv)
    gap = parts.bulb_center[bulb] - x
    to_bulb = optics.normalize(gap)
    facing = np.where((optics.dot(normal, to_bulb) < 0.0)[:, None], -normal, normal)
    d = cosine_directions(facing, rng)
    lobe = optics.blinn(facing, d, to_bulb, parts.scatter[part], parts.shininess[part])
    lit = lobe * sphere_irradiance(gap, parts.bulb_radius[bulb], facing, to_bulb)
    radiance = parts.glow_tint[part] * parts.bulb_radiance[bulb]  # ρ(λ) L_b(λ)
    return _rays(ctx, part, tri, x, d, P.REFLECTOR), (math.pi * area / n) * lit[:, None] * radiance


def trace(ctx: _Context, rays: MeshRays) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Follow light ``rays`` through the meshes until absorbed, ended or out: the source sample
    (``pix``), direction and attenuation (per band) of every branch that leaves the lamp."""
    out_pix, out_d, out_k = [], [], []
    band = Band(int(rays.pix.max()) + 1 if len(rays) else 0, ctx)  # the walk's passes: not used
    for _depth in range(ctx.max_depth):
        if not len(rays):
            break
        t, tri, _uv = nearest(ctx.geometry, ctx.embree, rays.o, rays.d, rays.triangle)
        on_die = die_hits(ctx, rays, t, tri)[0]
        tri[on_die] = -2  # absorbed by an LED die: neither out nor on
        gone = np.nonzero((tri == -1) & (rays.medium == P.IN_AIR))[0]
        out_pix.append(rays.pix[gone])
        out_d.append(rays.d[gone])
        out_k.append(rays.k[gone])
        rays = _step(ctx, band, rays.take(np.nonzero(tri >= 0)[0]), first=False)
    if not out_pix:
        return np.zeros(0, int), np.zeros((0, 3)), np.zeros((0, ctx.channels))
    return np.concatenate(out_pix), np.concatenate(out_d), np.concatenate(out_k)


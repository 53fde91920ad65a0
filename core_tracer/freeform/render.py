"""The paper's model on triangle meshes: the engine's wavefront (``raytrace.engine``) over Embree
queries, in world space.

The same improved ray tracing as the parametric lamps (docs/model.md §5), on the same engine: bands,
threads, samples, rays and the Fresnel split are the engine's. What differs is how a ray finds its
surface (``hits``: Embree's nearest triangle) and which part, and so which role, a hit belongs to
(``roles``): the reflector's constant on the first hit and Blinn's scatter toward its bulbs on
every hit (eq. 3); bulb, socket and side wall end a path; bodies are shaded by eq. (1); absorption
over the path length inside a lens (eq. 2). Where a lens is entered from outside through its outer
face (①), the reflected branch is the lens surface's own eq. (1) times the Fresnel reflectance, as
for the parametric lens.

Surroundings, sun and phantom light are the parametric tracer's (``raytrace.environment``,
``raytrace.sunlight``; docs/model.md, "Free-form designs"): rays leaving into nothing see the environment,
① also mirrors it, bodies and ① are lit by the sun and the environment's irradiance, and a
reflector hit whose line to the sun passes a lens and nothing opaque but bulbs and sockets gets the
sun's scatter through that lens's flat plate of its mean thickness (``mean_thickness``).
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..raytrace import optics, pixel_filter, sunlight
from ..raytrace import paths as P
from ..raytrace.camera import Camera, make_camera
from ..raytrace.engine.context import MAX_DEPTH
from ..raytrace.engine.rays import (
    BACKGROUND_PASS,
    BODY_PASS,
    BULB_PASS,
    BY_PASS,
    LENS_SURFACE,
    NOT_DEFERRED,
    REFLECTOR_CONSTANT,
    REFLECTOR_SCATTER,
    SIDE_WALL_PASS,
    SOCKET_PASS,
    UNPOLARISED,
    Band,
    Rays,
    alive,
    concat,
)
from ..raytrace.engine.render import Film, RenderResult
from ..raytrace.engine.schedule import BandImage, band_rows, never, traced_bands
from ..raytrace.engine.surfaces import sphere_irradiance, split_at_face
from ..raytrace.lighting import Lighting
from .cache import GeometryCache
from .embree import EmbreeScene
from .geometry import BODY, Geometry
from .hits import hit_point, nearest, on_side, shading_normal, surface_hits, toward
from .leds import Dies
from .meshes import MeshData
from .roles import PartTable

__all__ = ["NOT_IN_TABLE", "TO_BODY", "render_passes", "surface_hits"]

EYE = BODY + 1  # the source "surface" of an eye ray
# a class beyond Table 1 and its continuations (the prism plate's ⑬-⑲, the guide's ⑳-㉒): a segment that reaches a
# body (housing) and ends there
TO_BODY = P.LAST_CLASS + 1
NOT_IN_TABLE = 0  # a segment meshes allow and the paper's lamp does not (docs/model.md, "Free-form")
SUN_PASSES = 16  # surfaces a phantom-light ray toward the sun may pass through (lens faces, bulbs, sockets)


def _class_table() -> np.ndarray:
    """CLASS[medium, source surface, hit surface]: Table 1's classes (paths.CLASS_OF) for the
    surfaces the roles give, plus the segments that only meshes have."""
    table = np.zeros((2, EYE + 1, BODY + 1), np.int8)
    lens_and_air = P.CLASS_OF[[P.IN_LENS, P.IN_AIR]]  # meshes have no prism plate medium
    table[:, :lens_and_air.shape[1], :lens_and_air.shape[2]] = lens_and_air
    for src in (P.OUTER, P.CUT, P.REFLECTOR, EYE):
        table[P.IN_AIR, src, BODY] = TO_BODY
        table[P.IN_AIR, src, P.NOTHING] = P.LENS_OUTER_TO_OUTSIDE if src == P.OUTER else NOT_IN_TABLE
    table[P.IN_AIR, EYE, P.OUTER] = P.OUTSIDE_TO_LENS
    table[P.IN_AIR, P.OUTER, P.OUTER] = P.OUTSIDE_TO_LENS  # out of one lens and into another
    table[P.IN_AIR, P.REFLECTOR, P.OUTER] = P.REFLECTOR_TO_CUT  # no cut between them: the lens seen directly
    return table


CLASS = _class_table()


@dataclass
class MeshRays(Rays):
    """The engine's rays in a free-form design's world space: ``lamp`` is the part whose values
    they take (the lens they travel in, the surface they left), ``src`` may be ``EYE``, and each
    also knows the triangle its segment starts on."""

    triangle: np.ndarray  # -1 for an eye ray


class _Context(Lighting):
    """Everything constant during one render of a free-form design."""

    planes = BY_PASS  # its bands accumulate the passes (``rays.Band``)
    edge_samples = 0  # edge samples follow the parametric walk's main branches (``engine.edges``): none on meshes

    def __init__(self, scene: dict, camera: Camera, geometry: Geometry, embree: EmbreeScene, samples: int,
                 filter_name: str, record: bool, bands: int | None = None):
        super().__init__(scene, bands)  # the surroundings, the sun and the light model as the parametric tracer's
        self.camera, self.geometry, self.embree = camera, geometry, embree
        self.samples, self.filter_name, self.record = samples, filter_name, record
        self.adaptive_threshold = 0.0  # every sample of every pixel
        self.walker = _MeshWalk()  # the engine's rays find the meshes' surfaces through Embree
        self.max_depth = MAX_DEPTH  # meshes hold no light guide (``walk.depth_limit``)
        self.box_lo = self.box_hi = self.window = None  # no body's box: every eye ray is traced
        self.parts = PartTable(scene, geometry, self.photometric)
        self.dies = Dies.of(scene, self.photometric)  # the LED lamps' dies, found beside the meshes (``leds``)
        self.sun_transmit = sunlight.plate_transmittance(self.sun, self.parts.ior, self.parts.absorption,
                                                         mean_thickness(geometry, len(self.parts.ior)))
        self.phantom = scene["light"].get("phantom", False) and bool(self.sun_transmit.any())


def mean_thickness(g: Geometry, parts: int) -> np.ndarray:
    """Each part's mean thickness seen from the front (mm; 0 for a part with no outer face): its
    volume over the area of its outer face, the flat plate the sun's transmittance takes
    (``sunlight``, as the parametric lens's t + h / 2)."""
    c = g.vertices[g.triangles]
    volume = np.einsum("ij,ij->i", c[:, 0], np.cross(c[:, 1], c[:, 2])) / 6.0  # divergence theorem
    area = 0.5 * np.linalg.norm(np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0]), axis=1)
    volumes = np.bincount(g.part, weights=volume, minlength=parts)
    outer = np.bincount(g.part, weights=np.where(g.surface == P.OUTER, area, 0.0), minlength=parts)
    return np.where(outer > 0.0, volumes / np.where(outer > 0.0, outer, 1.0), 0.0)


def render_passes(scene: dict, meshes: dict[str, MeshData], width: int | None = None, height: int | None = None,
                  *, progress: Callable[[float], None] | None = None,
                  should_stop: Callable[[], bool] | None = None, samples: int | None = None,
                  geometry_cache: GeometryCache | None = None,
                  on_rows: Callable[[int, int, np.ndarray], None] | None = None,
                  on_band: Callable[[int, int, np.ndarray, dict[str, np.ndarray]], None] | None = None,
                  threads: int | None = None,
                  record_transitions: bool = False,
                  filter_name: str = pixel_filter.DEFAULT_FILTER, world_seen: bool = True,
                  bands: int | None = None) -> RenderResult:
    """Render a free-form design (a normalised scene with a ``freeform`` section and its meshes by
    name): the image and the contribution passes, as ``raytrace.engine.render_passes``.

    ``geometry_cache`` keeps the checked geometry and Embree scene between calls (built again only
    when the meshes or roles change); ``stats["build_seconds"]`` is the build time of this call
    (0 when reused). ``on_rows(row_start, row_stop, rows)`` and ``on_band(row_start, row_stop, rows,
    pass_rows)`` are called from the calling thread as bands finish, as in the parametric tracer;
    ``world_seen=False`` leaves out what eye rays that miss everything see (a transparent film).
    A photometric scene is traced on ``bands`` wavelength bands, its image and passes CIE XYZ in cd/m²,
    as the parametric tracer's (``stats["light_model"]``).
    Raises ``SceneError`` for a bad mesh or role, ``RenderCancelled`` when ``should_stop()`` (polled
    between bands) says so."""
    start = time.perf_counter()
    cache = geometry_cache if geometry_cache is not None else GeometryCache()
    geometry, embree, built = cache.get(scene, meshes)
    build_seconds = time.perf_counter() - start if built else 0.0
    width = int(width or scene["image"]["width"])
    height = int(height or scene["image"]["height"])
    samples = int(samples or scene["image"].get("samples", 1))
    pixel_filter.filter_support(filter_name)
    ctx = _Context(scene, make_camera(scene["camera"], width, height), geometry, embree, samples, filter_name,
                   record_transitions, bands)
    ctx.world_seen = world_seen
    bands = band_rows(ctx)
    threads = max(1, min(threads or os.cpu_count() or 1, len(bands)))
    film = Film(width, height, True, on_rows, on_band)
    trace_start = time.perf_counter()
    traced = traced_bands(ctx, bands, threads, should_stop or never)
    film.expose(((y0, y1, BandImage.of(band, True)) for y0, y1, band in traced), len(bands), progress)
    result = film.result(samples, time.perf_counter() - start)
    result.stats["trace_seconds"] = time.perf_counter() - trace_start
    result.stats["build_seconds"] = build_seconds
    result.stats["triangles"] = len(geometry.triangles)
    result.stats["light_model"] = "paper" if ctx.photometric is None else "photometric"
    if ctx.photometric is not None:
        result.stats["bands"] = ctx.channels
        result.stats["band_edges_nm"] = ctx.photometric.bands.edges_nm.tolist()
    return result


class _MeshWalk:
    """The engine's walk (``raytrace.engine.walk.Walker``) through a free-form design's meshes."""

    @staticmethod
    def first_hits(ctx: _Context, band: Band, o: np.ndarray, d: np.ndarray, pix: np.ndarray) -> MeshRays:
        """The eye rays ``o, d`` of slots ``pix`` to their first surface, and the rays that go on."""
        n = len(o)
        # photometric: every column of k a band, unpolarised light half s-polarised (``Rays.k_s``)
        rays = MeshRays(pix=pix, lamp=np.full(n, -1, np.int64), o=o, d=d, k=np.ones((n, ctx.channels)),
                        medium=np.full(n, P.IN_AIR, np.int8), src=np.full(n, EYE, np.int8),
                        parent=np.zeros(n, np.int8), branch=np.zeros(n, np.int8), seen_reflector=np.zeros(n, bool),
                        k_s=UNPOLARISED if ctx.photometric is None else np.full((n, ctx.channels), 0.5),
                        travelled=NOT_DEFERRED, triangle=np.full(n, -1, np.int64))
        return _step(ctx, band, rays, first=True)

    @staticmethod
    def step(ctx: _Context, band: Band, rays: MeshRays) -> MeshRays:
        return _step(ctx, band, rays, first=False)


def _spawn(rays: MeshRays, sel: np.ndarray, o: np.ndarray, d: np.ndarray, k: np.ndarray, k_s: np.ndarray,
           part: np.ndarray, medium: np.ndarray, tri: np.ndarray, src: np.ndarray, cls: np.ndarray, branch: int,
           seen: np.ndarray) -> MeshRays:
    """Child rays of the rays ``sel`` (indices into the generation) that stay above the cut-off."""
    go = np.nonzero(alive(k))[0]
    return MeshRays(pix=rays.pix[sel][go], lamp=part[go], o=o[go], d=d[go], k=k[go], medium=medium[go], src=src[go],
                    parent=cls[go], branch=np.full(len(go), branch, np.int8), seen_reflector=seen[go],
                    k_s=k_s[go], travelled=NOT_DEFERRED, triangle=tri[go])


def _step(ctx: _Context, band: Band, rays: MeshRays, first: bool) -> MeshRays:
    """One generation: find each segment's end, add its luminance, spawn the children."""
    g, parts = ctx.geometry, ctx.parts
    t, tri, uv = nearest(g, ctx.embree, rays.o, rays.d, rays.triangle)
    on_die, die_lamp, t_die = die_hits(ctx, rays, t, tri)
    if len(on_die):
        tri = tri.copy()
        tri[on_die] = -1  # the ray ends on the die, before any triangle
    hit_any = tri >= 0
    surface = np.where(hit_any, g.surface[np.maximum(tri, 0)], P.NOTHING).astype(np.int8)
    surface[on_die] = P.LED
    cls = CLASS[rays.medium, rays.src, surface]
    if not first:
        band.note(rays.pix, rays.parent, rays.branch, cls)

    hits = np.nonzero(tri >= 0)[0]  # the rays that meet a triangle
    tri_hit = tri[hits]
    t_hit, point = hit_point(g, rays.o[hits], rays.d[hits], t[hits], tri_hit)
    t = t.copy()
    t[hits] = t_hit  # from the segment's true start, in double precision
    normal = shading_normal(g, tri_hit, uv[hits])

    k, k_s = rays.k, rays.k_s
    inside = np.nonzero(rays.medium == P.IN_LENS)[0]
    if len(inside):  # eq. (2) over the path inside the lens (photometric: per band, Beer-Lambert)
        # Applied at once, not deferred to the leaves as the parametric lamp's (``spectral.Throughput``):
        # a ray here may cross several lenses of different filters.
        k = k.copy()
        length = np.where(np.isfinite(t[inside]), t[inside], 0.0)
        transmittance = optics.absorption(parts.absorption[rays.lamp[inside]], length)
        k[inside] *= transmittance
        if k_s is not UNPOLARISED:
            k_s = k_s.copy()
            k_s[inside] *= transmittance

    if len(on_die):  # LED dies end the path with their luminance toward the eye, k · L(θ, φ) (``leds``)
        at = rays.o[on_die] + t_die[:, None] * rays.d[on_die]
        band.add(BULB_PASS, rays.pix[on_die], k[on_die] * ctx.dies.emitted(die_lamp, rays.d[on_die], at))
        hit_any[on_die] = True  # not a miss: nothing of the surroundings behind a die
    miss = np.nonzero(~hit_any)[0]
    if not (first and not ctx.world_seen) and ctx.background_seen and len(miss):
        # Out of the lamp: the surroundings along the ray (through an outer face, ⑩: refracted)
        band.add(BACKGROUND_PASS, rays.pix[miss], k[miss] * ctx.sky(rays.d[miss]))

    # Per ray that meets a surface: its part (the role's values), the surface, k and direction.
    part_hit = g.part[tri_hit]
    surface_hit = surface[hits]
    k_hit = k[hits]
    k_s_hit = k_s[hits]
    d_hit = rays.d[hits]

    for sid, pass_id in ((P.WALL, SIDE_WALL_PASS), (P.BULB, BULB_PASS), (P.SOCKET, SOCKET_PASS)):
        met = surface_hit == sid
        if met.any():
            band.add(pass_id, rays.pix[hits[met]], k_hit[met] * parts.color[part_hit[met]])

    met = np.nonzero(surface_hit == BODY)[0]
    if len(met):  # eq. (1)
        facing = toward(normal[met], d_hit[met])
        body = part_hit[met]
        band.add(BODY_PASS, rays.pix[hits[met]], k_hit[met] * ctx.shade(facing, -d_hit[met], parts.color[body],
                                                                         parts.specular[body], parts.shininess[body]))

    children: list[MeshRays] = []
    met = np.nonzero(surface_hit == P.REFLECTOR)[0]
    if len(met):
        children.append(_reflector(ctx, band, rays, hits[met], k_hit[met], k_s_hit[met], point[met], normal[met],
                                   tri_hit[met], part_hit[met], cls[hits[met]]))
    met = np.nonzero((surface_hit == P.OUTER) | (surface_hit == P.CUT))[0]
    if len(met):
        children.extend(_dielectric(ctx, band, rays, hits[met], k_hit[met], k_s_hit[met], point[met], normal[met],
                                    tri_hit[met], part_hit[met], cls[hits[met]], surface_hit[met]))
    if not children:
        return rays.take(np.zeros(0, dtype=np.int64))
    return concat(children) if len(children) > 1 else children[0]


def die_hits(ctx: _Context, rays: MeshRays, t: np.ndarray, tri: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The rays (indices) that meet an LED die before any triangle (only rays in air can), their
    dies' lamps and their distances to them; empty when the design has no LED lamp."""
    if ctx.dies is None:
        return np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0)
    air = np.nonzero(rays.medium == P.IN_AIR)[0]
    t_die, lamp = ctx.dies.hit(rays.o[air], rays.d[air])
    nearer = t_die < np.where(tri[air] >= 0, t[air], np.inf)
    return air[nearer], lamp[nearer], t_die[nearer]


def _reflector(ctx: _Context, band: Band, rays: MeshRays, met: np.ndarray, k: np.ndarray, k_s: np.ndarray,
               hit: np.ndarray, normal: np.ndarray, tri: np.ndarray, part: np.ndarray, cls: np.ndarray) -> MeshRays:
    """A reflector hit (③ ④): the first-hit constant, Blinn's scatter toward its bulbs (eq. 3),
    then the mirror ray (k × reflectance) where it stays above the cut-off. Photometric: no
    constant (0), the glow tinted by the finish and spread over each bulb's irradiance (its sphere
    of the mesh's area, ``surfaces.sphere_irradiance``), the mirror (1 - s) ρ(λ), as the parametric
    reflector's (``surfaces.at_reflector``)."""
    parts = ctx.parts
    d = rays.d[met]
    pix = rays.pix[met]
    first = ~rays.seen_reflector[met]
    band.add(REFLECTOR_CONSTANT, pix[first], k[first] * parts.color[part[first]])
    facing = toward(normal, d)
    for bulb in range(len(parts.bulb_center)):
        sel = np.nonzero(parts.bulbs_of[part, bulb])[0]
        if len(sel) == 0:
            continue
        gap = parts.bulb_center[bulb] - hit[sel]
        to_bulb = optics.normalize(gap)
        scatter = optics.blinn(facing[sel], -d[sel], to_bulb, parts.scatter[part[sel]], parts.shininess[part[sel]])
        if ctx.photometric is not None:
            scatter = scatter * sphere_irradiance(gap, parts.bulb_radius[bulb], facing[sel], to_bulb)
        glow = k[sel] * parts.glow_tint[part[sel]]  # exactly k in the paper mode (a tint of ones)
        band.add(REFLECTOR_SCATTER, pix[sel], glow * scatter[:, None] * parts.bulb_radiance[bulb])
    if ctx.phantom:  # the sun's light scattered back out of the lamp (sunlight.phantom)
        lens = _lens_toward_sun(ctx, hit, tri, facing)
        lit = lens >= 0
        band.add(REFLECTOR_SCATTER, pix, k * parts.glow_tint[part] * sunlight.scattered(ctx.sun, facing, -d,
                                                                                      parts.scatter[part],
                                                                parts.shininess[part],
                                                                ctx.sun_transmit[np.maximum(lens, 0)], lit))
    mirrored = k * parts.mirror[part]
    mirrored_s = k_s if k_s is UNPOLARISED else k_s * parts.mirror[part]
    count = len(met)
    geometric = ctx.geometry.normal[tri]
    mirror = on_side(optics.reflect(d, facing), d, geometric,
                     lambda sel: optics.reflect(d[sel], toward(geometric[sel], d[sel])), same=False)
    return _spawn(rays, met, hit, mirror, mirrored, mirrored_s, part, np.full(count, P.IN_AIR, np.int8), tri,
                  np.full(count, P.REFLECTOR, np.int8), cls, P.REFLECTED, np.ones(count, bool))


def _lens_toward_sun(ctx: _Context, p: np.ndarray, tri: np.ndarray, n: np.ndarray) -> np.ndarray:
    """The lens part (-1 for none) through which the line from reflector points ``p`` (on
    triangles ``tri``, normal ``n`` toward the viewer's side) toward the sun leaves the lamp: the
    first lens the line meets, where it then reaches the open sky through lenses, bulbs and sockets
    only (their shadows are not modelled, as in the parametric lamp); any other surface on the
    way (a reflector, a side wall, a body) shades the point."""
    g = ctx.geometry
    lens = np.full(len(p), -1, np.int64)
    todo = np.nonzero(optics.dot(n, ctx.sun.direction[None, :]) > 0.0)[0]  # the sun on the lit side
    d = np.broadcast_to(ctx.sun.direction, (len(todo), 3))
    o = p[todo] + g.epsilon * n[todo]
    skip = tri[todo]
    for _ in range(SUN_PASSES):
        if len(todo) == 0:
            break
        t, hit, _uv = ctx.embree.nearest(o, d)
        surface = np.where(hit >= 0, g.surface[np.maximum(hit, 0)], P.NOTHING)
        at_lens = (surface == P.OUTER) | (surface == P.CUT)
        first_lens = at_lens & (lens[todo] < 0)
        lens[todo[first_lens]] = g.part[hit[first_lens]]
        through = (at_lens | (surface == P.BULB) | (surface == P.SOCKET) | (hit == skip)) & (hit >= 0)
        lens[todo[(hit >= 0) & ~through]] = -1  # in the shade of an opaque surface
        o = o[through] + (t[through] + g.epsilon)[:, None] * d[through]
        todo, d, skip = todo[through], d[through], hit[through]
    return lens


def _dielectric(ctx: _Context, band: Band, rays: MeshRays, met: np.ndarray, k: np.ndarray, k_s: np.ndarray,
                hit: np.ndarray, normal: np.ndarray, tri: np.ndarray, part: np.ndarray, cls: np.ndarray,
                surface: np.ndarray) -> list[MeshRays]:
    """A lens surface hit from either side: the engine's Fresnel split (TIR gives R = 1; photometric:
    per band and polarisation). Entering through the outer face from the air (①), the reflected
    branch is the lens surface's eq. (1) × R."""
    parts, g = ctx.parts, ctx.geometry
    d = rays.d[met]
    pix, seen = rays.pix[met], rays.seen_reflector[met]
    geometric = g.normal[tri]
    entering = optics.dot(d, geometric) < 0.0  # the side test: by the geometric (outward) normal
    facing = np.where(entering[:, None], normal, -normal)  # shading normal toward the incident side
    geometric_facing = np.where(entering[:, None], geometric, -geometric)
    # Where the smooth normal faces away from the ray (a grazing ray at a coarse silhouette), the
    # face's own normal decides: the ray does meet the face from the incident side.
    away = optics.dot(d, facing) >= 0.0
    if away.any():
        facing[away] = geometric_facing[away]
    split = split_at_face(k, k_s, d, facing, ~entering, parts.ior[part],
                          None if parts.band_ior is None else parts.band_ior[part])
    src = surface.astype(np.int8)
    medium_before = np.where(entering, P.IN_AIR, P.IN_LENS).astype(np.int8)
    medium_after = np.where(entering, P.IN_LENS, P.IN_AIR).astype(np.int8)
    out = []

    outer_from_air = entering & (surface == P.OUTER)
    s = np.nonzero(outer_from_air)[0]
    if len(s):  # ①: the surface's own eq. (1) in the reflected direction, no further tracing
        ps = part[s]
        # eq. (1) with the lens's colour, and the surroundings it mirrors (``Lighting.lens_surface``)
        shade = ctx.lens_surface(facing[s], d[s], parts.color[ps], parts.specular[ps], parts.shininess[ps])
        band.add(LENS_SURFACE, pix[s], split.reflected[s] * shade)
        if ctx.background_seen and ctx.environment is None:
            band.add(BACKGROUND_PASS, pix[s], split.reflected[s] * ctx.background)
        band.note(pix[s], cls[s], np.full(len(s), P.REFLECTED), np.full(len(s), P.LENS_OUTER_TO_OUTSIDE))
    mirrored = np.nonzero(~outer_from_air)[0]
    d_r, facing_r, geometric_r = d[mirrored], facing[mirrored], geometric_facing[mirrored]
    mirror = on_side(optics.reflect(d_r, facing_r), d_r, geometric[mirrored],
                     lambda sel: optics.reflect(d_r[sel], geometric_r[sel]), same=False)
    out.append(_spawn(rays, met[mirrored], hit[mirrored], mirror, split.reflected[mirrored],
                      split.reflected_s[mirrored], part[mirrored], medium_before[mirrored], tri[mirrored],
                      src[mirrored], cls[mirrored], P.REFLECTED, seen[mirrored]))

    through = np.nonzero(split.partial)[0]  # no total internal reflection
    d_t, facing_t, geometric_t = d[through], facing[through], geometric_facing[through]
    eta = split.eta[through]
    bent = on_side(optics.refract(d_t, facing_t, eta, split.cos_i[through]), d_t, geometric[through],
                   lambda sel: optics.refract(d_t[sel], geometric_t[sel], eta[sel]), same=True)
    out.append(_spawn(rays, met[through], hit[through], bent, split.transmitted[through],
                      split.transmitted_s[through], part[through], medium_after[through], tri[through],
                      src[through], cls[through], P.TRANSMITTED, seen[through]))
    return out

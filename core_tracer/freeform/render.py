"""The paper's model on triangle meshes: a world-space numpy wavefront over Embree queries.

The same improved ray tracing as ``raytrace.tracer`` (docs/model.md §5): rays from the eye branch at
every lens surface into a reflected and a transmitted ray (Fresnel, Snell, total internal
reflection), each carrying its accumulated attenuation k; luminance is added as k × the value
found; absorption over the path length inside a lens (eq. 2); the reflector's constant on the
first hit and Blinn's scatter toward its bulbs on every hit (eq. 3); bulb, socket and side wall
end a path; bodies are shaded by eq. (1). Branches below 0.1 % are dropped; ``MAX_DEPTH`` caps a
branch. Where a lens is entered from outside through its outer face (①), the reflected branch
is the lens surface's own eq. (1) times the Fresnel reflectance, as for the parametric lens.

Surroundings, sun and phantom light are the parametric tracer's (``raytrace.environment``,
``raytrace.sunlight``; README, "Free-form designs"): rays leaving into nothing see the environment,
① also mirrors it, bodies and ① are lit by the sun and the environment's irradiance, and a
reflector hit whose line to the sun passes a lens and nothing opaque but bulbs and sockets gets the
sun's scatter through that lens's flat plate of its mean thickness (``mean_thickness``).

Normals: the side a ray meets a lens from is told by the triangle's geometric normal (outward);
Fresnel, Snell, mirror and shading use the normal interpolated from the corner normals (smooth
shading), turned toward the incident side.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from ..raytrace import optics, pixel_filter, sunlight
from ..raytrace import paths as P
from ..raytrace.camera import Camera, eye_rays, make_camera
from ..raytrace.lighting import Lighting
from ..raytrace.tracer import (
    CUTOFF,
    MAX_DEPTH,
    PASS_NAMES,
    TILE_RAYS,
    RenderCancelled,
    RenderResult,
    add_to_pass,
    sample_groups,
)
from .embree import EmbreeScene
from .geometry import BODY, Geometry, GeometryCache
from .meshes import MeshData
from .roles import PartTable

(LENS_SURFACE, BULB_PASS, REFLECTOR_CONSTANT, REFLECTOR_SCATTER, SOCKET_PASS, SIDE_WALL_PASS, BODY_PASS,
 BACKGROUND_PASS) = range(len(PASS_NAMES))

EYE = BODY + 1  # the source "surface" of an eye ray
TO_BODY = 20  # a class beyond Table 1 and the prism plate's ⑬-⑲: a segment that reaches a body (housing) and ends there
NOT_IN_TABLE = 0  # a segment meshes allow and the paper's lamp does not (README, "Free-form")
SELF_HIT_RETRIES = 2
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
class _Rays:
    pix: np.ndarray
    o: np.ndarray
    d: np.ndarray
    k: np.ndarray
    lens: np.ndarray  # part index of the lens the ray travels in, -1 in the air
    src_tri: np.ndarray  # triangle the segment starts on, -1 for an eye ray
    src: np.ndarray  # surface id the segment starts on (EYE for an eye ray)
    parent: np.ndarray
    branch: np.ndarray
    seen_reflector: np.ndarray

    def __len__(self) -> int:
        return len(self.pix)


_FIELDS = ("pix", "o", "d", "k", "lens", "src_tri", "src", "parent", "branch", "seen_reflector")


def _concat(parts: list[_Rays]) -> _Rays:
    return _Rays(*(np.concatenate([getattr(p, f) for p in parts]) for f in _FIELDS))


class _Context(Lighting):
    def __init__(self, scene: dict, camera: Camera, geometry: Geometry, embree: EmbreeScene, samples: int,
                 filter_name: str, record: bool):
        super().__init__(scene)  # the surroundings and the sun as the parametric tracer's
        self.camera, self.geometry, self.embree = camera, geometry, embree
        self.samples, self.filter_name, self.record = samples, filter_name, record
        self.parts = PartTable(scene, geometry)
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


class _Band:
    """The passes of one band of rays and its statistics (as the parametric tracer's)."""

    def __init__(self, n: int, record: bool):
        self.acc = np.zeros((len(PASS_NAMES), n, 3))
        self.segments = 0
        self.max_depth = 0
        self.transitions: set[tuple[int, int, int]] = set()
        self.record = record

    def add(self, pass_id: int, pix: np.ndarray, values: np.ndarray) -> None:
        add_to_pass(self.acc[pass_id], pix, values)

    def note(self, parent: np.ndarray, branch: np.ndarray | int, child: np.ndarray | int) -> None:
        if not self.record or len(parent) == 0:
            return
        branch = np.broadcast_to(branch, parent.shape)
        child = np.broadcast_to(child, parent.shape)
        codes = np.unique(parent.astype(np.int64) * 10000 + branch.astype(np.int64) * 100 + child)
        self.transitions.update((int(c) // 10000, (int(c) // 100) % 100, int(c) % 100) for c in codes)


def render_passes(scene: dict, meshes: dict[str, MeshData], width: int | None = None, height: int | None = None,
                  *, progress: Callable[[float], None] | None = None,
                  should_stop: Callable[[], bool] | None = None, samples: int | None = None,
                  geometry_cache: GeometryCache | None = None,
                  on_rows: Callable[[int, int, np.ndarray], None] | None = None,
                  on_band: Callable[[int, int, np.ndarray, dict[str, np.ndarray]], None] | None = None,
                  threads: int | None = None,
                  record_transitions: bool = False,
                  filter_name: str = pixel_filter.DEFAULT_FILTER, world_seen: bool = True) -> RenderResult:
    """Render a free-form design (a normalised scene with a ``freeform`` section and its meshes by
    name): the image and the contribution passes, as ``raytrace.tracer.render_passes``.

    ``geometry_cache`` keeps the checked geometry and Embree scene between calls (built again only
    when the meshes or roles change); ``stats["build_seconds"]`` is the build time of this call
    (0 when reused). ``on_rows(row_start, row_stop, rows)`` and ``on_band(row_start, row_stop, rows,
    pass_rows)`` are called from the calling thread as bands finish, as in the parametric tracer;
    ``world_seen=False`` leaves out what eye rays that miss everything see (a transparent film).
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
                   record_transitions)
    ctx.world_seen = world_seen
    should_stop = should_stop or (lambda: False)
    rows_per_band = max(1, TILE_RAYS // (width * samples))
    bands = [(y, min(height, y + rows_per_band)) for y in range(0, height, rows_per_band)]
    threads = max(1, min(threads or os.cpu_count() or 1, len(bands)))
    passes = np.zeros((len(PASS_NAMES), height, width, 3), np.float32)
    stats = {"segments": 0, "max_depth": 0, "transitions": set()}
    trace_start = time.perf_counter()
    with ThreadPoolExecutor(max_workers=threads) as pool:
        pending = list(bands)
        running = []
        done = 0
        try:
            while pending or running:
                while pending and len(running) < threads:
                    if should_stop():
                        raise RenderCancelled("render cancelled")
                    y0, y1 = pending.pop(0)
                    running.append((y0, y1, pool.submit(_trace_band, ctx, y0, y1)))
                y0, y1, future = running.pop(0)
                band = future.result()
                if should_stop():
                    raise RenderCancelled("render cancelled")
                passes[:, y0:y1] = band.acc.reshape(len(PASS_NAMES), y1 - y0, width, 3)
                if on_rows is not None or on_band is not None:
                    rows = passes[:, y0:y1].sum(axis=0)
                    if on_rows is not None:
                        on_rows(y0, y1, rows)
                    if on_band is not None:
                        on_band(y0, y1, rows, {name: passes[i, y0:y1] for i, name in enumerate(PASS_NAMES)})
                stats["segments"] += band.segments
                stats["max_depth"] = max(stats["max_depth"], band.max_depth)
                stats["transitions"] |= band.transitions
                done += 1
                if progress is not None:
                    progress(done / len(bands))
        finally:
            pool.shutdown(wait=True, cancel_futures=True)
    stats["seconds"] = time.perf_counter() - start
    stats["trace_seconds"] = time.perf_counter() - trace_start
    stats["build_seconds"] = build_seconds
    stats["triangles"] = len(geometry.triangles)
    stats["width"], stats["height"], stats["samples"] = width, height, samples
    return RenderResult(passes.sum(axis=0), dict(zip(PASS_NAMES, passes, strict=True)), stats)


def _trace_band(ctx: _Context, y0: int, y1: int) -> _Band:
    cam = ctx.camera
    pixels = np.arange(y0 * cam.width, y1 * cam.width)
    band = _Band(len(pixels), ctx.record)
    if ctx.samples == 1:  # the paper's setting: one ray through each pixel centre
        _trace_rays(ctx, band, *eye_rays(cam, pixels))
        return band
    for count, o, d in sample_groups(cam, pixels, ctx.samples, ctx.filter_name):
        group = _Band(len(o), ctx.record)
        _trace_rays(ctx, group, o, d)
        band.acc += group.acc.reshape(len(PASS_NAMES), len(pixels), count, 3).sum(axis=2)
        band.segments += group.segments
        band.max_depth = max(band.max_depth, group.max_depth)
        band.transitions |= group.transitions
    band.acc /= ctx.samples  # the filter placed the samples: the pixel is their mean
    return band


def _trace_rays(ctx: _Context, band: _Band, o: np.ndarray, d: np.ndarray) -> None:
    n = len(o)
    rays = _Rays(pix=np.arange(n), o=o, d=d, k=np.ones((n, 3)), lens=np.full(n, -1, np.int32),
                 src_tri=np.full(n, -1, np.int64), src=np.full(n, EYE, np.int8), parent=np.zeros(n, np.int8),
                 branch=np.zeros(n, np.int8), seen_reflector=np.zeros(n, bool))
    depth = 0
    while len(rays) and depth < MAX_DEPTH:
        band.segments += len(rays)
        rays = _step(ctx, band, rays, depth == 0)
        depth += 1
    band.max_depth = max(band.max_depth, depth)


def _nearest(ctx: _Context, rays: _Rays) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each ray's next triangle (-1 for none), the distance to it and the barycentric (u, v) of
    the hit, never its own triangle: a self-hit is skipped by asking again from just beyond it."""
    g = ctx.geometry
    o = rays.o
    on_surface = np.nonzero(rays.src_tri >= 0)[0]
    if len(on_surface):
        # Query from just off the surface, on the side the ray leaves to; the segment itself
        # starts on the surface (``_hit_point`` measures from there: exact path lengths).
        n = g.normal[rays.src_tri[on_surface]]
        side = np.where((optics.dot(rays.d[on_surface], n) >= 0.0)[:, None], n, -n)
        o = o.copy()
        o[on_surface] += g.epsilon * side
    t, tri, uv = ctx.embree.nearest(o, rays.d)
    for _ in range(SELF_HIT_RETRIES):
        again = np.nonzero((tri == rays.src_tri) & (tri >= 0))[0]
        if len(again) == 0:
            break
        skip = t[again] + g.epsilon
        t2, tri2, uv2 = ctx.embree.nearest(o[again] + skip[:, None] * rays.d[again], rays.d[again])
        t[again] = t2 + skip
        tri[again] = tri2
        uv[again] = uv2
    return t, tri, uv


def _hit_point(g: Geometry, o: np.ndarray, d: np.ndarray, t: np.ndarray, tri: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray]:
    """The hit in double precision on the triangle's plane (Embree's distance is single precision):
    distance and point."""
    n = g.normal[tri]
    p0 = g.vertices[g.triangles[tri, 0]]
    denom = optics.dot(d, n)
    plane_t = optics.dot(p0 - o, n) / np.where(denom != 0.0, denom, 1.0)
    t = np.where((denom != 0.0) & np.isfinite(plane_t), plane_t, t)
    return t, o + t[:, None] * d


def _shading_normal(g: Geometry, tri: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """The corner normals interpolated at the hit (barycentric ``uv`` of the second and third
    corners), unit, on the geometric normal's side (a smooth normal that disagrees with the face,
    at a silhouette of a coarse mesh, gives way to it)."""
    c = g.corner_normals[tri]
    u, v = uv[:, 0:1], uv[:, 1:2]
    n = (1.0 - u - v) * c[:, 0] + u * c[:, 1] + v * c[:, 2]
    length = np.linalg.norm(n, axis=1)
    geometric = g.normal[tri]
    ok = (length > 1e-12) & (optics.dot(n, geometric) > 0.0)
    n = np.where(ok[:, None], n / np.where(length > 1e-12, length, 1.0)[:, None], geometric)
    return n


def _alive(k: np.ndarray) -> np.ndarray:
    return np.max(k, axis=1) >= CUTOFF


def _spawn(rays: _Rays, sel: np.ndarray, o: np.ndarray, d: np.ndarray, k: np.ndarray, lens: np.ndarray,
           tri: np.ndarray, src: np.ndarray, cls: np.ndarray, branch: int, seen: np.ndarray) -> _Rays:
    """Child rays of the rays ``sel`` (indices into the generation) that stay above the cut-off."""
    go = np.nonzero(_alive(k))[0]
    return _Rays(pix=rays.pix[sel][go], o=o[go], d=d[go], k=k[go], lens=lens[go], src_tri=tri[go], src=src[go],
                 parent=cls[go], branch=np.full(len(go), branch, np.int8), seen_reflector=seen[go])


def _step(ctx: _Context, band: _Band, rays: _Rays, first: bool) -> _Rays:
    """One generation: find each segment's end, add its luminance, spawn the children."""
    g, parts = ctx.geometry, ctx.parts
    t, tri, uv = _nearest(ctx, rays)
    hit_any = tri >= 0
    surface = np.where(hit_any, g.surface[np.maximum(tri, 0)], P.NOTHING).astype(np.int8)
    medium = np.where(rays.lens >= 0, P.IN_LENS, P.IN_AIR)
    cls = CLASS[medium, rays.src, surface]
    if not first:
        band.note(rays.parent, rays.branch, cls)

    h = np.nonzero(hit_any)[0]
    tri_h = tri[h]
    t_h, p_h = _hit_point(g, rays.o[h], rays.d[h], t[h], tri_h)
    t = t.copy()
    t[h] = t_h  # from the segment's true start, in double precision
    normal = _shading_normal(g, tri_h, uv[h])

    k = rays.k
    inside = np.nonzero(rays.lens >= 0)[0]
    if len(inside):
        k = k.copy()
        length = np.where(np.isfinite(t[inside]), t[inside], 0.0)
        k[inside] *= optics.absorption(parts.absorption[rays.lens[inside]], length)

    miss = np.nonzero(~hit_any)[0]
    if not (first and not ctx.world_seen) and ctx.background_seen and len(miss):
        # Out of the lamp: the surroundings along the ray (through an outer face, ⑩: refracted)
        band.add(BACKGROUND_PASS, rays.pix[miss], k[miss] * ctx.sky(rays.d[miss]))

    part_h = g.part[tri_h]
    surf_h = surface[h]
    k_h = k[h]
    d_h = rays.d[h]

    for sid, pass_id in ((P.WALL, SIDE_WALL_PASS), (P.BULB, BULB_PASS), (P.SOCKET, SOCKET_PASS)):
        m = surf_h == sid
        if m.any():
            band.add(pass_id, rays.pix[h[m]], k_h[m] * parts.color[part_h[m]])

    m = np.nonzero(surf_h == BODY)[0]
    if len(m):
        facing = _toward(normal[m], d_h[m])
        pm = part_h[m]
        band.add(BODY_PASS, rays.pix[h[m]],
                 k_h[m] * ctx.shade(facing, -d_h[m], parts.color[pm], parts.specular[pm], parts.shininess[pm]))

    children: list[_Rays] = []
    m = np.nonzero(surf_h == P.REFLECTOR)[0]
    if len(m):
        children.append(_reflector(ctx, band, rays, h[m], k_h[m], p_h[m], normal[m], tri_h[m], part_h[m],
                                   cls[h[m]]))
    m = np.nonzero((surf_h == P.OUTER) | (surf_h == P.CUT))[0]
    if len(m):
        children.extend(_dielectric(ctx, band, rays, h[m], k_h[m], p_h[m], normal[m], tri_h[m], part_h[m],
                                    cls[h[m]], surf_h[m]))
    if not children:
        return _concat([_Rays(*(getattr(rays, f)[:0] for f in _FIELDS))])
    return _concat(children) if len(children) > 1 else children[0]


def _on_side(new: np.ndarray, d: np.ndarray, geometric: np.ndarray, by_face: Callable[[np.ndarray], np.ndarray],
             same: bool) -> np.ndarray:
    """Child directions ``new`` of rays ``d`` at faces of normal ``geometric``, kept on the side the
    branch belongs to (``same``: on through the face, as a transmitted ray; else back, as a
    reflected one). An interpolated normal can tip a grazing child across the face, which would put
    it on the wrong side of the medium it is said to be in: there ``by_face(selection)``, the same
    law with the face's own normal, decides."""
    want = np.sign(optics.dot(d, geometric)) * (1.0 if same else -1.0)  # the side, along the face normal
    wrong = optics.dot(new, geometric) * want <= 0.0
    if wrong.any():
        sel = np.nonzero(wrong)[0]
        new = new.copy()
        new[sel] = by_face(sel)
        # Grazing (refraction at the critical angle): the face's own law gives a direction in the
        # face's plane, or a rounding off it; tip it just onto the right side.
        still = sel[optics.dot(new[sel], geometric[sel]) * want[sel] <= 1e-9]
        if len(still):
            n = geometric[still]
            along = optics.dot(new[still], n) - 1e-6 * want[still]
            new[still] = optics.normalize(new[still] - along[:, None] * n)
    return new


def _toward(n: np.ndarray, d: np.ndarray) -> np.ndarray:
    """``n`` turned to face the ray's incident side (against ``d``)."""
    return np.where((optics.dot(n, d) > 0.0)[:, None], -n, n)


def _reflector(ctx: _Context, band: _Band, rays: _Rays, m: np.ndarray, k: np.ndarray, p: np.ndarray,
               normal: np.ndarray, tri: np.ndarray, part: np.ndarray, cls: np.ndarray) -> _Rays:
    """A reflector hit (③ ④): the first-hit constant, Blinn's scatter toward its bulbs (eq. 3),
    then the mirror ray (k × reflectance) where it stays above the cut-off."""
    parts = ctx.parts
    d = rays.d[m]
    pix = rays.pix[m]
    first = ~rays.seen_reflector[m]
    band.add(REFLECTOR_CONSTANT, pix[first], k[first] * parts.color[part[first]])
    n = _toward(normal, d)
    for b in range(len(parts.bulb_center)):
        sel = np.nonzero(parts.bulbs_of[part, b])[0]
        if len(sel) == 0:
            continue
        to_bulb = optics.normalize(parts.bulb_center[b] - p[sel])
        scatter = optics.blinn(n[sel], -d[sel], to_bulb, parts.scatter[part[sel]], parts.shininess[part[sel]])
        band.add(REFLECTOR_SCATTER, pix[sel], k[sel] * scatter[:, None] * parts.bulb_intensity[b])
    if ctx.phantom:  # the sun's light scattered back out of the lamp (sunlight.phantom)
        lens = _lens_toward_sun(ctx, p, tri, n)
        lit = lens >= 0
        band.add(REFLECTOR_SCATTER, pix, k * sunlight.scattered(ctx.sun, n, -d, parts.scatter[part],
                                                                parts.shininess[part],
                                                                ctx.sun_transmit[np.maximum(lens, 0)], lit))
    k = k * parts.reflectance[part, None]
    count = len(m)
    mirror = _on_side(optics.reflect(d, n), d, ctx.geometry.normal[tri], lambda sel: optics.reflect(
        d[sel], _toward(ctx.geometry.normal[tri[sel]], d[sel])), same=False)
    return _spawn(rays, m, p, mirror, k, np.full(count, -1, np.int32), tri,
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


def _dielectric(ctx: _Context, band: _Band, rays: _Rays, m: np.ndarray, k: np.ndarray, p: np.ndarray,
                normal: np.ndarray, tri: np.ndarray, part: np.ndarray, cls: np.ndarray,
                surface: np.ndarray) -> list[_Rays]:
    """A lens surface hit from either side: Fresnel split (TIR gives r = 1). Entering through the
    outer face from the air (①), the reflected branch is the lens surface's eq. (1) × r."""
    parts, g = ctx.parts, ctx.geometry
    d = rays.d[m]
    pix, seen = rays.pix[m], rays.seen_reflector[m]
    geometric = g.normal[tri]
    entering = optics.dot(d, geometric) < 0.0  # the side test: by the geometric (outward) normal
    facing = np.where(entering[:, None], normal, -normal)  # shading normal toward the incident side
    geometric_facing = np.where(entering[:, None], geometric, -geometric)
    # Where the smooth normal faces away from the ray (a grazing ray at a coarse silhouette), the
    # face's own normal decides: the ray does meet the face from the incident side.
    away = optics.dot(d, facing) >= 0.0
    if away.any():
        facing[away] = np.where(entering[away, None], geometric[away], -geometric[away])
    ior = parts.ior[part]
    n1 = np.where(entering, 1.0, ior)
    n2 = np.where(entering, ior, 1.0)
    cos_i = np.clip(-optics.dot(d, facing), 0.0, 1.0)
    r = optics.fresnel_reflectance(cos_i, n1, n2)
    src = surface.astype(np.int8)
    out = []

    outer_from_air = entering & (surface == P.OUTER)
    s = np.nonzero(outer_from_air)[0]
    if len(s):  # ①: the surface's own eq. (1) in the reflected direction, no further tracing
        ps = part[s]
        shade = ctx.shade(facing[s], -d[s], parts.color[ps], parts.specular[ps], parts.shininess[ps])
        if ctx.environment is not None:  # the outer face mirrors the surroundings
            shade = shade + ctx.sky(optics.reflect(d[s], facing[s]))
        band.add(LENS_SURFACE, pix[s], k[s] * r[s, None] * shade)
        if ctx.background_seen and ctx.environment is None:
            band.add(BACKGROUND_PASS, pix[s], k[s] * r[s, None] * ctx.background)
        band.note(cls[s], P.REFLECTED, P.LENS_OUTER_TO_OUTSIDE)
    traced = np.nonzero(~outer_from_air)[0]
    k_r = k[traced] * r[traced, None]
    out.append(_spawn(rays, m[traced], p[traced],
                      _on_side(optics.reflect(d[traced], facing[traced]), d[traced], geometric[traced],
                               lambda sel: optics.reflect(d[traced][sel], geometric_facing[traced][sel]),
                               same=False), k_r,
                      np.where(entering[traced], -1, part[traced]).astype(np.int32), tri[traced], src[traced],
                      cls[traced], P.REFLECTED, seen[traced]))

    tc = np.nonzero(r < 1.0)[0]
    k_t = k[tc] * (1.0 - r[tc, None])
    eta = n1[tc] / n2[tc]
    out.append(_spawn(rays, m[tc], p[tc],
                      _on_side(optics.refract(d[tc], facing[tc], eta), d[tc], geometric[tc],
                               lambda sel: optics.refract(d[tc][sel], geometric_facing[tc][sel], eta[sel]),
                               same=True),
                      k_t, np.where(entering[tc], part[tc], -1).astype(np.int32), tri[tc], src[tc], cls[tc],
                      P.TRANSMITTED, seen[tc]))
    return out


def surface_hits(scene: dict, meshes: dict[str, MeshData], o: np.ndarray, d: np.ndarray,
                 geometry_cache: GeometryCache | None = None) -> dict[str, np.ndarray]:
    """The first surface each ray (``o``, unit ``d``, (N, 3) mm) meets, as the tracer finds it:
    ``t`` (inf for none), ``triangle`` (-1), ``part`` (index into freeform.parts, -1), ``point``
    and the smooth ``normal`` there (outward for a lens)."""
    cache = geometry_cache if geometry_cache is not None else GeometryCache()
    geometry, embree, _ = cache.get(scene, meshes)
    o = np.asarray(o, np.float64)
    d = np.asarray(d, np.float64)
    t, tri, uv = embree.nearest(o, d)
    hit = np.nonzero(tri >= 0)[0]
    point = np.full((len(o), 3), np.nan)
    normal = np.full((len(o), 3), np.nan)
    th, point[hit] = _hit_point(geometry, o[hit], d[hit], t[hit], tri[hit])
    t = t.copy()
    t[hit] = th
    normal[hit] = _shading_normal(geometry, tri[hit], uv[hit])
    part = np.where(tri >= 0, geometry.part[np.maximum(tri, 0)], -1)
    return {"t": t, "triangle": tri, "part": part, "point": point, "normal": normal}

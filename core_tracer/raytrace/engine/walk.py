"""The walk of the ray-tracing tree (Fig. 7) one generation at a time: each live ray's nearest
surface among the parts its medium can reach, absorption along the segment (eq. 2), the luminance
of the surface that ends a path, and the children of the surfaces that branch (``surfaces``).
"""

from __future__ import annotations

from dataclasses import replace
from typing import Protocol

import numpy as np

from .. import optics
from .. import paths as P
from ..parts import led_die
from ..parts.base import Segments, put_rows, rows
from ..spectral import Throughput
from .context import Context
from .eyes import first_hits, put_traced, rays_toward_body
from .rays import BULB_PASS, SIDE_WALL_PASS, SOCKET_PASS, UNPOLARISED, UNRECORDED, Band, Rays, concat
from .surfaces import at_lens_face, at_plate_face, at_reflector


def depth_limit(ctx: Context) -> int:
    """The depth limit of a render (``context.MAX_DEPTH``, or ``context.GUIDE_MAX_DEPTH`` where a lamp
    has a light guide): the context's ``max_depth``."""
    return ctx.max_depth


def trace_eye_rays(ctx: Context, band: Band, o: np.ndarray, d: np.ndarray) -> None:
    """``trace_rays`` of the eye rays of samples (ray i adds to slot i of the fresh ``band``), the
    rays that miss the body's box taken apart (``rays_toward_body``). The same values in every slot:
    a ray's branches keep their order whatever other rays are traced with them."""
    toward = rays_toward_body(ctx, band, o, d)
    if toward is None:
        trace_rays(ctx, band, o, d)
    elif len(toward):
        traced = Band(len(toward), ctx)
        trace_rays(ctx, traced, o[toward], d[toward])
        put_traced(band, toward, traced)


def trace_rays(ctx: Context, band: Band, o: np.ndarray, d: np.ndarray, slots: np.ndarray | None = None) -> None:
    """Trace eye rays ``o, d`` (ray i adds to slot i of ``band``, or to ``slots[i]``) to the end of
    every branch."""
    band.segments += len(o)
    rays = first_generation(ctx, band, o, d, np.arange(len(o)) if slots is None else slots)
    depth, limit = 1, depth_limit(ctx)
    while len(rays) and depth < limit:
        band.segments += len(rays)
        rays = next_generation(ctx, band, rays)
        depth += 1
    band.max_depth = depth
    band.cut_at_depth += len(rays)


class Walker(Protocol):
    """How the rays of a kind of design find their surfaces and what happens there: a context's
    ``walker`` (None: the parametric lamps', ``eyes.first_hits`` and ``step``; the free-form
    tracer's walks its meshes)."""

    def first_hits(self, ctx, band: Band, o: np.ndarray, d: np.ndarray, pix: np.ndarray) -> Rays: ...

    def step(self, ctx, band: Band, rays: Rays) -> Rays: ...


def first_generation(ctx: Context, band: Band, o: np.ndarray, d: np.ndarray, pix: np.ndarray) -> Rays:
    """What the eye rays ``o, d`` of slots ``pix`` meet first, and the rays that go on from there."""
    if ctx.walker is None:
        return first_hits(ctx, band, o, d, pix)
    return ctx.walker.first_hits(ctx, band, o, d, pix)


def next_generation(ctx: Context, band: Band, rays: Rays) -> Rays:
    """The rays that go on after one generation of ``rays`` (``step``, or the context's walker's)."""
    return step(ctx, band, rays) if ctx.walker is None else ctx.walker.step(ctx, band, rays)


# Per part that gives normals: its surface id, the rays it was given (None: all) and their normals.
_Normals = list[tuple[int, np.ndarray | None, np.ndarray]]


def intersect(ctx: Context, rays: Rays) -> tuple[np.ndarray, np.ndarray, _Normals]:
    """Nearest surface of every ray among the parts its medium can reach (``parts.PARTS``, in
    order; ties keep the earlier part): (t, surface id, the normals out of the lens material that
    the parts gave, the lens faces': ``normals_at`` reads those of the rays that need them)."""
    n = len(rays)
    t_best = np.full(n, np.inf)
    surface = np.full(n, P.NOTHING, np.int8)
    normals: _Normals = []
    reaching: dict[tuple[int, ...], tuple[np.ndarray | None, Segments]] = {}
    # Light guides and no prism plate: the rays inside a rod meet its surface first (a closed solid inside
    # the lamp), so they are not given the lens's and the air's parts (the side wall, the cuts).
    rods_only = ctx.lamps.guide is not None and not ctx.lamps.ring_count.any()
    for media, run in _runs_of_media(ctx.parts):
        if media not in reaching:
            reaching[media] = _reaching(rays, media, rods_only)
        idx, seg = reaching[media]
        if len(seg.o) == 0:
            continue
        # The nearest hits of the rays reaching this run of parts (the air's reflector, bulb and
        # socket), kept apart and updated in place: one gather and one scatter for the run.
        t_run = t_best if idx is None else t_best.take(idx)
        surface_run = surface if idx is None else surface.take(idx)
        for part in run:
            t, part_normal = part.intersect(seg, ctx.lamps, t_run)
            np.copyto(surface_run, part.SURFACE, where=t < t_run)
            # t where t < t_run: fmin is that select, the run's t never being NaN (it starts at inf
            # and only takes a part's t that is smaller), and faster than copyto with where=.
            np.fmin(t_run, t, out=t_run)
            if part_normal is not None:
                normals.append((part.SURFACE, idx, part_normal))
        if idx is not None:
            t_best[idx] = t_run
            surface[idx] = surface_run
    return t_best, surface, normals


def _runs_of_media(parts: tuple) -> list[tuple[tuple[int, ...], list]]:
    """``parts`` in order, those next to each other that the same media reach grouped: (media, parts)."""
    runs: list[tuple[tuple[int, ...], list]] = []
    for part in parts:
        if runs and runs[-1][0] == part.MEDIA:
            runs[-1][1].append(part)
        else:
            runs.append((part.MEDIA, [part]))
    return runs


def normals_at(normals: _Normals, met: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """The normals (len(met), 3) where the segments ``met`` end, on the surfaces ``faces``: each
    from the part that surface is (the nearest part, so the last that gave the ray a normal)."""
    normal = np.zeros((len(met), 3))
    for sid, idx, part_normal in normals:
        sel = np.nonzero(faces == sid)[0]
        if len(sel) and part_normal.strides[0] == 0:  # one normal for all (the flat outer face)
            for axis in range(3):
                normal[sel, axis] = part_normal[0, axis]
        elif len(sel):
            at = met.take(sel) if idx is None else np.searchsorted(idx, met.take(sel))  # idx is sorted
            put_rows(normal, sel, rows(part_normal, at))
    return normal


def _reaching(rays: Rays, media: tuple[int, ...], rods: bool = False) -> tuple[np.ndarray | None, Segments]:
    """The rays travelling in one of ``media``: their indices (None for all) and their segments. The
    parts of the lens and the air are given every ray (the rays of a prism plate too), or with ``rods``
    (lamps with light guides, none with a plate) all but those inside a rod."""
    if {P.IN_LENS, P.IN_AIR} <= set(media) and not rods:
        idx = None
    else:  # one medium, or the prism plate's and the light guide's parts: the air and the plate
        reach = rays.medium == media[0]
        for medium in media[1:]:  # (a comparison per medium: np.isin sorts, several times slower)
            reach |= rays.medium == medium
        idx = np.nonzero(reach)[0]
    if idx is None or len(idx) == len(rays):
        return None, Segments(rays.o, rays.d, rays.lamp, rays.src, rays.medium)
    return idx, Segments(rows(rays.o, idx), rows(rays.d, idx), rays.lamp.take(idx), rays.src.take(idx),
                         rays.medium.take(idx))


def step(ctx: Context, band: Band, rays: Rays) -> Rays:
    """Trace one generation: find each segment's end, add its luminance, spawn the children."""
    lamps = ctx.lamps
    t, surface, normals = intersect(ctx, rays)
    # The path classes only feed the transitions a render records (``Band.note``).
    cls = _path_class(rays.medium, rays.src, surface) if ctx.record else UNRECORDED
    band.note(rays.pix, rays.parent, rays.branch, cls)

    rays = _absorbed(ctx, rays, t)
    k = rays.k

    # Surfaces that end a path: the luminance they show, times k. The photometric mode's side wall,
    # socket and housing are unlit (``spectral``): only its bulb adds, k expanded to the bands.
    throughput = ctx.throughput
    ends = ((P.BULB, BULB_PASS, lamps.bulb_radiance),) if throughput is not None else (
        (P.WALL, SIDE_WALL_PASS, lamps.wall_color), (P.BULB, BULB_PASS, lamps.bulb_radiance),
        (P.SOCKET, SOCKET_PASS, lamps.socket_color))
    for sid, pass_id, color in ends:
        met = np.nonzero(surface == sid)[0]
        if len(met):
            lamp = rays.lamp.take(met)
            k_met = rows(k, met)
            if throughput is not None:
                k_met = throughput.bands(k_met, rows(rays.travelled, met), lamp)
            # a bulb's light is its lamp's (``rays.BySource``); a wall's or socket's colour the surroundings'
            band.add(pass_id, rays.pix.take(met), k_met * rows(color, lamp), lamp if sid == P.BULB else None)
    # LED dies end the path with their luminance toward the eye, k · L(θ, φ) (``parts.led_die``)
    met = np.nonzero(surface == P.LED)[0] if ctx.leds else ()
    if len(met):
        lamp = rays.lamp.take(met)
        k_met = rows(k, met)
        if throughput is not None:
            k_met = throughput.bands(k_met, rows(rays.travelled, met), lamp)
        d_met = rows(rays.d, met)
        at = rows(rays.o, met) + optics.scaled(d_met, t.take(met))  # which die: a guide lit at both ends has two arrays
        band.add(BULB_PASS, rays.pix.take(met), k_met * led_die.emitted(lamps, lamp, d_met, at), lamp)
    # a plate lamp's housing ends the path
    met = np.nonzero(surface == P.HOUSING)[0] if ctx.plates and throughput is None else ()
    if len(met):
        band.add(SIDE_WALL_PASS, rays.pix.take(met), rows(k, met) * rows(lamps.housing_color, rays.lamp.take(met)))

    # Surfaces that branch. Only the rays that go on need their end point (their t is finite).
    children: list[Rays] = []
    met = np.nonzero(surface == P.REFLECTOR)[0]
    if len(met):
        d, hit = _end_points(rays, t, met)
        children.append(at_reflector(ctx, band, rays, met, rows(k, met), d, hit, cls.take(met)))
    met = np.nonzero((surface == P.OUTER) | (surface == P.CUT))[0]
    if len(met):
        d, hit = _end_points(rays, t, met)
        faces = surface.take(met)
        children.extend(at_lens_face(ctx, band, rays, met, rows(k, met), d, hit, cls.take(met), faces,
                                     normals_at(normals, met, faces)))
    # the lamp's second dielectric: a prism plate's faces or a light guide's rod
    second = (surface == P.PLATE_FRONT) | (surface == P.RINGS) | (surface == P.GUIDE) if ctx.plates else None
    met = np.nonzero(second)[0] if ctx.plates else ()
    if len(met):
        d, hit = _end_points(rays, t, met)
        faces = surface.take(met)
        children.extend(at_plate_face(rays, met, rows(k, met), d, hit, cls.take(met), faces,
                                      normals_at(normals, met, faces), lamps, throughput))
    if not children:
        return rays.take(np.zeros(0, dtype=np.int64))
    return concat(children) if len(children) > 1 else children[0]


def _absorbed(ctx: Context, rays: Rays, t: np.ndarray) -> Rays:
    """The rays with their accumulated attenuation k (and its s-polarised share) at the end of
    their segments of length ``t``: eq. (2) along those inside a lens or a prism plate; in the
    photometric mode the lengths are added to what the rays travelled in each material, the
    bands' absorption taken at the leaves (``spectral.Throughput``)."""
    if ctx.throughput is not None:
        travelled = rays.travelled.copy()
        for column, medium in ((Throughput.LENS_MM, P.IN_LENS), (Throughput.PLATE_MM, P.IN_PLATE)):
            inside = np.nonzero(rays.medium == medium)[0] if medium == P.IN_LENS or ctx.plates else ()
            if len(inside):
                travelled[inside, column] += t.take(inside)
        return replace(rays, travelled=travelled)
    lamps = ctx.lamps
    k, k_s = rays.k, rays.k_s
    in_lens = np.nonzero(rays.medium == P.IN_LENS)[0]
    if len(in_lens):
        k = k.copy()
        transmittance = optics.absorption(rows(lamps.absorption, rays.lamp.take(in_lens)), t.take(in_lens))
        put_rows(k, in_lens, rows(k, in_lens) * transmittance)
        if k_s is not UNPOLARISED:
            k_s = k_s.copy()
            put_rows(k_s, in_lens, rows(k_s, in_lens) * transmittance)
    in_plate = np.nonzero(rays.medium == P.IN_PLATE)[0] if ctx.plates else ()
    if len(in_plate):
        k = k.copy() if k is rays.k else k
        transmittance = optics.absorption(rows(lamps.plate_absorption, rays.lamp.take(in_plate)), t.take(in_plate))
        put_rows(k, in_plate, rows(k, in_plate) * transmittance)
        if k_s is not UNPOLARISED:
            k_s = k_s.copy() if k_s is rays.k_s else k_s
            put_rows(k_s, in_plate, rows(k_s, in_plate) * transmittance)
    return rays if k is rays.k else replace(rays, k=k, k_s=k_s)


def _end_points(rays: Rays, t: np.ndarray, met: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The directions of the segments ``met`` and where they end: o + t d."""
    d = rows(rays.d, met)
    return d, rows(rays.o, met) + optics.scaled(d, t.take(met))


def _path_class(medium: np.ndarray, src: np.ndarray, surface: np.ndarray) -> np.ndarray:
    """``paths.CLASS_OF[medium, src, surface]`` as one flat look-up: numpy's indexing by three
    small-integer arrays is several times slower."""
    code = medium.astype(np.intp)
    code *= P.CLASS_OF.shape[1]
    code += src
    code *= P.CLASS_OF.shape[2]
    code += surface
    return P.CLASS_OF.take(code)

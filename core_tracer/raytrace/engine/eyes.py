"""Eye rays and what they meet first (paper §3.1): the background, the body (eq. 1), or a lens's
outer face (①), found against the body's box (or its curved front) rather than against the parts;
and the screening of eye rays that cannot meet the body at all (outside its picture on the screen,
or missing its box), whose pixels see only the world.
"""

from __future__ import annotations

import numpy as np

from .. import optics
from ..parts import body_box, outer_face
from ..parts.base import rows
from ..parts.cylinder_lens import outward_normal
from .context import Context
from .rays import BACKGROUND_PASS, BODY_PASS, Band, Rays, put_slots
from .surfaces import into_lenses


def rays_toward_body(ctx: Context, band: Band, o: np.ndarray, d: np.ndarray) -> np.ndarray | None:
    """The eye rays ``o, d`` (ray i of slot i of the fresh ``band``) that meet the body's box, to be
    traced; the others see only the world (``first_hits``), looked up here at once. None: trace
    them all (too few miss to be worth the copies)."""
    t_near, t_far, _ = body_box.hit_box(o, d, ctx.box_lo, ctx.box_hi)
    toward = (t_near <= t_far) & (t_near > 0)
    miss = np.nonzero(~toward)[0]
    if len(miss) < len(o) // 8:
        return None
    if ctx.background_seen and ctx.world_seen:
        put_slots(band.acc[BACKGROUND_PASS], miss, ctx.sky(d[miss]))
    band.segments += len(miss)
    band.max_depth = max(band.max_depth, 1)
    return np.nonzero(toward)[0]


def put_traced(band: Band, toward: np.ndarray, traced: Band) -> None:
    """The traced rays ``toward`` (``rays_toward_body``) into their slots of ``band``."""
    for acc, values in zip(band.acc, traced.acc, strict=True):
        put_slots(acc, toward, values)
    band.segments += traced.segments
    band.max_depth = max(band.max_depth, traced.max_depth)
    band.transitions |= traced.transitions


def slots_seeing_body(ctx: Context, y0: int, y1: int) -> np.ndarray | None:
    """The pixels of the band of rows [y0, y1) (slots, from its first pixel) whose eye rays can
    meet the body, where the others add nothing (a black background or a transparent film): those
    outside ``body_box.screen_window``. None: every pixel."""
    if ctx.window is None or (ctx.background_seen and ctx.world_seen):
        return None
    first_col, last_col, first_row, last_row = ctx.window
    rows = np.arange(max(y0, first_row), min(y1, last_row + 1)) - y0
    cols = np.arange(first_col, last_col + 1)
    return (rows[:, None] * ctx.camera.width + cols).ravel()


def first_hits(ctx: Context, band: Band, o: np.ndarray, d: np.ndarray, pix: np.ndarray) -> Rays:
    """Classify the eye rays (paper §3.1), ray i of the band's slot ``pix[i]``: background, body,
    or lens (①)."""
    n = len(o)
    if ctx.wraps:
        return _first_hits_wrapped(ctx, band, o, d, pix)
    t_near, t_far, face = body_box.hit_box(o, d, ctx.box_lo, ctx.box_hi)
    hit_box = (t_near <= t_far) & (t_near > 0)

    if ctx.background_seen and ctx.world_seen:
        band.add(BACKGROUND_PASS, pix[~hit_box], ctx.sky(d[~hit_box]))

    # Only rays entering the front face can reach a lens: find their points there.
    front = np.nonzero(hit_box & (face == 1) & (d[:, 1] > 0))[0]
    p = rows(o, front) + t_near[front, None] * rows(d, front)
    L = ctx.lamps
    lamp_front = outer_face.lens_at(p[:, 0], p[:, 2], L)
    lamp = np.full(n, -1)
    lamp[front] = lamp_front
    on_lens = lamp >= 0
    on_body = hit_box & ~on_lens

    # Body: equation (1) with the face's outward normal.
    b = np.nonzero(on_body)[0]
    normal = np.zeros((len(b), 3))
    normal[np.arange(len(b)), face[b]] = -np.sign(d[b, face[b]])
    body = ctx.body
    band.add(BODY_PASS, pix[b], ctx.shade(normal, -rows(d, b), np.asarray(body["color"]), body["specular"],
                                          body["shininess"]))

    # Lens outer face (①): Fresnel split; the reflected branch is shaded by eq. (1) (§3.2.3).
    s = np.nonzero(on_lens)[0]
    li = lamp[s]
    ds = rows(d, s)
    local = p[lamp_front >= 0] - np.stack([L.center[li, 0], np.zeros(len(s)), L.center[li, 1]], axis=1)
    local[:, 1] = 0.0
    return into_lenses(ctx, band, pix[s], li, ds, np.tile(outer_face.NORMAL, (len(s), 1)), ds[:, 1], local)


def _first_hits_wrapped(ctx: Context, band: Band, o: np.ndarray, d: np.ndarray, pix: np.ndarray) -> Rays:
    """``first_hits`` for a body whose front curves round to the side (cylindrical lenses): the
    same classification, with the curved panel's normals and the cylindrical outer faces'."""
    n = len(o)
    t_near, hit_body, face, normal = body_box.hit_body(o, d, ctx.box_lo, ctx.box_hi, ctx.wraps)
    if ctx.background_seen and ctx.world_seen:
        band.add(BACKGROUND_PASS, pix[~hit_body], ctx.sky(d[~hit_body]))
    front = np.nonzero(hit_body & (((face == 1) & (d[:, 1] > 0)) | (face == body_box.CURVED_FRONT)))[0]
    p = rows(o, front) + t_near[front, None] * rows(d, front)
    L = ctx.lamps
    lamp = np.full(n, -1)
    lamp[front] = outer_face.lens_at(p[:, 0], p[:, 2], L)
    on_lens = lamp >= 0
    b = np.nonzero(hit_body & ~on_lens)[0]
    body = ctx.body
    band.add(BODY_PASS, pix[b], ctx.shade(rows(normal, b), -rows(d, b), np.asarray(body["color"]), body["specular"],
                                           body["shininess"]))

    s = np.nonzero(on_lens)[0]
    li = lamp[s]
    ds = rows(d, s)
    local = o[s] + t_near[s, None] * ds - np.stack([L.center[li, 0], np.zeros(len(s)), L.center[li, 1]], axis=1)
    flat = L.cylindrical[li] == 0
    local[flat, 1] = 0.0
    face_normal = np.tile(outer_face.NORMAL, (len(s), 1))
    curved = np.nonzero(~flat)[0]
    face_normal[curved] = outward_normal(local[curved], L.cyl_axis_x[li[curved]], L.cyl_radius[li[curved]])
    cos_i = np.clip(-optics.dot(ds, face_normal), 0.0, 1.0)
    return into_lenses(ctx, band, pix[s], li, ds, face_normal, cos_i, local)

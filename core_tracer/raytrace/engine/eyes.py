"""Eye rays and what they meet first (paper §3.1): the background, the body (eq. 1), or a lens's
outer face (①), found against the body's box (or its curved front) rather than against the parts;
and the screening of eye rays that cannot meet the body at all (outside its picture on the screen,
or missing its box), whose pixels see only the world.
"""

from __future__ import annotations

import numpy as np

from ..parts import body_box, outer_face
from ..parts.base import rows
from ..parts.cylinder_lens import outward_normal
from .context import Context
from .rays import BACKGROUND_PASS, BODY_PASS, Band, Rays, put_slots
from .surfaces import into_lenses


def rays_toward_body(ctx: Context, band: Band, o: np.ndarray, d: np.ndarray) -> np.ndarray | None:
    """The eye rays ``o, d`` (ray i of slot i of the fresh ``band``) that meet the body's box, to be
    traced; the others see only the world (``first_hits``), looked up here at once. None: trace
    them all (too few miss to be worth the copies, or no body's box: a free-form design)."""
    if ctx.box_lo is None:
        return None
    t_near, t_far, _ = body_box.hit_box(o, d, ctx.box_lo, ctx.box_hi)
    toward = (t_near <= t_far) & (t_near > 0)
    miss = np.nonzero(~toward)[0]
    if len(miss) < len(o) // 8:
        return None
    if ctx.background_seen and ctx.world_seen:
        put_slots(band.acc[band.planes.of(BACKGROUND_PASS)], miss, ctx.sky_seen(d[miss]))
    band.segments += len(miss)
    band.max_depth = max(band.max_depth, 1)
    return np.nonzero(toward)[0]


def put_traced(band: Band, toward: np.ndarray, traced: Band) -> None:
    """The traced rays ``toward`` (``rays_toward_body``) into their slots of ``band``."""
    for acc, values in zip(band.acc, traced.acc, strict=True):
        put_slots(acc, toward, values)
    band.segments += traced.segments
    band.max_depth = max(band.max_depth, traced.max_depth)
    band.cut_at_depth += traced.cut_at_depth
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
        band.add_seen(BACKGROUND_PASS, pix[~hit_box], ctx.sky_seen(d[~hit_box]))

    # Only rays entering the front face can reach a lens: find their points there.
    front = np.nonzero(hit_box & (face == 1) & (d[:, 1] > 0))[0]
    at_front = rows(o, front) + t_near[front, None] * rows(d, front)
    lamps = ctx.lamps
    lamp_at_front = outer_face.lens_at(at_front[:, 0], at_front[:, 2], lamps)
    lamp = np.full(n, -1)
    lamp[front] = lamp_at_front
    on_lens = lamp >= 0

    # Body: equation (1) with the face's outward normal.
    on_body = np.nonzero(hit_box & ~on_lens)[0]
    normal = np.zeros((len(on_body), 3))
    normal[np.arange(len(on_body)), face[on_body]] = -np.sign(d[on_body, face[on_body]])
    body = ctx.body
    band.add(BODY_PASS, pix[on_body], ctx.shade(normal, -rows(d, on_body), ctx.body_color,
                                                body["specular"], body["shininess"]))

    # Lens outer face (①): Fresnel split; the reflected branch is shaded by eq. (1) (§3.2.3).
    on_lens = np.nonzero(on_lens)[0]
    lamp = lamp[on_lens]
    local = at_front[lamp_at_front >= 0] - np.stack([lamps.center[lamp, 0], np.zeros(len(lamp)),
                                                     lamps.center[lamp, 1]], axis=1)
    local[:, 1] = 0.0
    return into_lenses(ctx, band, pix[on_lens], lamp, rows(d, on_lens), np.tile(outer_face.NORMAL, (len(lamp), 1)),
                       local)


def lens_seen(ctx: Context, o: np.ndarray, d: np.ndarray) -> np.ndarray:
    """The lamp whose lens's outer face each eye ray ``o, d`` meets first, or -1 (the body, the
    background): geometry only, as ``first_hits`` classifies, whatever the lens shows (an unlit lens
    too). A free-form design has no body's box: every ray gives -1."""
    lamp = np.full(len(o), -1)
    if ctx.box_lo is None:
        return lamp
    if ctx.wraps:
        t_near, hit, face, _normal = body_box.hit_body(o, d, ctx.box_lo, ctx.box_hi, ctx.wraps)
        front = hit & (((face == 1) & (d[:, 1] > 0)) | (face == body_box.CURVED_FRONT))
    else:
        t_near, t_far, face = body_box.hit_box(o, d, ctx.box_lo, ctx.box_hi)
        front = (t_near <= t_far) & (t_near > 0) & (face == 1) & (d[:, 1] > 0)
    front = np.nonzero(front)[0]
    at_front = rows(o, front) + t_near[front, None] * rows(d, front)
    lamp[front] = outer_face.lens_at(at_front[:, 0], at_front[:, 2], ctx.lamps)
    return lamp


def _first_hits_wrapped(ctx: Context, band: Band, o: np.ndarray, d: np.ndarray, pix: np.ndarray) -> Rays:
    """``first_hits`` for a body whose front curves round to the side (cylindrical lenses): the
    same classification, with the curved panel's normals and the cylindrical outer faces'."""
    n = len(o)
    t_near, hit_body, face, normal = body_box.hit_body(o, d, ctx.box_lo, ctx.box_hi, ctx.wraps)
    if ctx.background_seen and ctx.world_seen:
        band.add_seen(BACKGROUND_PASS, pix[~hit_body], ctx.sky_seen(d[~hit_body]))
    front = np.nonzero(hit_body & (((face == 1) & (d[:, 1] > 0)) | (face == body_box.CURVED_FRONT)))[0]
    at_front = rows(o, front) + t_near[front, None] * rows(d, front)
    lamps = ctx.lamps
    lamp = np.full(n, -1)
    lamp[front] = outer_face.lens_at(at_front[:, 0], at_front[:, 2], lamps)
    on_lens = lamp >= 0
    on_body = np.nonzero(hit_body & ~on_lens)[0]
    body = ctx.body
    band.add(BODY_PASS, pix[on_body], ctx.shade(rows(normal, on_body), -rows(d, on_body), ctx.body_color,
                                                body["specular"], body["shininess"]))

    on_lens = np.nonzero(on_lens)[0]
    lamp = lamp[on_lens]
    d_lens = rows(d, on_lens)
    local = (o[on_lens] + t_near[on_lens, None] * d_lens
             - np.stack([lamps.center[lamp, 0], np.zeros(len(lamp)), lamps.center[lamp, 1]], axis=1))
    flat = lamps.cylindrical[lamp] == 0
    local[flat, 1] = 0.0
    face_normal = np.tile(outer_face.NORMAL, (len(lamp), 1))
    curved = np.nonzero(~flat)[0]
    face_normal[curved] = outward_normal(local[curved], lamps.cyl_axis_x[lamp[curved]], lamps.cyl_radius[lamp[curved]])
    return into_lenses(ctx, band, pix[on_lens], lamp, d_lens, face_normal, local)

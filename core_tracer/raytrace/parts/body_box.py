"""The body (docs/model.md §3): an axis-aligned box, its front face in y = 0, in the world frame.
Only eye rays meet it: it decides background, body or lens (paper §3.1)."""

from __future__ import annotations

import math

import numpy as np

from ..camera import Camera


def body_box(body: dict) -> tuple[np.ndarray, np.ndarray]:
    """The body's box (docs/model.md §3): its lowest and highest corners; the front face lies in y = 0
    and the depth runs into +y."""
    (cx, cz), (sx, sz) = body["center"], body["size"]
    return np.array([cx - sx / 2, 0.0, cz - sz / 2]), np.array([cx + sx / 2, body["depth"], cz + sz / 2])


def hit_box(o: np.ndarray, d: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rays against the axis-aligned box [lo, hi] (the slab test): per ray, the entry distance, the
    exit distance and the axis (0, 1, 2) of the entry face. A ray from outside hits the box where
    ``t_near <= t_far`` and ``t_near > 0``."""
    # Axis by axis on the columns (the same values as on the (N, 3) arrays, without numpy's slow
    # reductions over a 3-wide axis).
    t_lo, t_hi = [], []
    for axis in range(3):
        oa, da = o[:, axis], d[:, axis]
        with np.errstate(divide="ignore", invalid="ignore"):  # (in place: these run on every eye ray)
            t1, t2 = np.subtract(lo[axis], oa), np.subtract(hi[axis], oa)
            t1 /= da
            t2 /= da
        # A ray parallel to a slab is inside it (−inf, inf) or outside it (inf, −inf).
        parallel = da == 0
        if parallel.any():
            inside = (oa >= lo[axis]) & (oa <= hi[axis])
            t_lo.append(np.where(parallel, np.where(inside, -np.inf, np.inf), np.fmin(t1, t2)))
            t_hi.append(np.where(parallel, np.where(inside, np.inf, -np.inf), np.fmax(t1, t2)))
        else:
            t_lo.append(np.fmin(t1, t2))
            t_hi.append(np.fmax(t1, t2, out=t2))
    t_near = np.maximum(t_lo[0], t_lo[1])
    np.maximum(t_near, t_lo[2], out=t_near)
    t_far = np.minimum(t_hi[0], t_hi[1], out=t_hi[0])
    np.minimum(t_far, t_hi[2], out=t_far)
    # argmax's choice: the first axis whose entry is the latest
    face = np.where((t_lo[0] >= t_lo[1]) & (t_lo[0] >= t_lo[2]), 0, np.where(t_lo[1] >= t_lo[2], 1, 2))
    return t_near, t_far, face


def screen_window(cam: Camera, lo: np.ndarray, hi: np.ndarray, margin: int = 2) -> tuple[int, int, int, int] | None:
    """The pixels whose eye rays can meet the box [lo, hi]: (first column, last column, first row,
    last row), the box's corners projected, widened by ``margin`` pixels so that no ray rounding
    the other way at the box's silhouette is left out; empty (first > last) when the box is out of
    view. None when some corner lies behind a perspective camera (every pixel may see the box).

    The box lies inside the convex hull of its corners, whose picture lies inside the rectangle
    of their pictures: a ray through a pixel outside it misses the box."""
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    rel = corners - cam.position
    depth, across, upward = (rel[:, 0] * a[0] + rel[:, 1] * a[1] + rel[:, 2] * a[2]
                             for a in (cam.forward, cam.right, cam.up))
    if cam.orthographic:
        u, v = across, upward
    elif (depth <= 0).any():
        return None
    else:
        u, v = across / depth, upward / depth
    # camera.eye_rays: u = ((col + 1/2) / W * 2 - 1) half_width + shift_x, and v likewise down the rows
    col = ((u - cam.shift[0]) / cam.half_width + 1.0) * cam.width / 2.0 - 0.5
    row = (1.0 - (v - cam.shift[1]) / cam.half_height) * cam.height / 2.0 - 0.5
    return (max(0, math.floor(col.min()) - margin), min(cam.width - 1, math.ceil(col.max()) + margin),
            max(0, math.floor(row.min()) - margin), min(cam.height - 1, math.ceil(row.max()) + margin))


CURVED_FRONT = 3  # the face code of a curved end of the front (``hit_body``), after the box's 0, 1, 2


def hit_body(o: np.ndarray, d: np.ndarray, lo: np.ndarray, hi: np.ndarray,
             wraps: list[tuple[float, float, float]]) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Rays against a body whose front curves round to the side (``scene.derived.body_wraps``):
    the box cut by the front panel, the plane y = 0 between the tangent lines and, beyond the
    line x = x_t of a wrap toward ``side``, the cylinder of its radius about (x_t, radius).

    The body is the box's points on or behind the front panel, y >= f(x) with f convex, so the
    part of a ray inside it is one interval: where the ray enters the box on or behind the panel
    it enters there; otherwise it enters through the curved panel, at the first root on the
    circle's near arc inside the box. Returns per ray the entry distance, whether it hits, the face
    (0, 1, 2 as ``hit_box``, ``CURVED_FRONT``) and the outward normal."""
    t_near, t_far, face = hit_box(o, d, lo, hi)
    hit = (t_near <= t_far) & (t_near > 0)
    normal = np.zeros((len(o), 3))
    rows = np.arange(len(o))
    normal[rows, face] = -np.sign(d[rows, face])
    entering = np.nonzero(hit)[0]  # only these can meet the curved panel: test them alone
    x = o[entering, 0] + t_near[entering] * d[entering, 0]
    y = o[entering, 1] + t_near[entering] * d[entering, 1]
    in_front = np.zeros(len(entering), bool)
    for side, x_t, radius in wraps:
        u = side * (x - x_t)
        curved = u > 0
        with np.errstate(invalid="ignore"):
            in_front[curved] |= y[curved] < radius - np.sqrt(radius * radius - u[curved] ** 2)
    through_arc = entering[in_front]
    t_arc = np.full(len(through_arc), np.inf)
    arc_normal = np.zeros((len(through_arc), 3))
    oa, da = o[through_arc], d[through_arc]
    for side, x_t, radius in wraps:
        X, Y = oa[:, 0] - x_t, oa[:, 1] - radius
        a = da[:, 0] ** 2 + da[:, 1] ** 2
        b = X * da[:, 0] + Y * da[:, 1]
        c = X * X + Y * Y - radius * radius
        with np.errstate(invalid="ignore", divide="ignore"):
            t = (-b - np.sqrt(b * b - a * c)) / a  # entering the cylinder: the near root
            x, y = X + t * da[:, 0], Y + t * da[:, 1]
            ok = ((t >= t_near[through_arc] - 1e-9) & (t <= t_far[through_arc]) & (side * x >= 0) & (y <= 0)
                  & (t < t_arc))
        t_arc = np.where(ok, t, t_arc)
        arc_normal[ok] = np.stack([x[ok], y[ok], np.zeros(int(ok.sum()))], axis=1) / radius
    t_near = t_near.copy()
    t_near[through_arc] = t_arc
    hit[through_arc] = np.isfinite(t_arc)
    face = face.copy()
    face[through_arc] = CURVED_FRONT
    normal[through_arc] = arc_normal
    return t_near, hit, face, normal

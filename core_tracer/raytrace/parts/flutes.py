"""Cylindrical flutes: parallel cylindrical ridges on the lens's inner face, Table 1's cut face
like the fish-eye cuts (``cuts``) and the saw-tooth ridges (``sawtooth``).

Geometry (docs/model.md, model: where the paper is silent). With s = a . (x, z) across the ridges
(``LampTable.ridge_across``), strip k covers (k - 1/2) p <= s <= (k + 1/2) p, one strip centred on
the axis; its flute is the cylinder of radius rho = (p^2/4 + h^2) / 2h along the ridges, apex at
(s = k p, plane B), meeting plane A at the strip's borders, so neighbouring flutes meet in creases.

Intersection: the paper's plane-A / plane-B method (Fig. 9) with strips for cells: the strips
crossed between the two planes are walked from the entry side (a 1-D traversal) and each one's
cylinder tested; the first root inside its own strip is the hit. A ray crosses a few strips in the
slab, and at most (2R/p + 3) however it is aimed, which validation bounds."""

from __future__ import annotations

import numpy as np

from ...scene.spec import MAX_CUTS_ACROSS
from .. import optics
from .. import paths as P
from ..lamp_table import LampTable
from .base import T_MIN, Segments, put_rows, rows, slab_span
from .cuts import INTO_AIR, INTO_LENS, OFF_CAP, flat_base_hits

SURFACE = P.CUT
MEDIA = (P.IN_LENS, P.IN_AIR)
MAX_STRIP_STEPS = MAX_CUTS_ACROSS + 3  # across the lens diameter 2R <= MAX_CUTS_ACROSS p, and the ends
TOL = 1e-9  # mm of ray parameter: a root on a strip border belongs to both strips


def intersect(rays: Segments, lamps: LampTable, t_limit: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    # As for the fish-eye caps: a ray that starts on a flute excludes it by geometry.
    on_cap = np.where(rays.src != P.CUT, OFF_CAP, np.where(rays.medium == P.IN_AIR, INTO_AIR, INTO_LENS))
    li = rays.lamp  # (the lamps' rows gathered with take: faster than indexing)
    return hit_flutes(rays.o, rays.d, lamps.plane_a.take(li), lamps.plane_b.take(li), lamps.pitch.take(li),
                      lamps.flute_radius.take(li), lamps.ridge_across.take(li, axis=0), t_limit, on_cap.astype(np.int8))


def hit_flutes(o: np.ndarray, d: np.ndarray, plane_a: np.ndarray, plane_b: np.ndarray, pitch: np.ndarray,
               rho: np.ndarray, across: np.ndarray, t_limit: np.ndarray,
               on_cap: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The fluted surface: the hit parameter (inf for none nearer than ``t_limit``) and the unit
    normal out of the lens material. ``on_cap`` as in ``cuts.hit_cuts``."""
    n = len(o)
    t_hit = np.full(n, np.inf)
    normal = np.zeros((n, 3))
    normal[:, 1] = 1.0
    on_cap = np.zeros(n, np.int8) if on_cap is None else on_cap

    curved = np.isfinite(rho)
    every_curved = bool(curved.all())
    if not every_curved:
        flat_base_hits(o, d, plane_a, t_limit, np.nonzero(~curved & (on_cap == OFF_CAP))[0], t_hit)
    # (one errstate for the walk: rays parallel to a plane or to the ridges divide by zero, on purpose)
    with np.errstate(divide="ignore", invalid="ignore"):
        strip = _StripWalk.enter(o, d, plane_a, plane_b, pitch, rho, across, t_limit, on_cap, every_curved).walk(t_hit)

    hit = np.nonzero(np.isfinite(t_hit) & curved if not every_curved else np.isfinite(t_hit))[0]
    if len(hit):
        oh, dh, th = rows(o, hit), rows(d, hit), t_hit[hit]
        hx, hy, hz = oh[:, 0] + th * dh[:, 0], oh[:, 1] + th * dh[:, 1], oh[:, 2] + th * dh[:, 2]
        ax, az = across[hit, 0], across[hit, 1]
        ns = hx * ax + hz * az - strip[hit] * pitch[hit]
        h = np.empty((len(hit), 3))
        np.multiply(ns, ax, out=h[:, 0])
        np.subtract(hy, plane_b[hit] - rho[hit], out=h[:, 1])
        np.multiply(ns, az, out=h[:, 2])
        put_rows(normal, hit, optics.normalize(h))
    return t_hit, normal


class _StripWalk:
    """The rays still walking the flutes' strips (a 1-D traversal), one column per ray of a single
    (rows, K) array so that dropping the finished rays is one gather (as ``cuts._CellWalk``)."""

    ROWS = ("s0", "ds", "p", "t_cell", "t_out", "k", "t_next", "dt", "b_y", "c_y", "a2", "step", "cap")

    def __init__(self, ray: np.ndarray, state: np.ndarray, n: int):
        self._set(ray, state)
        self.n = n
        self.first = True  # in the strip where the ray enters the slab: its own flute if it starts on one

    def _set(self, ray: np.ndarray, state: np.ndarray) -> None:
        self.ray = ray  # index of the ray in the caller's arrays
        self.state = state  # (len(ROWS), K)
        self.r = dict(zip(self.ROWS, state, strict=True))  # its rows by name

    @classmethod
    def enter(cls, o, d, plane_a, plane_b, pitch, rho, across, t_limit, on_cap, every_curved) -> _StripWalk:
        """The rays with flutes whose path crosses the slab between planes A and B before
        ``t_limit``, each in the strip where it enters the slab."""
        n = len(o)
        ray = np.arange(n) if every_curved else np.nonzero(np.isfinite(rho))[0]
        pick = (lambda a: a) if every_curved else (lambda a: a.take(ray, axis=0))
        oy, dy, a_plane, b_plane = pick(o[:, 1]), pick(d[:, 1]), pick(plane_a), pick(plane_b)
        t_in, t_out = slab_span(oy, dy, a_plane, b_plane, pick(t_limit))
        live = np.nonzero(t_in <= t_out)[0]
        everyone = len(live) == len(ray)
        if not everyone:
            ray = ray[live]
        state = np.empty((len(cls.ROWS), len(ray)))
        walk = cls(ray, state, n)
        row = walk.r
        # (rows of (N, 3) arrays gathered whole: ``take`` of a strided column copies the column first)
        if everyone and every_curved:
            oc, dc, ac, r, p_ray = o, d, across, rho, pitch
        else:
            oc, dc, ac, r, p_ray = rows(o, ray), rows(d, ray), rows(across, ray), rho.take(ray), pitch.take(ray)
        if not everyone:
            oy, dy, b_plane, t_in, t_out = oc[:, 1], dc[:, 1], b_plane.take(live), t_in.take(live), t_out.take(live)
        row["t_cell"][:], row["t_out"][:] = t_in, t_out
        row["p"][:] = p_ray
        t_cell = row["t_cell"]
        ax, az = ac[:, 0], ac[:, 1]
        s0, ds, p = row["s0"], row["ds"], row["p"]
        np.add(oc[:, 0] * ax, oc[:, 2] * az, out=s0)
        np.add(dc[:, 0] * ax, dc[:, 2] * az, out=ds)
        k, step, t_next, dt = row["k"], row["step"], row["t_next"], row["dt"]
        np.floor((s0 + t_cell * ds) / p + 0.5, out=k)
        np.sign(ds, out=step)
        t_next[:] = ((k + 0.5 * step) * p - s0) / ds
        np.divide(p, np.abs(ds), out=dt)
        along = step == 0
        if along.any():
            t_next[along] = dt[along] = np.inf
        # Cell-independent terms of the roots, relative to the apex (see ``cuts._CellWalk.cap_hits``):
        # |q + t D + rho y|^2 = rho^2 with q = (s0 - k p, o_y - plane B), D = (d_s, d_y).
        qy = oy - b_plane
        np.add(ds * ds, dy * dy, out=row["a2"])
        np.add(qy * dy, r * dy, out=row["b_y"])
        np.add(qy * qy, 2.0 * r * qy, out=row["c_y"])
        row["cap"][:] = on_cap if everyone and every_curved else on_cap.take(ray)
        if row["cap"].any():
            walk._leave_own_flutes()
        else:
            walk.first = False
        return walk

    def _leave_own_flutes(self) -> None:
        """A ray leaving a flute into the air never meets it again (``walk``): it starts in the
        next strip, and most leave the slab before."""
        leaving = self.r["cap"] == INTO_AIR
        if leaving.any():
            keep = ~leaving | (self.r["t_next"] <= self.r["t_out"])
            self._keep(keep)
            leaving = leaving[keep] if not keep.all() else leaving
            r = self.r
            np.copyto(r["t_cell"], r["t_next"], where=leaving)
            np.add(r["k"], r["step"], out=r["k"], where=leaving)
            np.add(r["t_next"], r["dt"], out=r["t_next"], where=leaving)
            r["cap"][leaving] = OFF_CAP
        self.first = bool(self.r["cap"].any())

    def _keep(self, keep: np.ndarray) -> None:
        if not keep.all():
            idx = np.nonzero(keep)[0]
            self._set(self.ray[idx], self.state.take(idx, axis=1))

    def walk(self, t_hit: np.ndarray) -> np.ndarray:
        """Walk to each ray's hit or out of the slab: the hits go into ``t_hit``; returns each
        ray's strip of its hit."""
        strip = np.zeros(self.n)
        for _ in range(MAX_STRIP_STEPS):
            if len(self.ray) == 0:
                break
            r = self.r
            s0, ds, p, k, a2, t_cell, t_next, t_out = (r["s0"], r["ds"], r["p"], r["k"], r["a2"], r["t_cell"],
                                                       r["t_next"], r["t_out"])
            qs = s0 - k * p
            b = qs * ds + r["b_y"]
            c = qs * qs + r["c_y"]
            q = -(b + np.copysign(np.sqrt(b * b - a2 * c), b))
            r1, r2 = q / a2, c / q
            lo, hi = np.fmin(r1, r2), np.fmax(r1, r2)
            if self.first:  # the flute a ray starts on: leaving it inward, only its far root
                lo[r["cap"] != OFF_CAP] = np.nan
                self.first = False
            t_end = np.minimum(t_next, t_out)
            lo_ok = (lo > T_MIN) & (lo >= t_cell - TOL) & (lo <= t_end + TOL)
            hi_ok = (hi > T_MIN) & (hi >= t_cell - TOL) & (hi <= t_end + TOL)
            t = np.where(lo_ok, lo, np.where(hi_ok, hi, np.inf))
            found = np.isfinite(t)
            hits = np.nonzero(found)[0]
            if len(hits):
                ray = self.ray[hits]
                t_hit[ray] = t[hits]
                strip[ray] = k[hits]
            self._keep(~found & (t_next <= t_out))
            if len(self.ray):
                r = self.r
                r["t_cell"][:] = r["t_next"]
                r["k"] += r["step"]
                r["t_next"] += r["dt"]
        return strip


def profile_height(x: np.ndarray, z: np.ndarray, plane_b: float, pitch: float, rho: float,
                   across: tuple[float, float]) -> np.ndarray:
    """Height y of the fluted surface above (x, z)."""
    s = np.asarray(x) * across[0] + np.asarray(z) * across[1]
    u = s - np.floor(s / pitch + 0.5) * pitch
    return plane_b - u * u / (rho + np.sqrt(np.maximum(rho * rho - u * u, 0.0)))

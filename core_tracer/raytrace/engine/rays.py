"""Rays and passes: one generation of live rays as arrays, and what a band of pixels accumulates.

Each ray carries its accumulated attenuation k (paper §3.4, docs/model.md §5): luminance found at the
end of a segment is added to the ray's pixel as k × the value, into one of the contribution passes
(docs/model.md §5.2), so the ray-tracing tree of Fig. 7 is never stored.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from functools import cache

import numpy as np

from ..parts.base import put_rows, rows

CUTOFF = 1e-3  # paper §3.4: a branch whose accumulated attenuation falls below 0.1 % is dropped
# The photometric cut-off test (``alive``): branches whose bound lies below this multiple of the
# cut-off are tested on their bands.
EXACT_NEAR = 4.0
PASS_NAMES = ("lens_surface", "bulb", "reflector_constant", "reflector_scatter", "socket", "side_wall",
              "body", "background")
(LENS_SURFACE, BULB_PASS, REFLECTOR_CONSTANT, REFLECTOR_SCATTER, SOCKET_PASS, SIDE_WALL_PASS, BODY_PASS,
 BACKGROUND_PASS) = range(len(PASS_NAMES))


@dataclass
class Rays:
    """One generation of live rays inside the lamps (a parametric design's in local lamp
    coordinates), one row each."""

    pix: np.ndarray  # pixel index within the band
    lamp: np.ndarray  # the row of the lamp table its values come from (free-form: of the part table)
    o: np.ndarray
    d: np.ndarray
    # accumulated attenuation, one column per channel: R, G, B; photometric: the product of the Fresnel
    # factors at the wavelength nodes, the rest of it in ``travelled`` (``spectral.Throughput``)
    k: np.ndarray
    medium: np.ndarray  # paths.IN_LENS / IN_AIR
    src: np.ndarray  # surface the segment starts on
    parent: np.ndarray  # path class of the segment that spawned this one
    branch: np.ndarray  # paths.REFLECTED / TRANSMITTED
    seen_reflector: np.ndarray
    # The photometric mode's share of k carried by s-polarised light (the rest is p-polarised), per
    # channel: Fresnel splits each share with its own reflectance (``surfaces.fresnel_split``).
    # UNPOLARISED in the paper mode, which splits k by the average reflectance at every surface.
    k_s: np.ndarray
    # The photometric mode's (N, 3): mm through the lens's material, mm through the plate's, and
    # reflections off the reflector's finish, from which a leaf takes the bands' absorption and the
    # finish's reflectance (``spectral.Throughput.bands``). UNRECORDED in the paper mode, whose k
    # holds them.
    travelled: np.ndarray

    def __len__(self) -> int:
        return len(self.pix)

    def take(self, sel: np.ndarray) -> Rays:
        if sel.dtype == bool:
            if sel.all():
                return self
            sel = np.nonzero(sel)[0]
        return type(self)(*(rows(getattr(self, f), sel) for f in field_names(type(self))))


@cache
def field_names(kind: type[Rays]) -> tuple[str, ...]:
    """The fields of ``Rays`` or of a kind of rays that carries more (``freeform.render.MeshRays``)."""
    return tuple(f.name for f in fields(kind))


class NotKept:
    """A column of the rays that a render does not keep, one of three (below): nothing is computed
    or gathered for it, every gather of it is itself, and it says which it is."""

    def __init__(self, name: str, why: str):
        self.name, self.why = name, why

    def __repr__(self) -> str:
        return self.name

    def take(self, *_args, **_kwargs) -> NotKept:
        return self

    def __getitem__(self, _key) -> NotKept:
        return self


# ``Rays.parent`` and ``Rays.branch`` of a render that records no transitions (they only feed ``Band.note``)
UNRECORDED = NotKept("UNRECORDED", "the render records no path transitions")
# ``Rays.k_s`` of the paper mode, which splits k by the average reflectance
UNPOLARISED = NotKept("UNPOLARISED", "the paper mode splits k by the average reflectance")
# ``Rays.travelled`` of the paper mode, whose k holds the absorption and the finish
NOT_DEFERRED = NotKept("NOT_DEFERRED", "the paper mode's k holds what the photometric one defers")


def branch_tags(cls: np.ndarray | NotKept, branch: int, n: int) -> np.ndarray | NotKept:
    """The ``branch`` of ``n`` children whose parents' classes are ``cls`` (UNRECORDED: none kept)."""
    return UNRECORDED if cls is UNRECORDED else np.full(n, branch, np.int8)


def concat(parts: list[Rays]) -> Rays:
    kind = type(parts[0])
    columns = ([getattr(p, f) for p in parts] for f in field_names(kind))
    return kind(*(_kept(each) for each in columns))


def _kept(column: list) -> np.ndarray | NotKept:
    """One column of several generations of rays, joined; a column not kept stays so."""
    for part in column:
        if isinstance(part, NotKept):
            return part
    return np.concatenate(column)


def add_to_pass(acc: np.ndarray, pix: np.ndarray, values: np.ndarray) -> None:
    """Add ``values`` (N, C) to the pixels ``pix`` of one pass ``acc`` (pixels, C), repeats summed
    (C channels: 3 in the paper mode, the bands in the photometric one).

    One count over the (pixel, channel) bins of the pixels spanned, each bin summing its values in
    ray order, then added to the pass: the same sums as one count per channel. A few rays spread
    over many pixels (the deep branches of a band) are counted over the pixels they reach alone:
    the same sums, without adding zeros to every pixel between."""
    if len(pix) == 0:
        return
    first, last = int(pix.min()), int(pix.max()) + 1
    if 4 * len(pix) < last - first:
        pixels, slot = _distinct(pix)
        sums = rows(acc, pixels)
        sums += _bin_sums(slot, values, len(pixels))
        put_rows(acc, pixels, sums)
    else:
        acc[first:last] += _bin_sums(pix - first, values, last - first)


def _distinct(pix: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``np.unique(pix, return_inverse=True)`` for pixel indices (|pix| < 2^31): the distinct
    pixels, ascending, and each ray's slot among them. One sort of (pixel, ray) packed into one
    integer instead of numpy's argsort, in about two thirds of its time (the deep branches' calls)."""
    n = len(pix)
    key = np.left_shift(pix, 32, dtype=np.int64)
    key |= np.arange(n)
    key.sort()
    ascending = key >> 32
    new = np.empty(n, bool)
    new[0] = True
    np.not_equal(ascending[1:], ascending[:-1], out=new[1:])
    slot = np.empty(n, np.intp)
    key &= 0xFFFFFFFF  # the rays in pixel order
    slot[key] = np.cumsum(new) - 1
    return ascending[new], slot


def _bin_sums(slot: np.ndarray, values: np.ndarray, n_slots: int) -> np.ndarray:
    """Per slot (n_slots, C), the sum of the ``values`` (N, C) of its rays in ray order."""
    # bin C slot + channel, a column at a time (numpy broadcasts slowly over short rows)
    channels = values.shape[-1]
    bins = np.empty((len(slot), channels), dtype=np.intp)
    np.multiply(slot, channels, out=bins[:, 0])
    for c in range(1, channels):
        np.add(bins[:, 0], c, out=bins[:, c])
    weights = np.broadcast_to(values, bins.shape)
    return np.bincount(bins.ravel(), weights=weights.ravel(),
                       minlength=channels * n_slots).reshape(n_slots, channels)


class ByPass:
    """The planes a band accumulates: one per contribution pass (``PASS_NAMES``, docs/model.md §5.2)."""

    names = PASS_NAMES

    @property
    def count(self) -> int:
        return len(self.names)

    def of(self, pass_id: int) -> int:
        """The plane of what ``pass_id`` adds that no lamp emits (the background, the body, the sun)."""
        return pass_id

    def add(self, acc: np.ndarray, pass_id: int, pix: np.ndarray, values: np.ndarray,
            lamp: np.ndarray | None = None) -> None:
        """Add ``values`` (N, C) of pass ``pass_id`` to the pixels ``pix`` of the planes ``acc``;
        ``lamp``: the lamp that emitted each value (None: no lamp did)."""
        add_to_pass(acc[pass_id], pix, values)


class BySource(ByPass):
    """The planes of a render of light states: one per source of light, so that the light of each
    can be weighted after one walk (``measures.states``). Radiance is linear in the sources,

        L = L_surroundings + Σ_lamps L_lamp

    where L_lamp is what lamp's bulb or LED dies emit (a bulb hit ⑪, a die, eq. 3's glow or the
    photometric reflector's scatter of the bulb's light) and L_surroundings everything else (the
    sun, sky and environment, the ambient term, the reflector constant, the phantom light). Plane 0
    holds the surroundings, plane 1 + i lamp i's light: the same rays, so the planes' sum is the
    render's image."""

    SURROUNDINGS = 0

    def __init__(self, lamp_count: int):
        self.names = ("surroundings", *(f"lamp{i}" for i in range(lamp_count)))

    def of(self, pass_id: int) -> int:
        return self.SURROUNDINGS

    def add(self, acc: np.ndarray, pass_id: int, pix: np.ndarray, values: np.ndarray,
            lamp: np.ndarray | None = None) -> None:
        if lamp is None:
            add_to_pass(acc[self.SURROUNDINGS], pix, values)
            return
        lamps = np.unique(lamp)
        if len(lamps) == 1:  # every ray of one lamp: no gathers
            add_to_pass(acc[1 + int(lamps[0])], pix, values)
            return
        for one in lamps:
            sel = np.nonzero(lamp == one)[0]
            add_to_pass(acc[1 + int(one)], pix.take(sel), rows(values, sel))


BY_PASS = ByPass()


class Band:
    """Accumulates the planes of one band of pixels (``ctx.planes``: its passes, or its sources'
    light) and the band's statistics."""

    def __init__(self, n_pixels: int, ctx, acc: np.ndarray | None = None):
        self.n = n_pixels
        self.planes = ctx.planes
        self.acc = np.zeros((self.planes.count, n_pixels, ctx.pass_channels)) if acc is None else acc
        self.to_xyz = ctx.to_xyz  # (K, 3): a photometric leaf's bands to X, Y, Z as added; None: kept (R, G, B)
        self.segments = 0
        self.max_depth = 0
        self.cut_at_depth = 0  # branches alive at the depth limit (walk.depth_limit), ended there: counted, not dropped
        self.busy = 0  # pixels that took every sample (adaptive sampling)
        self.transitions: set[tuple[int, int, int]] = set()
        self.record = ctx.record  # whether the render records path transitions (its context's flag)

    def add(self, pass_id: int, pix: np.ndarray, values: np.ndarray, lamp: np.ndarray | None = None) -> None:
        """Add ``values`` (N, C) to the pixels ``pix`` of a pass: R, G, B as they are; photometric
        bands (N, K) as X, Y, Z, so that passes, samples and adaptive sampling work on 3 channels.
        ``lamp`` (N,): the lamps whose bulb or dies emitted the values (``BySource``); None: light
        no lamp emits."""
        self.planes.add(self.acc, pass_id, pix, self.in_pass(values), lamp)

    def add_seen(self, pass_id: int, pix: np.ndarray, values: np.ndarray) -> None:
        """Add values already as the pass holds them (``Lighting.sky_seen``)."""
        add_to_pass(self.acc[self.planes.of(pass_id)], pix, values)

    def in_pass(self, values: np.ndarray) -> np.ndarray:
        """Leaf values (N, C) as a pass holds them: photometric bands turned to X, Y, Z in cd/m²."""
        return values if self.to_xyz is None else values @ self.to_xyz

    def note(self, pix: np.ndarray, parent: np.ndarray, branch: np.ndarray, child: np.ndarray) -> None:
        """Record the transitions (parent class, branch, child class) of the rays at slots ``pix``."""
        if self.record and len(child):
            codes = np.unique(parent.astype(np.int64) * 10000 + branch.astype(np.int64) * 100 + child)
            self.transitions.update((int(c) // 10000, (int(c) // 100) % 100, int(c) % 100) for c in codes)


def no_rays() -> Rays:
    return Rays(*(np.zeros(0, dtype=np.int64) for _ in field_names(Rays)))


def put_slots(acc: np.ndarray, slots: np.ndarray, values: np.ndarray) -> None:
    """``acc[slots] = values`` for (N, C) float64 rows: each row copied as one item of C float64s,
    about twice as fast as numpy's scatter of rows (the same bytes)."""
    slot = np.dtype((np.void, acc.shape[-1] * 8))  # one slot of a pass, its channels as one item
    acc.view(slot)[slots, 0] = np.ascontiguousarray(values, dtype=np.float64).view(slot)[:, 0]


def alive(k: np.ndarray, deferred: tuple | None = None) -> np.ndarray:
    """The branches whose accumulated attenuation is still above the cut-off in some channel (a
    branch ends when every channel, every band in the photometric mode, is below it). ``deferred``
    (photometric): (``spectral.Throughput``, the rays' ``travelled``, their lamps), k being the
    Fresnel product at the nodes (``Throughput.alive``)."""
    if deferred is not None:
        return _alive_deferred(k, *deferred)
    if k.shape[1] == 3:
        return np.maximum(np.maximum(k[:, 0], k[:, 1]), k[:, 2]) >= CUTOFF
    return largest_column(k) >= CUTOFF


def _alive_deferred(k: np.ndarray, throughput, travelled: np.ndarray, lamp: np.ndarray) -> np.ndarray:
    """``alive`` of photometric branches: those whose bound (the largest node of k times
    ``Throughput.reach``) is below the cut-off end; of the others, those whose bound is within
    ``EXACT_NEAR`` of it are tested band by band (their bands expanded), so that only a branch whose
    bound exceeds its largest band more than that can live on where the bands would end it."""
    bound = largest_column(k) * throughput.reach(travelled, lamp)
    going = bound >= CUTOFF
    near = np.nonzero(going & (bound < EXACT_NEAR * CUTOFF))[0]
    if len(near):
        bands = throughput.bands(rows(k, near), rows(travelled, near), lamp.take(near))
        going[near] = largest_column(bands) >= CUTOFF
    return going


def largest_column(values: np.ndarray) -> np.ndarray:
    """Per row of (N, C) ``values`` the largest: a column at a time, about 4 times faster than
    ``values.max(axis=1)`` over short rows."""
    out = values[:, 0].copy()
    for column in range(1, values.shape[1]):
        np.maximum(out, values[:, column], out=out)
    return out

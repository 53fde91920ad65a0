"""The bands a photometric scene is traced on, chosen from what it contains (issue 32).

Carrying a spectrum as K band means makes each product along a path a product of means: a source
S(λ) through filters and finishes A(λ) is counted as Σ_k S̄_k Ā_k M_k (``cie.xyz_matrix``), not
Km ∫ S A (x̄, ȳ, z̄) dλ. The difference grows with each band's width squared times the curves'
curvature, so a narrow LED line (630 nm, 20 nm wide) needs finer bands than an incandescent bulb
behind a red filter. ``scene_error`` evaluates that difference for every path a scene's light takes
(each source as if lit through each lamp's lens and plate or guide filters, with and without the
reflector's finish; the sun through them too), against 0.5 nm bands, without tracing; ``scene_bands``
takes the default 40 bands of 10 nm when they meet ``ACCEPT`` and otherwise refines them where the
light is (docs/photometric.md, "Bands per scene").
"""

from __future__ import annotations

import functools
import hashlib
import warnings
from dataclasses import dataclass

import numpy as np

from ..photometry import daylight, materials
from ..photometry.bands import Bands
from ..photometry.cie import xyz_matrix
from ..photometry.spectrum import Spectrum
from ..scene.led_array import uses_leds
from ..scene.reading import SceneError
from . import spectral

# The reference: 0.5 nm bands (their own error is (0.5 / 10)² = 1/400 of the 10 nm bands').
FINE = Bands.uniform(800)
# The filter thicknesses d / t a path is checked at: straight through the lens, oblique or through a
# cut, reflected inside it. Measured: the LED stop lamp's lit lens behaves as about 4 (its 40-band
# luminance error, 2.04 % against 81 bands, is the one of a red LED through 4 thicknesses of its filter).
PASSES = (1.0, 2.0, 4.0)
# (xy, relative luminance) against FINE: the default bands are kept when every path meets ACCEPT (every
# bulb preset does: at worst 0.0010 and 0.77 %, daylight through 4 thicknesses of a red filter); else
# they are refined until every path meets REFINE, a margin under the limits (0.002, 1 %).
ACCEPT = (0.0012, 0.008)
REFINE = (0.0005, 0.003)
MAX_BANDS = 240  # the refinement stops here (a CSV line narrower than ~2 nm would need more)
MIN_WIDTH_NM = 1.0  # no band is split below this


@dataclass(frozen=True)
class Path:
    """Light of spectrum ``source`` through ``filters`` (internal transmittances at their thickness)
    ``passes`` thicknesses each, and off or through ``parts`` (reflectances), multiplied. The tracer
    takes a filter's band mean T̄ to the power d / t (Beer–Lambert, ``materials.absorption_per_mm``)
    where the light's T(λ)^(d/t) has the band mean of the power."""

    source: Spectrum
    filters: tuple[Spectrum, ...]
    parts: tuple[Spectrum, ...] = ()
    passes: float = 1.0

    @functools.cached_property
    def fine_cumulative(self) -> np.ndarray:
        """(801, 3) X, Y, Z on FINE summed from 380 nm to each of its edges, T(λ)^(d/t) in 0.5 nm bands."""
        per_band = _light(self, FINE)[:, None] * xyz_matrix(FINE)
        return np.vstack([np.zeros((1, 3)), np.cumsum(per_band, axis=0)])


def scene_paths(scene: dict) -> list[Path]:
    """Every source-to-eye product of a normalised photometric scene's spectra, each once: each bulb or
    LED array as if lit (so that a scene's lighting states share its bands, ``measures.states``), and the
    sun when it shines, through each lens's filter (and its plate's or guide's), with and without each
    reflector's finish, at each of ``PASSES``. Equal curves are one object (``_light``'s ``means``)."""
    sun = [daylight.daylight_spectrum(daylight.SUN_CCT_K)] if scene["light"]["illuminance_lux"] > 0 else []
    curves: list[Spectrum] = []

    def one(curve: Spectrum) -> Spectrum:
        same = next((c for c in curves if c == curve), None)
        if same is None:
            curves.append(curve)
        return same or curve

    products = []
    for sources, chains, finishes in _lamps(scene):
        for source in sources + sun:
            for chain in chains:
                for parts in [()] + [(finish,) for finish in finishes]:
                    product = (one(source), tuple(map(one, chain)), tuple(map(one, parts)))
                    if product not in products:
                        products.append(product)
    return [Path(*product, passes) for product in products for passes in PASSES]


def _lamps(scene: dict) -> list[tuple[list[Spectrum], list[tuple[Spectrum, ...]], list[Spectrum]]]:
    """Per lamp (a free-form design: one), (its lit sources, its filter chains, its reflectors' finishes)."""
    if "freeform" in scene:
        parts = [(f"freeform.parts[{i}].{part['role']}", part["role"], part[part["role"]])
                 for i, part in enumerate(scene["freeform"]["parts"])]
        sources = [spectral.bulb_spectrum(v, where)[1] for where, role, v in parts if role == "bulb"]
        # the LED dies of the design's lamps, traced beside the meshes (``freeform.leds``)
        sources += [spectral.led_spectrum(lamp["led"], f"lamps[{i}].led")
                    for i, lamp in enumerate(scene["lamps"]) if uses_leds(lamp)]
        chains = [(spectral.filter_curve(v, where),) for where, role, v in parts if role == "lens"] or [()]
        finishes = [_finish(v) for _, role, v in parts if role == "reflector"]
        return [(sources, chains, finishes)]
    out = []
    for i, lamp in enumerate(scene["lamps"]):
        where = f"lamps[{i}]"
        chain = [spectral.filter_curve(lamp["lens"], f"{where}.lens")]
        guide = lamp.get("light_guide", {})
        if guide.get("enabled"):
            chain.append(spectral.filter_curve(guide, f"{where}.light_guide"))
        elif lamp.get("collection", "reflector") == "prism_plate":
            chain.append(spectral.filter_curve(lamp["prism_plate"], f"{where}.prism_plate"))
        source = (spectral.led_spectrum(lamp["led"], f"{where}.led") if uses_leds(lamp)
                  else spectral.bulb_spectrum(lamp["bulb"], f"{where}.bulb")[1])
        out.append(([source], [tuple(chain)], [_finish(lamp["reflector"])]))
    return out


def _finish(reflector: dict) -> Spectrum:
    return materials.mirror_reflectance(spectral.FINISHES[reflector["finish"]])


def _light(path: Path, bands: Bands, means: dict[int, np.ndarray] | None = None) -> np.ndarray:
    """(K,) the path's band-mean light, its source scaled to luminance 1 in ``bands`` (as the tracer does).
    ``means`` keeps each curve's band means on ``bands`` by the curve's id, for the next path."""
    means = {} if means is None else means

    def mean(curve: Spectrum) -> np.ndarray:
        if id(curve) not in means:
            means[id(curve)] = curve.band_means(bands)
        return means[id(curve)]

    source = mean(path.source)
    luminance = float(source @ xyz_matrix(bands)[:, 1])
    # no visible light: no error to weigh (the render refuses the source, ``spectral.bulb_radiance``)
    light = source / luminance if luminance > 0 else np.zeros(bands.k)
    for curve in path.filters:
        light = light * np.maximum(mean(curve), spectral.MIN_TRANSMITTANCE) ** path.passes
    for curve in path.parts:
        light = light * mean(curve)
    return light


def _per_band(path: Path, bands: Bands, means: dict[int, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """((K, 3) X, Y, Z per band on ``bands``, (K, 3) the same from FINE), for one path."""
    cumulative = path.fine_cumulative
    fine = np.diff(np.stack([np.interp(bands.edges_nm, FINE.edges_nm, c) for c in cumulative.T], axis=1), axis=0)
    return _light(path, bands, means)[:, None] * xyz_matrix(bands), fine


def path_error(path: Path, bands: Bands, means: dict[int, np.ndarray] | None = None) -> tuple[float, float]:
    """(max |Δx|, |Δy| of the chromaticity, |ΔY| / Y) of ``path`` on ``bands`` against FINE."""
    coarse, fine = (a.sum(axis=0) for a in _per_band(path, bands, {} if means is None else means))
    if not fine[1] > 0:
        return 0.0, 0.0
    xy_coarse, xy_fine = coarse[:2] / coarse.sum(), fine[:2] / fine.sum()
    return float(np.abs(xy_coarse - xy_fine).max()), abs(float(coarse[1] / fine[1]) - 1.0)


def scene_error(paths: list[Path], bands: Bands) -> tuple[float, float]:
    """The worst (xy, relative luminance) error over ``paths`` on ``bands``."""
    means: dict[int, np.ndarray] = {}
    errors = [path_error(p, bands, means) for p in paths] or [(0.0, 0.0)]
    return max(e[0] for e in errors), max(e[1] for e in errors)


def meets(error: tuple[float, float], limits: tuple[float, float]) -> bool:
    return error[0] <= limits[0] and error[1] <= limits[1]


def refined(paths: list[Path], bands: Bands) -> Bands:
    """``bands`` with the bands that add most to the error halved, again until every path meets
    ``REFINE`` (or ``MAX_BANDS``): each band's share is |its X, Y, Z − FINE's over it| / Y."""
    while bands.k < MAX_BANDS and not meets(scene_error(paths, bands), REFINE):
        share, means = np.zeros(bands.k), {}
        for path in paths:
            coarse, fine = _per_band(path, bands, means)
            total = fine[:, 1].sum()
            if total > 0:
                share = np.maximum(share, np.abs(coarse - fine).max(axis=1) / total)
        split = (share >= 0.5 * share.max()) & (bands.widths_nm >= 2.0 * MIN_WIDTH_NM)
        if not split.any():
            break
        split_at = bands.centres_nm[split][: MAX_BANDS - bands.k]
        bands = Bands(np.sort(np.concatenate([bands.edges_nm, split_at])))
    return bands


def render_bands(scene: dict, k: int | None) -> Bands:
    """The bands a render traces: ``k`` uniform bands when the caller gives K (with a warning when they
    are too coarse for the scene's spectra, ``coarse_warning``), else ``scene_bands``."""
    if k is None:
        return scene_bands(scene)
    bands = Bands.uniform(int(k))
    warning = coarse_warning(scene, bands)
    if warning:
        warnings.warn(warning, stacklevel=2)
    return bands


def scene_bands(scene: dict) -> Bands:
    """The bands a normalised photometric scene is traced on: ``spectral.DEFAULT_BANDS`` uniform bands
    when every path of its light meets ``ACCEPT`` on them, else those bands ``refined`` where its light
    is. Kept per set of paths (a render makes a context in each of its worker processes; an edit of a
    lamp's shape keeps its spectra), found by their curves' values, so an edited CSV file counts."""
    paths = scene_paths(scene)
    key = hashlib.sha256(b"".join(
        np.concatenate([curve.wavelengths_nm, curve.values, [path.passes]]).tobytes()
        for path in paths for curve in (path.source, *path.filters, *path.parts))).hexdigest()
    if key not in _CHOSEN:
        if len(_CHOSEN) >= CHOSEN_KEPT:
            _CHOSEN.clear()
        default = Bands.uniform(spectral.DEFAULT_BANDS)
        _CHOSEN[key] = default if meets(scene_error(paths, default), ACCEPT) else refined(paths, default)
    return _CHOSEN[key]


def words(bands: Bands) -> str:
    """The bands in words, as the command line prints them: "40 bands", "55 bands of 2.5 to 10 nm"."""
    narrow, wide = float(bands.widths_nm.min()), float(bands.widths_nm.max())
    return f"{bands.k} bands" if wide - narrow < 1e-9 else f"{bands.k} bands of {narrow:g} to {wide:g} nm"


def look(scene: dict) -> str:
    """The bands a scene is traced on, in words for a thumbnail's name: "40 bands" for the default ones
    (every thumbnail made before the choice keeps its name), else K and a hash of the edges. A scene whose
    curves cannot be read says so (its thumbnail fails with the field's message when it is made)."""
    try:
        bands = scene_bands(scene)
    except SceneError:
        return "bands of unread curves"
    if bands == Bands.uniform(spectral.DEFAULT_BANDS):
        return f"{bands.k} bands"
    return f"{bands.k} bands {hashlib.sha256(bands.edges_nm.tobytes()).hexdigest()[:8]}"


_CHOSEN: dict[str, Bands] = {}  # ``scene_bands``'s, by a hash of the paths' curves
CHOSEN_KEPT = 64


def coarse_warning(scene: dict, bands: Bands) -> str | None:
    """A line saying that a user's ``bands`` miss ``ACCEPT`` on this scene (None when they meet it)."""
    xy, luminance = scene_error(scene_paths(scene), bands)
    if meets((xy, luminance), ACCEPT):
        return None
    return (f"{bands.k} bands are too coarse for this scene's spectra: up to {luminance * 100:.2f} % in luminance "
            f"and {xy:.4f} in xy off 0.5 nm bands (allowed {ACCEPT[1] * 100:g} % and {ACCEPT[0]:g}); "
            f"the default chooses {scene_bands(scene).k}")

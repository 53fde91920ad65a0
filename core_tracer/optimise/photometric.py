"""The measures of the photometric report as objectives and constraints (``measures.register``).

They need a design in the photometric light model (light in cd): a base in the paper's model asking
for one gets a one-line error when the file is read. What a trial's measures need is worked out on
the worker, in the trial's task (``figures``), at a cost kept small and stated:

- **Homogeneity** (``lmin_over_lmax``, ``lmin_over_lmean``, ``luminance_cv``, ``dark_fraction``):
  one orthographic luminance render of the lamp seen from H-V (``measures.intensity.view_along``),
  pixels of ``pixel_mm`` (default 1 mm: 232 x 132 px for the photometric stop lamp, 0.3-0.5 s),
  the lit lens the pixels whose lens is a lit lamp's of the ``function`` (default every lit lamp);
  the figures as ``measures.homogeneity`` gives them, blurred to what an eye at ``distance_m``
  (default 10 m) resolves.
- **Grid margin** (``grid_min_margin``): the lowest margin of the ``function``'s UN R148 01 series
  grid (``measures.regulation_grid``: every test point's minimum and the maximum over the 45-point
  field sweep; a margin is the share by which a value clears its limit, negative fails), from
  intensities by light tracing (``measures.light_tracing``, the estimator that gives every
  direction from one set of photons): ``photons`` per source and lamp (default 20,000; 3° cones).
  Its standard error at H-V is about 5 % of I there for the photometric stop lamp (6.6 cd of 132
  cd), so a margin within ±0.1 of 0 is uncertain; ``photons`` 4x halves it.
- **Colour** (``colour_distance``): the distance in CIE 1931 xy from the light's chromaticity at
  H-V to the nearest edge of the function's signal-colour region, positive inside, negative
  outside (UN R48 §2.29 and SAE J578, ``measures.colour``; the smaller of the two, or one of them
  by ``regulation``).
- **Total flux** (``total_flux``, lm): the luminous flux leaving the ``function``'s lamps in every
  direction, counted from the same photons as the grid (its standard error about 0.35 % at 20,000
  photons: 51.6 ± 0.18 lm of the stop lamp's 440 lm bulb).
- **Intensity at H-V** (``intensity_hv``, cd): the rendered estimator (``measures.intensity``,
  2 mm pixels, 2 shifted renders; about 1 % standard error).

The intensity and colour at H-V share one set of renders; every lit lamp's figures come from the
same renders (flat lenses split by lens), so the function's lamps are summed afterwards.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..measures.functions import FUNCTIONS
from ..scene.messages import show_value
from ..scene.reading import SceneError
from .registry import Measure, Trial, register

DEFAULT_FRONT_PIXEL_MM = 1.0
DEFAULT_PHOTONS = 20_000
MAX_PHOTONS = 2_000_000
CONE_DEG = 3.0
AXIS_PIXEL_MM = 2.0
AXIS_REPLICATES = 2
REGULATIONS = ("UN R48", "SAE J578")


@dataclass(frozen=True)
class Request:
    """What a trial's photometric measures need worked out on the worker (merged over them)."""

    front_pixel_mm: float | None = None  # a front luminance view at this pixel (homogeneity)
    grid_directions: tuple[tuple[float, float], ...] = ()  # light-traced intensities here
    photons: int = 0
    axis: bool = False  # the rendered intensity and colour at H-V
    flux: bool = False  # the light-traced flux leaving the lamps (from the same photons as the grid)

    def merge(self, other: Request) -> Request:
        pixels = [p for p in (self.front_pixel_mm, other.front_pixel_mm) if p is not None]
        directions = tuple(dict.fromkeys(self.grid_directions + other.grid_directions))
        return Request(min(pixels) if pixels else None, directions, max(self.photons, other.photons),
                       self.axis or other.axis, self.flux or other.flux)

    @property
    def traces(self) -> bool:
        return bool(self.grid_directions) or self.flux

    def __bool__(self) -> bool:
        return self.front_pixel_mm is not None or self.traces or self.axis


@dataclass
class Figures:
    """What ``figures`` returns from the worker: per lit lamp, so any function's lamps add up."""

    front_luminance: np.ndarray | None = None  # (H, W) cd/m²
    front_owner: np.ndarray | None = None  # (H, W) the lamp each pixel's lens belongs to (-1: none)
    front_pixel_mm: float = 0.0
    # lamp -> (h, v) -> (cd, variance), light-traced
    grid: dict[int, dict[tuple[float, float], tuple[float, float]]] = field(default_factory=dict)
    axis: dict[int, tuple[float, float, np.ndarray]] = field(default_factory=dict)  # lamp -> (cd, stderr, xyz)
    flux: dict[int, tuple[float, float]] = field(default_factory=dict)  # lamp -> (lm leaving, variance)
    seconds: dict[str, float] = field(default_factory=dict)


def lit_lamps(scene: dict) -> list[int]:
    return [i for i, lamp in enumerate(scene["lamps"]) if lamp["bulb"]["on"]]


def figures(scene: dict, request: Request) -> Figures:
    """The task's photometric work for one design (the worker runs it)."""
    import time

    from ..measures import intensity as I
    from ..measures.directions import direction
    from ..measures.light_tracing import traced_beam

    out = Figures()
    lamps = lit_lamps(scene)
    if request.front_pixel_mm is not None:
        start = time.perf_counter()
        view = I.view_along(scene, direction(0.0, 0.0), request.front_pixel_mm)
        out.front_luminance = I.render_view(I.measurement_scene(scene), view, threads=1)[..., 1].astype(np.float32)
        out.front_owner = I.lamp_of_pixels(scene, view).astype(np.int16)
        out.front_pixel_mm = request.front_pixel_mm
        out.seconds["front view"] = time.perf_counter() - start
    if request.traces and lamps:
        start = time.perf_counter()
        directions = list(request.grid_directions) or [(0.0, 0.0)]
        per_lamp, flux = traced_beam(scene, directions, [[i] for i in lamps], photons=request.photons,
                                     cone_deg=CONE_DEG, seed=0)
        for i, values, (lm, err) in zip(lamps, per_lamp, flux, strict=True):
            if request.grid_directions:
                out.grid[i] = {d: (v.cd, v.stderr ** 2) for d, v in zip(directions, values, strict=True)}
            if request.flux:
                out.flux[i] = (lm, err ** 2)
        out.seconds["light tracing"] = time.perf_counter() - start
    if request.axis and lamps:
        start = time.perf_counter()
        values = I.rendered_intensities(scene, 0.0, 0.0, [[i] for i in lamps], pixel_mm=AXIS_PIXEL_MM,
                                        replicates=AXIS_REPLICATES, seed=0, threads=1)
        out.axis = {i: (v.cd, v.stderr, np.asarray(v.xyz)) for i, v in zip(lamps, values, strict=True)}
        out.seconds["H-V"] = time.perf_counter() - start
    return out


# ---------------------------------------------------------------------------------------------
# Options


@dataclass(frozen=True)
class Prepared:
    request: Request
    function: str | None
    options: dict


def _function(options: dict, where: str) -> str | None:
    name = options.get("function")
    if name is None:
        return None
    if name not in FUNCTIONS:
        raise SceneError(f"{where}.function", f"{show_value(name)} is not a lamp function; allowed "
                                              f"{', '.join(FUNCTIONS)}")
    return name


def _positive(options: dict, key: str, where: str, default: float, lo: float, hi: float) -> float:
    value = options.get(key, default)
    if isinstance(value, bool) or not isinstance(value, int | float) or not lo <= value <= hi:
        raise SceneError(f"{where}.{key}", f"{show_value(value)} is out of range; allowed {lo:g} to {hi:g}")
    return float(value)


def _prepare_homogeneity(options: dict, where: str, folder: str) -> Prepared:
    pixel = _positive(options, "pixel_mm", where, DEFAULT_FRONT_PIXEL_MM, 0.1, 10.0)
    return Prepared(Request(front_pixel_mm=pixel), _function(options, where),
                    {"distance_m": _positive(options, "distance_m", where, 10.0, 0.5, 1000.0),
                     "dark_below": _positive(options, "dark_below", where, 0.5, 0.01, 0.99)})


def _photons(options: dict, where: str) -> int:
    photons = options.get("photons", DEFAULT_PHOTONS)
    if isinstance(photons, bool) or not isinstance(photons, int) or not 1000 <= photons <= MAX_PHOTONS:
        raise SceneError(f"{where}.photons", f"{show_value(photons)} is out of range; allowed a whole number "
                                             f"1000 to {MAX_PHOTONS}")
    return photons


def _prepare_flux(options: dict, where: str, folder: str) -> Prepared:
    return Prepared(Request(photons=_photons(options, where), flux=True), _function(options, where), {})


def _prepare_grid(options: dict, where: str, folder: str) -> Prepared:
    from ..measures import regulation_grid
    function = _function(options, where)
    photons = _photons(options, where)
    keys = [FUNCTIONS[function][0]] if function else [FUNCTIONS[f][0] for f in FUNCTIONS]
    directions = tuple(dict.fromkeys(d for key in keys for d in regulation_grid.directions_for(key)))
    return Prepared(Request(grid_directions=directions, photons=photons), function, {})


def _prepare_axis(options: dict, where: str, folder: str) -> Prepared:
    regulation = options.get("regulation")
    if regulation is not None and regulation not in REGULATIONS:
        raise SceneError(f"{where}.regulation", f"{show_value(regulation)} is not a colour regulation; allowed "
                                                f"{', '.join(REGULATIONS)}")
    return Prepared(Request(axis=True), _function(options, where), {"regulation": regulation})


# ---------------------------------------------------------------------------------------------
# The measures


def function_lamps(scene: dict, function: str | None) -> dict[str, list[int]]:
    """{function: its lit lamps}; ``function`` None: every lit lamp's function."""
    from ..measures.report import lamp_function

    out: dict[str, list[int]] = {}
    for i in lit_lamps(scene):
        name = lamp_function(scene["lamps"][i])
        if name is not None and (function is None or name == function):
            out.setdefault(name, []).append(i)
    return out


def _lamps(trial: Trial, function: str | None) -> list[int]:
    if function is None:
        return lit_lamps(trial.scene)
    return function_lamps(trial.scene, function).get(function, [])


def _homogeneity(trial: Trial, prepared: Prepared):
    from ..measures.homogeneity import homogeneity

    f = trial.figures
    mask = np.isin(f.front_owner, _lamps(trial, prepared.function)) & (f.front_luminance > 0)
    if not mask.any():
        return None
    return homogeneity(f.front_luminance, mask, f.front_pixel_mm, **prepared.options)


def _lmin_over_lmax(trial: Trial, prepared: Prepared) -> float:
    h = _homogeneity(trial, prepared)
    return h.uniformity_min_max if h else 0.0


def _lmin_over_lmean(trial: Trial, prepared: Prepared) -> float:
    h = _homogeneity(trial, prepared)
    return h.uniformity_min_mean if h else 0.0


def _cv(trial: Trial, prepared: Prepared) -> float:
    h = _homogeneity(trial, prepared)
    return h.cv if h else math.inf


def _dark_fraction(trial: Trial, prepared: Prepared) -> float:
    h = _homogeneity(trial, prepared)
    return h.dark_fraction if h else 1.0


def _summed(grid: dict, lamps: list[int]):
    def at(h: float, v: float) -> tuple[float, float]:
        cd = sum(grid[i][(h, v)][0] for i in lamps)
        return cd, math.sqrt(sum(grid[i][(h, v)][1] for i in lamps))
    return at


def grid_rows(trial: Trial, prepared: Prepared) -> list:
    """The UN R148 rows of each function asked for (``regulation_grid.check``)."""
    from ..measures import regulation_grid
    rows = []
    for name, lamps in function_lamps(trial.scene, prepared.function).items():
        key = FUNCTIONS[name][0]
        at = _summed(trial.figures.grid, lamps)
        rows += regulation_grid.check(key, {d: at(*d) for d in regulation_grid.directions_for(key)})
    return rows


def _grid_min_margin(trial: Trial, prepared: Prepared) -> float:
    rows = grid_rows(trial, prepared)
    return min((r.margin for r in rows), default=-1.0)  # no lit lamp of the function: it fails


def _axis(trial: Trial, prepared: Prepared) -> tuple[float, np.ndarray]:
    lamps = _lamps(trial, prepared.function)
    cd = sum(trial.figures.axis[i][0] for i in lamps)
    xyz = sum((trial.figures.axis[i][2] for i in lamps), np.zeros(3))
    return float(cd), xyz


def _intensity_hv(trial: Trial, prepared: Prepared) -> float:
    return _axis(trial, prepared)[0]


def _total_flux(trial: Trial, prepared: Prepared) -> float:
    return float(sum(trial.figures.flux[i][0] for i in _lamps(trial, prepared.function)))


def signed_distance(xy, corners) -> float:
    """Distance in xy from ``xy`` to the polygon's nearest edge: positive inside, negative outside."""
    from ..measures import colour

    p = np.asarray(xy, dtype=np.float64)
    poly = np.asarray(corners, dtype=np.float64)
    a, b = poly, np.roll(poly, -1, axis=0)
    ab = b - a
    t = np.clip(((p - a) * ab).sum(axis=1) / (ab * ab).sum(axis=1), 0.0, 1.0)
    nearest = float(np.min(np.linalg.norm(a + t[:, None] * ab - p, axis=1)))
    return nearest if colour.inside(p, corners) else -nearest


def _colour_distance(trial: Trial, prepared: Prepared) -> float:
    from ..measures import colour
    _, xyz = _axis(trial, prepared)
    if not xyz.sum() > 0:
        return -1.0  # no light: no colour, outside every region
    xy = colour.xy_of(xyz)
    names = list(function_lamps(trial.scene, prepared.function)) or ["stop"]
    regions = {"UN R48": colour.REGIONS["UN R48 §2.29"], "SAE J578": colour.REGIONS["SAE J578"]}
    wanted = [prepared.options["regulation"]] if prepared.options["regulation"] else list(regions)
    return min(signed_distance(xy, regions[r][FUNCTIONS[n][2]]) for r in wanted for n in names)


def _request(prepared: Prepared) -> Request:
    return prepared.request


HOMOGENEITY_OPTIONS = ("function", "pixel_mm", "distance_m", "dark_below")
for _name, _goal, _words, _compute in (
        ("lmin_over_lmax", "maximise", "Lmin/Lmax of the lit lens seen from H-V (eye-resolved)", _lmin_over_lmax),
        ("lmin_over_lmean", "maximise", "Lmin/Lmean of the lit lens seen from H-V (eye-resolved)", _lmin_over_lmean),
        ("luminance_cv", "minimise", "coefficient of variation of the lit lens's luminance seen from H-V",
         _cv),
        ("dark_fraction", "minimise", "share of the lit lens below half its mean luminance (dark areas)",
         _dark_fraction)):
    register(Measure(_name, "", _words, False, _compute, _prepare_homogeneity, HOMOGENEITY_OPTIONS,
                     goal=_goal, request=_request))
register(Measure("grid_min_margin", "", "lowest margin over the function's UN R148 grid (>= 0: every point met; "
                 "light-traced)", False, _grid_min_margin, _prepare_grid, ("function", "photons"),
                 request=_request))
register(Measure("total_flux", "lm", "luminous flux leaving the lamps, every direction (light-traced)", False,
                 _total_flux, _prepare_flux, ("function", "photons"), request=_request))
register(Measure("intensity_hv", "cd", "luminous intensity at H-V (rendered, about 1 % standard error)", False,
                 _intensity_hv, _prepare_axis, ("function",), request=_request))
register(Measure("colour_distance", "xy", "distance inside the signal colour's region at H-V (UN R48, SAE J578; "
                 "negative outside)", False, _colour_distance, _prepare_axis, ("function", "regulation"),
                 request=_request))


"""The measures of a design, together: each lamp's function, its regulation grids (UN R148 and FMVSS
108), the stop/tail ratios, the colour of each function's light, the homogeneity of each lit lens,
and a one-page picture of them (``measures.json`` and ``measures.png``).

Which function a lamp serves: its ``function`` field; for a "custom" lamp, its lens filter and bulb
filament: amber → turn, clear → reversing, red with a bulb on its tail filament → tail, other red →
stop (the four-lamp presets' lamps are custom and follow this). ``functions`` overrides it.
"""

from __future__ import annotations

import datetime
import json
import math
import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from .. import budget
from . import colour, export, page, regulation_grid
from .directions import direction
from .functions import FUNCTIONS, NOTE
from .homogeneity import DEFAULT_DISTANCE_M, homogeneity
from .intensity import lamp_of_pixels, measured_together, measurement_scene, render_view, view_along

if TYPE_CHECKING:
    from ..freeform.design import DesignMeshes

SCHEMA = "lamp-measures/1"  # measures.json's format; readers of earlier files (no schema) still read them


def lamp_function(lamp: dict) -> str | None:
    """What a lamp is for, from its ``function`` or (custom) its lens filter and bulb filament; None
    for a function without a rear-signal regulation here (position, fog)."""
    declared = lamp.get("function", "custom")
    if declared != "custom":
        return declared if declared in FUNCTIONS else None
    lens_filter = lamp["lens"].get("filter", "clear")
    if lens_filter == "amber":
        return "turn"
    if lens_filter == "clear":
        return "reversing"
    return "tail" if lamp["bulb"].get("state") == "tail" else "stop"


@dataclass
class Measures:
    """What ``measure`` found (``as_dict`` is measures.json)."""

    scene_name: str
    functions: dict[str, list[int]]
    rows: list[regulation_grid.Row]
    colours: dict[str, dict]
    homogeneity: dict[str, dict]
    intensities: dict[str, dict[tuple[float, float], tuple[float, float]]]
    seconds: dict[str, float]
    pixel_mm: float
    front_view: dict = field(default_factory=dict)  # luminance image, mask and blurred map for the picture
    scene_digest: str = ""  # library.presets.digest of the scene measured: which design these figures are of
    date: str = ""  # when it was measured, UTC, ISO 8601
    beams: dict[str, export.Distribution] = field(default_factory=dict)  # each function's beam file, when asked

    def verdicts(self) -> dict[str, bool]:
        out: dict[str, bool] = {}
        for r in self.rows:
            out[r.function] = out.get(r.function, True) and r.passed
        return out

    def as_dict(self) -> dict:
        from .. import __version__

        return {
            "schema": SCHEMA, "tool": {"name": "core_tracer", "version": __version__}, "date": self.date,
            "scene": self.scene_name, "scene_digest": self.scene_digest, "note": NOTE,
            "sources": {k: v["document"] for k, v in regulation_grid.data()["sources"].items()},
            "functions": {name: {"lamps": lamps, "regulations": list(FUNCTIONS[name][:2]),
                                 "colour": self.colours.get(name)} for name, lamps in self.functions.items()},
            "verdicts": self.verdicts(),
            "failed": [r.as_dict() for r in self.rows if not r.passed],
            "rows": [r.as_dict() for r in self.rows],
            "homogeneity": self.homogeneity,
            "intensities_cd": {name: [[h, v, cd, err] for (h, v), (cd, err) in sorted(values.items())]
                               for name, values in self.intensities.items()},
            "seconds": self.seconds, "pixel_mm": self.pixel_mm,
        }


def largest_view(scene: dict, pixel_mm: float = 2.0, front_pixel_mm: float = 0.5) -> tuple[int, int]:
    """(width, height) px of the largest view ``measure`` renders: the front view at ``front_pixel_mm``,
    or a view at ``pixel_mm`` from a direction of the beam files' (C, γ) sweep, which spans every
    direction the regulation grids read too (γ up to 90°: side views included)."""
    views = [view_along(scene, direction(0.0, 0.0), front_pixel_mm)]
    for c in range(0, 360, 30):
        for gamma in range(0, 91, 10):
            h, v = export.angles_of(export.gonio_direction(float(c), float(gamma)))
            views.append(view_along(scene, direction(float(h), float(v)), pixel_mm))
    view = max(views, key=lambda w: w.width * w.height)
    return view.width, view.height


def check_memory(scene: dict, pixel_mm: float = 2.0, front_pixel_mm: float = 0.5) -> None:
    """Refuse, before anything is rendered, a ``measure`` past the memory budget (``budget.check_measure``)."""
    budget.check_measure(*largest_view(scene, pixel_mm, front_pixel_mm))


def measure(scene: dict, *, functions: dict[int, str] | None = None, pixel_mm: float = 2.0, replicates: int = 2,
            distance_m: float = DEFAULT_DISTANCE_M, front_pixel_mm: float = 0.5,
            progress: Callable[[str], None] | None = None, meshes: DesignMeshes | None = None,
            beams: export.BeamGrid | None = None, photons: int = export.TRACED_PHOTONS) -> Measures:
    """Every measure of a photometric design (module docstring); a free-form design's on its
    ``meshes``, measured whole as one lamp of the function of its first lamp (``--function 0=NAME``
    names another), its bulbs as its parts have them. With ``beams``, also each function's beam file
    on that grid (``export.measure_distributions``, its flux out traced with ``photons``).

    One sweep on the local pool (``intensity.measured_together``) measures the regulation grids'
    directions and the beam files' together, each at the seed it has alone (the same figures bit for
    bit), with the flux out's light tracing and the front view as tasks beside them."""
    say = progress or (lambda text: None)
    measurement_scene(scene)  # refuses a paper-mode scene at once, naming light_model
    _band_pool(PICTURE_WIDTH, PICTURE_WIDTH)  # started now, its workers are ready for lamp_picture
    by_function: dict[str, list[int]] = {}
    freeform = "freeform" in scene
    for i, lamp in enumerate(scene["lamps"][:1] if freeform else scene["lamps"]):
        name = (functions or {}).get(i) or lamp_function(lamp)
        if name is not None and (lamp["bulb"]["on"] or freeform):
            by_function.setdefault(name, []).append(i)
    names = list(by_function)
    groups = [by_function[n] for n in names]
    seconds: dict[str, float] = {}

    start = time.perf_counter()
    wanted: dict[tuple[float, float], None] = {}
    for name in names:
        for key in FUNCTIONS[name][:2]:
            wanted.update(dict.fromkeys(regulation_grid.directions_for(key)))
    grid_points = list(wanted)
    beam_points = export.beam_directions(beams) if beams is not None and names else []
    # A direction both read (17 of the default grid's: on the H and V axes) is measured twice, each at
    # its own seed: read once, the beam file's nodes there moved by their estimates' scatter (up to 13
    # of the two-replicate standard errors: benchmarks/RESULTS.md) for 1.6 % of the sweep's time.
    seeds = list(range(len(grid_points))) + [0] * len(beam_points)  # each sweep's seeds, as alone
    view = view_along(scene, direction(0.0, 0.0), front_pixel_mm)
    tasks = [(render_view, (measurement_scene(scene), view, None, 1 if meshes is None else None, meshes))]
    task_bytes = budget.WORKER_BYTES + budget.render_bytes(view.width, view.height, False, "exr") - budget.BASE_BYTES
    if beam_points and photons:
        tasks.append((export.traced_flux, (scene, groups, photons)))
        task_bytes = max(task_bytes, export.TRACED_FLUX_BYTES)
    measured: dict[str, dict] = {n: {} for n in names}
    xyz_at_axis: dict[str, np.ndarray] = {}

    def counted(done: int, total: int) -> None:
        if done % 10 == 0 and done < total:
            say(f"intensity: direction {done + 1} of {total}")

    say(f"intensity: direction 1 of {len(grid_points) + len(beam_points)}")
    values, done = measured_together(scene, grid_points + beam_points, groups, tasks=tasks,
                                     task_bytes=task_bytes, seeds=seeds,
                                     progress=counted, pixel_mm=pixel_mm, replicates=replicates,
                                     meshes=meshes)  # the local pool
    for (h, v), at in zip(grid_points, values, strict=False):
        for name, value in zip(names, at, strict=True):
            measured[name][(h, v)] = (value.cd, value.stderr)
            if (h, v) == (0.0, 0.0):
                xyz_at_axis[name] = value.xyz
    seconds["intensity"] = time.perf_counter() - start

    start = time.perf_counter()
    rows: list[regulation_grid.Row] = []
    for name in names:
        for key in FUNCTIONS[name][:2]:
            rows += regulation_grid.check(key, measured[name])
    if "stop" in measured and "tail" in measured:
        rows += regulation_grid.check_ratio("R148 stop/position 5:1", measured["stop"], measured["tail"])
        rows += regulation_grid.check_ratio("FMVSS stop/taillamp", measured["stop"], measured["tail"])
    seconds["regulation grid"] = time.perf_counter() - start

    start = time.perf_counter()
    colours = {}
    for name in names:
        xy = colour.xy_of(xyz_at_axis[name])
        wanted_colour = FUNCTIONS[name][2]
        verdict = colour.check(xy, wanted_colour)
        colours[name] = {"xy": [float(xy[0]), float(xy[1])], "required": wanted_colour, "inside": verdict,
                         "direction": "H-V"}
    seconds["colour"] = time.perf_counter() - start

    start = time.perf_counter()
    say("homogeneity: front view")
    luminance = done[0][..., 1]  # the front view, rendered on the pool beside the directions
    owner = lamp_of_pixels(scene, view)
    lit = {}
    dark = np.zeros(luminance.shape, bool)
    blurred = np.full(luminance.shape, np.nan)
    for name, lamps in by_function.items():
        mask = np.isin(owner, lamps) & (luminance > 0)
        if mask.any():
            figures = homogeneity(luminance, mask, front_pixel_mm, distance_m=distance_m)
            lit[name] = figures.as_dict()
            dark |= figures.dark
            blurred[mask] = figures.blurred[mask]
    seconds["homogeneity"] = time.perf_counter() - start
    front = {"luminance": luminance, "blurred": blurred, "dark": dark, "pixel_mm": front_pixel_mm}
    distributions = {}
    if beam_points:
        say("beam files: from the sweep's directions")
        distributions = export.distributions(scene, names, groups, beams, values[len(grid_points):],
                                             done[1] if photons else None)
    from ..library.presets import digest

    date = datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds")
    return Measures(scene.get("name", ""), by_function, rows, colours, lit, measured, seconds, pixel_mm, front,
                    digest(scene), date, distributions)


def write_json(result: Measures, path: str | os.PathLike) -> None:
    """measures.json as strict JSON (RFC 8259): a figure that is missing (a standard error from one
    replicate, a margin against a limit of 0) is null, never NaN or Infinity, which strict readers refuse."""
    tmp = f"{os.fspath(path)}.part"
    with open(tmp, "w", encoding="utf-8") as f:
        json.dump(strict(result.as_dict()), f, indent=1, ensure_ascii=False, allow_nan=False)
    os.replace(tmp, path)


def strict(value):
    """``value`` with numpy numbers and arrays made plain and every non-finite float made None."""
    if isinstance(value, dict):
        return {k: strict(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [strict(v) for v in value]
    if isinstance(value, np.ndarray):
        return strict(value.tolist())
    if isinstance(value, (np.floating, np.integer, np.bool_)):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


# ---------------------------------------------------------------------------------------------
# The page


def write_page(result: Measures, path: str | os.PathLike, lamp_image: np.ndarray | None = None) -> None:
    """The one-page report: the rendered lamp, the front luminance with homogeneity figures, each
    function's UN R148 grid in pass/fail colours, and the chromaticity diagram (``page``: numpy only,
    as a real Blender's Python has it)."""
    page.write(result, path, lamp_image)


def _band_pool(width: int, height: int):
    """The band pool for the picture, when its workers fit the memory budget beside this process
    (``budget.render_bytes``) and this process is not itself a worker: a measure lasts long enough
    for the pool's 0.2 s start-up to pay even below ``budget.POOL_RAYS``; None: threads."""
    import multiprocessing
    import os

    from ..raytrace import band_pool

    workers = os.cpu_count() or 1
    if workers < 2 or multiprocessing.parent_process() is not None or \
            budget.render_bytes(width, height, False, "exr", workers=workers) > budget.MEMORY_BUDGET:
        return None
    return band_pool.shared()


PICTURE_WIDTH = 520


def lamp_picture(scene: dict, width: int = PICTURE_WIDTH, meshes: DesignMeshes | None = None) -> np.ndarray:
    """The design as its camera sees it (photometric render, the scene's exposure, the lamp view
    ``display.LAMP_VIEW``, through ``display.shown``), as display RGB in [0, 1]; a free-form design's on
    its ``meshes``."""
    from ..images import display
    from ..raytrace.engine import render_passes

    height = max(1, round(width * scene["image"]["height"] / scene["image"]["width"]))
    samples = min(4, scene["image"]["samples"])
    if meshes is not None and "freeform" in scene:
        image = meshes.render_passes(scene, width, height, samples=samples).image
    else:
        pool = _band_pool(width, height)
        image = render_passes(scene, width, height, keep_passes=False, samples=samples, pool=pool).image
    return display.shown(image, scene, view=display.view_transform(display.LAMP_VIEW)).pixels[0]

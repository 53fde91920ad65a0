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

import numpy as np

from . import colour, regulation_grid
from .directions import direction
from .homogeneity import DEFAULT_DISTANCE_M, homogeneity
from .intensity import lamp_of_pixels, measurement_scene, render_view, rendered_intensities, view_along

# function -> (UN R148 key, FMVSS 108 key, signal colour)
FUNCTIONS: dict[str, tuple[str, str, str]] = {
    "tail": ("R148 R1", "FMVSS taillamp", "red"),
    "stop": ("R148 S1", "FMVSS stop", "red"),
    "turn": ("R148 2a", "FMVSS rear turn amber", "amber"),
    "reversing": ("R148 AR", "FMVSS backup", "white"),
}
SCHEMA = "lamp-measures/1"  # measures.json's format; readers of earlier files (no schema) still read them
NOTE = ("Simulated figures of a design, for choosing between variants; a homologation laboratory's measurement "
        "of a built lamp decides approval.")


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


def measure(scene: dict, *, functions: dict[int, str] | None = None, pixel_mm: float = 2.0, replicates: int = 2,
            distance_m: float = DEFAULT_DISTANCE_M, front_pixel_mm: float = 0.5,
            progress: Callable[[str], None] | None = None) -> Measures:
    """Every measure of a photometric design (module docstring)."""
    say = progress or (lambda text: None)
    measurement_scene(scene)  # refuses a paper-mode scene at once, naming light_model
    by_function: dict[str, list[int]] = {}
    for i, lamp in enumerate(scene["lamps"]):
        name = (functions or {}).get(i) or lamp_function(lamp)
        if name is not None and lamp["bulb"]["on"]:
            by_function.setdefault(name, []).append(i)
    names = list(by_function)
    groups = [by_function[n] for n in names]
    seconds: dict[str, float] = {}

    start = time.perf_counter()
    wanted: dict[tuple[float, float], None] = {}
    for name in names:
        for key in FUNCTIONS[name][:2]:
            wanted.update(dict.fromkeys(regulation_grid.directions_for(key)))
    measured: dict[str, dict] = {n: {} for n in names}
    xyz_at_axis: dict[str, np.ndarray] = {}
    for k, (h, v) in enumerate(wanted):
        if k % 10 == 0:
            say(f"intensity: direction {k + 1} of {len(wanted)}")
        for name, value in zip(names, rendered_intensities(scene, h, v, groups, pixel_mm=pixel_mm,
                                                           replicates=replicates, seed=k), strict=True):
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
    view = view_along(scene, direction(0.0, 0.0), front_pixel_mm)
    image = render_view(measurement_scene(scene), view)
    luminance = image[..., 1]
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
    from ..library.presets import digest

    date = datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds")
    return Measures(scene.get("name", ""), by_function, rows, colours, lit, measured, seconds, pixel_mm, front,
                    digest(scene), date)


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
    function's UN R148 grid in pass/fail colours, and the chromaticity diagram (matplotlib)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(result.functions)
    fig = plt.figure(figsize=(16.5, 11.7), dpi=110)  # A3 landscape
    grid = fig.add_gridspec(3, 4, height_ratios=[1.0, 1.0, 1.05], hspace=0.42, wspace=0.28)
    verdicts = result.verdicts()
    failed = [r for r in result.rows if not r.passed]
    title = f"Measures of \u201c{result.scene_name}\u201d"
    passed = [k for k, ok in verdicts.items() if ok]
    failing = [k for k, ok in verdicts.items() if not ok]
    summary = (f"FAILS {', '.join(failing)}" if failing else "passes every check") + (
        f"   |   passes {', '.join(passed)}" if failing and passed else "")
    fig.suptitle(f"{title}\n{summary}", fontsize=12, x=0.02, ha="left", color="#b0201a" if failing else "black")
    fig.text(0.02, 0.005, NOTE + " Sources: UN R148 01 series (ECE/TRANS/WP.29/2022/92), FMVSS 108 (49 CFR "
             "571.108), UN R48 §2.29, SAE J578 — docs/measures.md.", fontsize=8, color="0.3")

    ax = fig.add_subplot(grid[0, 0:2])
    if lamp_image is not None:
        ax.imshow(lamp_image)
    ax.set_title("the design (photometric render)")
    ax.axis("off")

    ax = fig.add_subplot(grid[0, 2:4])
    lum = result.front_view["luminance"]
    shown = np.log10(np.maximum(lum, 1.0))
    im = ax.imshow(shown, cmap="inferno", vmin=0.0, vmax=max(1.0, float(np.nanmax(shown))))
    if result.front_view["dark"].any():
        ax.contour(result.front_view["dark"], levels=[0.5], colors="cyan", linewidths=0.8)
    cbar = fig.colorbar(im, ax=ax, fraction=0.025)
    cbar.set_label("log10 luminance, cd/m²")
    lines = []
    for name, h in result.homogeneity.items():
        lines.append(f"{name}: Lmin/Lmax {h['lmin_over_lmax']:.2f}  Lmin/Lmean {h['lmin_over_lmean']:.2f}  "
                     f"CV {h['cv']:.2f}  dark {100 * h['dark_fraction']:.0f} %")
    some = next(iter(result.homogeneity.values()), None)
    where = (f"at {some['viewing_distance_m']:g} m (eye resolves {some['eye_resolution_mm']:.1f} mm); cyan: below "
             f"{some['dark_below_fraction_of_mean']:g} × mean") if some else ""
    ax.set_title(f"front view from H-V: luminance; homogeneity {where}", fontsize=9)
    ax.text(0.0, -0.04, "\n".join(lines), transform=ax.transAxes, fontsize=8, va="top", family="monospace")
    ax.axis("off")

    for k, name in enumerate(names[:4]):
        key = FUNCTIONS[name][0]
        ax = fig.add_subplot(grid[1, k])
        _grid_plot(ax, [r for r in result.rows if r.function == key], f"{name}: {key}")

    ax = fig.add_subplot(grid[2, 0:2])
    _chromaticity_plot(ax, result)

    ax = fig.add_subplot(grid[2, 2:4])
    ax.axis("off")
    fmvss = [(name, FUNCTIONS[name][1]) for name in names]
    text = ["FMVSS 108 and ratios:"]
    for name, key in fmvss:
        rows = [r for r in result.rows if r.function == key]
        bad = [r for r in rows if not r.passed]
        text.append(f"  {name} ({key}): {'pass' if not bad else 'FAIL'}, {len(rows)} checks"
                    + (f"; fails {', '.join(f'{r.point} {r.kind}' for r in bad[:4])}" if bad else ""))
    for key in ("R148 stop/position 5:1", "FMVSS stop/taillamp"):
        rows = [r for r in result.rows if r.function == key]
        if rows:
            worst = min(rows, key=lambda r: r.margin)
            text.append(f"  {key}: {'pass' if all(r.passed for r in rows) else 'FAIL'}, lowest "
                        f"{worst.simulated:.1f} at {worst.point} (needs {worst.required:g}); applies where "
                        "the lamps are combined")
    text.append("")
    text.append(f"failed points ({len(failed)}):")
    for r in failed[:14]:
        text.append(f"  {r.function} {r.point} {r.kind}: {r.simulated:.3g} cd vs {r.required:.3g} "
                    f"({100 * r.margin:+.0f} %)")
    text.append("")
    text.append("times: " + ", ".join(f"{k} {v:.1f} s" for k, v in result.seconds.items()))
    ax.text(0.0, 1.0, "\n".join(text), va="top", fontsize=8.5, family="monospace")

    fig.savefig(os.fspath(path), dpi=110)
    plt.close(fig)


def _grid_plot(ax, rows, title: str) -> None:
    """A regulation grid's points at (H, V): green where they pass, red where they fail (a red edge
    where a maximum fails there); the simulated and required cd written in the cell."""
    points = [r for r in rows if r.kind == "min" and r.h is not None]
    maxima = [r for r in rows if r.kind == "max"]
    over = {(r.h, r.v) for r in maxima if not r.passed}
    if points:
        hs = [r.h for r in points]
        vs = [r.v for r in points]
        width = max(hs) - min(hs) + 8
        ax.set_xlim(min(hs) - 4, max(hs) + 4)
        ax.set_ylim(min(vs) - 3, max(vs) + 3)
        cell = 4.8 * max(1.0, width / 48.0)  # the cells keep their look on a wider grid (the reversing lamp's)
        for r in points:
            ax.add_patch(_cell(r.h, r.v, cell, 4.8,
                               "#3a9a4a" if r.passed else "#d0342c", "#ff2020" if (r.h, r.v) in over else "white"))
            ax.text(r.h, r.v + 0.9, f"{r.simulated:.3g}", ha="center", va="center", fontsize=6.5, color="white")
            ax.text(r.h, r.v - 1.1, f"≥{r.required:.3g}", ha="center", va="center", fontsize=5.5, color="white")
    worst = min(maxima, key=lambda r: r.margin, default=None)
    ok = all(r.passed for r in rows)
    extra = f"\nmax {worst.simulated:.3g} cd at {worst.point}, limit {worst.required:g}" if worst else ""
    ax.set_title(f"{title}: {'pass' if ok else 'FAIL'}{extra}", fontsize=9, color="black" if ok else "#b0201a")
    ax.set_xlabel("H, degrees")
    ax.set_ylabel("V, degrees")
    ax.grid(True, color="0.9")


def _cell(h, v, width, height, face, edge):
    from matplotlib.patches import Rectangle

    return Rectangle((h - width / 2, v - height / 2), width, height, facecolor=face, edgecolor=edge, linewidth=1.5)


def _chromaticity_plot(ax, result: Measures) -> None:
    from ..photometry.cie import cmfs

    wavelengths, bars = cmfs()
    keep = (wavelengths >= 380) & (wavelengths <= 700)
    locus = bars[keep] / bars[keep].sum(axis=1, keepdims=True)
    ax.plot(np.append(locus[:, 0], locus[0, 0]), np.append(locus[:, 1], locus[0, 1]), color="0.4", lw=1)
    styles = {"UN R48 §2.29": ("-", 1.4), "SAE J578": ("--", 1.0)}
    tints = {"red": "#c0392b", "amber": "#e08e0b", "white": "#7f8c8d"}
    for name, regions in colour.REGIONS.items():
        for col, corners in regions.items():
            poly = np.asarray(corners + (corners[0],))
            ax.plot(poly[:, 0], poly[:, 1], styles[name][0], lw=styles[name][1], color=tints[col],
                    label=f"{name} {col}" if name == "UN R48 §2.29" else None)
    for k, (fname, c) in enumerate(result.colours.items()):
        x, y = c["xy"]
        ok = all(c["inside"].values())
        ax.plot(x, y, "o", ms=7, mfc=tints[c["required"]], mec="black" if ok else "red", mew=1.5)
        ax.annotate(f"{fname} ({x:.3f}, {y:.3f}) {'in' if ok else 'OUT'}", (x, y), textcoords="offset points",
                    xytext=(8, 10 - 12 * k), fontsize=8)
    ax.set_xlim(0.25, 0.75)
    ax.set_ylim(0.2, 0.5)
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.set_title("colour at H-V (CIE 1931): UN R48 §2.29 solid, SAE J578 dashed", fontsize=9)
    ax.legend(fontsize=7, loc="upper left")
    ax.grid(True, color="0.92")


def lamp_picture(scene: dict, width: int = 520) -> np.ndarray:
    """The design as its camera sees it (photometric render, the scene's exposure, Blender's default
    view), as display RGB in [0, 1]."""
    from ..images import display
    from ..raytrace import spectral
    from ..raytrace.engine import render_passes

    height = max(1, round(width * scene["image"]["height"] / scene["image"]["width"]))
    image = render_passes(scene, width, height, keep_passes=False, samples=min(4, scene["image"]["samples"])).image
    ev100 = spectral.exposure_ev100(image, scene)
    return display.view_transform().to_display(spectral.display_linear(image, ev100))

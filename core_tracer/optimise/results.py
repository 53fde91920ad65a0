"""What an optimisation leaves: the best design (or each design of the Pareto front) as a preset,
a contact sheet of the best trials with their measures, the history plot, and every trial's
figures in ``trials.json``; all in one folder, each file written atomically."""

from __future__ import annotations

import json
import math
import os
from collections.abc import Sequence

import numpy as np

from ..cluster.cache import CellCache
from ..cluster.cells import Inputs, make_cell
from ..fileio import atomic_path, atomic_write_text
from ..images import bitmap_font, display, labels
from ..images.imageio import write_display
from ..scene.reading import scene_to_json
from ..study.definition import format_value
from . import storage
from . import trials as T
from .spec import Optimisation

SHEET_TRIALS = 8
SHEET_COLUMNS = 4
SHEET_SIDE = 192  # px a trial's image is shown at least (by whole multiples)
BACKGROUND = (0.018, 0.018, 0.02)
TEXT_COLOR = (0.75, 0.75, 0.75)


def setting(values: dict) -> str:
    return ", ".join(f"{name}={format_value(v)}" for name, v in values.items())


def trial_scene(opt: Optimisation, trial) -> dict:
    scene = opt.scene_of(trial.user_attrs["design"])
    scene["name"] = f"{opt.base['name']} (trial {trial.number})"[:120]
    return scene


def write_presets(opt: Optimisation, trials: Sequence, folder: str) -> list[str]:
    """``best.json`` for one objective; ``pareto-NN.json`` for each design of a front."""
    paths = []
    for i, trial in enumerate(trials):
        name = "best.json" if len(opt.objectives) == 1 else f"pareto-{i:02d}.json"
        path = os.path.join(folder, name)
        atomic_write_text(path, scene_to_json(trial_scene(opt, trial)))
        paths.append(path)
    return paths


def trial_images(opt: Optimisation, trials: Sequence, cache: CellCache | None) -> list[np.ndarray]:
    """Each trial's image: from the cache, else rendered here (a trial another machine ran)."""
    inputs = Inputs()
    images = []
    for trial in trials:
        cell = make_cell(opt.traced(opt.scene_of(trial.user_attrs["design"])), *opt.size, inputs)
        found = T.cached(cache, cell.key)
        if found is None:
            found = T.render_trial(cell, inputs.data.get(cell.environment))
            T.keep(cache, cell.key, *found)
        images.append(found[0])
    return images


def trial_lines(opt: Optimisation, trial) -> list[str]:
    """Under a trial's image: its number, one line per measure, one per parameter (4 digits)."""
    measures = trial.user_attrs.get("measures", {})
    lines = [f"trial {trial.number}"] + [f"{k} {v:.4g}" for k, v in measures.items()]
    lines += [f"{name.split('.')[-1]}={_short(v)}" for name, v in trial.user_attrs["design"].items()]
    return lines


def _short(value) -> str:
    return f"{value:.4g}" if isinstance(value, float) else format_value(value)


def compose_sheet(opt: Optimisation, trials: Sequence, images: Sequence[np.ndarray]) -> tuple[np.ndarray, float]:
    """The sheet in display values and the exposure used (one for every trial, so they compare)."""
    view = display.view_transform(display.LAMP_VIEW)
    # one exposure for every trial (the base's camera EV100 for XYZ in cd/m², else "auto" over all)
    shown = display.shown(list(images), opt.base, view=view)
    images = shown.pixels
    ev = shown.exposure.paper_stops or 0.0
    zoom = max(1, SHEET_SIDE // max(opt.size))  # small trial images shown larger, pixel for pixel
    images = [np.repeat(np.repeat(image, zoom, axis=0), zoom, axis=1) for image in images]
    w, h = opt.size[0] * zoom, opt.size[1] * zoom
    scale = 1 if min(w, h) < 96 else 2
    line_h = (bitmap_font.LINE_H + 2) * scale
    rows_of_text = max(len(trial_lines(opt, t)) for t in trials)
    cols = min(SHEET_COLUMNS, len(trials))
    rows = -(-len(trials) // cols)
    gap = 4 * scale
    cell_w = max(w, 26 * bitmap_font.ADVANCE_W * scale)  # "colour_distance 0.0001476"
    title_h = line_h + gap
    cell_h = h + rows_of_text * line_h + gap
    width, height = cols * (cell_w + gap) + gap, title_h + rows * cell_h + gap
    background = display.srgb_encode(np.asarray(BACKGROUND, np.float32)).astype(np.float32)
    color = display.srgb_encode(np.asarray(TEXT_COLOR, np.float32)).astype(np.float32)
    canvas = np.empty((height, width, 3), np.float32)
    canvas[:] = background
    oiio_text = labels.use_oiio("auto")

    def text(line: str, x: int, y: int, room: int) -> None:
        line = labels.shorten(line, room, bitmap_font.ADVANCE_W * scale)
        m = labels.coverage(line, room, line_h, size=line_h, oiio_text=oiio_text)[..., None]
        region = canvas[y:y + line_h, x:x + room]
        region[:] = region * (1.0 - m) + color * m

    goal = ", ".join(o.label for o in opt.objectives)
    text(f"{opt.name}: best trials by {goal}", gap, gap // 2, width - 2 * gap)
    for i, (trial, image) in enumerate(zip(trials, images, strict=True)):
        x = gap + (i % cols) * (cell_w + gap)
        y = title_h + (i // cols) * cell_h
        canvas[y:y + h, x:x + w] = image
        for k, line in enumerate(trial_lines(opt, trial)):
            text(line, x, y + h + k * line_h, cell_w)
    return canvas, ev


def write_sheet(opt: Optimisation, trials: Sequence, images: Sequence[np.ndarray], path: str) -> float:
    shown, ev = compose_sheet(opt, trials, images)
    write_display(path, shown, attributes={"ImageDescription": f"{opt.name}: best trials"},
                  view=display.LAMP_VIEW, exposure=ev)
    return ev


def write_history(opt: Optimisation, study, path: str) -> None:
    """One panel per objective: every finished trial (hollow: infeasible) and the best so far; with
    two objectives, a third panel of one against the other with the front."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib import pyplot as plt

    done = storage.finished_trials(study)
    n = len(opt.objectives)
    panels = n + (1 if n == 2 else 0)
    fig, axes = plt.subplots(1, panels, figsize=(4.2 * panels, 3.4), squeeze=False)
    for j, objective in enumerate(opt.objectives):
        ax = axes[0][j]
        numbers = [t.number for t in done]
        values = [t.values[j] for t in done]
        ok = [storage.feasible(t) for t in done]
        ax.scatter([x for x, f in zip(numbers, ok, strict=True) if f],
                   [v for v, f in zip(values, ok, strict=True) if f], s=16, color="tab:blue", label="trial")
        ax.scatter([x for x, f in zip(numbers, ok, strict=True) if not f],
                   [v for v, f in zip(values, ok, strict=True) if not f], s=16, facecolors="none",
                   edgecolors="tab:gray", label="infeasible")
        best, line_x, line_y = None, [], []
        for t in sorted(done, key=lambda t: t.number):
            if not storage.feasible(t):
                continue
            v = t.values[j]
            if best is None or (v > best if objective.goal == "maximise" else v < best):
                best = v
            line_x.append(t.number)
            line_y.append(best)
        if line_x:
            ax.step(line_x, line_y, where="post", color="tab:red", label="best so far")
        ax.set_xlabel("trial")
        ax.set_ylabel(f"{objective.measure.name} ({objective.goal})")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    if n == 2:
        ax = axes[0][2]
        front = storage.best(opt, study)
        ax.scatter([t.values[0] for t in done], [t.values[1] for t in done], s=12, color="tab:gray", label="trials")
        ax.scatter([t.values[0] for t in front], [t.values[1] for t in front], s=20, color="tab:red",
                   label="Pareto front")
        ax.set_xlabel(opt.objectives[0].label)
        ax.set_ylabel(opt.objectives[1].label)
        ax.legend(fontsize=7)
        ax.grid(alpha=0.3)
    # parse_math off: a name is the user's text, never mathtext ("$\\frac{" in one stopped the plot, issue 33)
    fig.suptitle(f"{opt.name}: {len(done)} trials ({opt.sampler})", fontsize=10, parse_math=False)
    fig.tight_layout()
    with atomic_path(path) as partial:
        fig.savefig(partial, dpi=110, format="png")
    plt.close(fig)


def write_trials(opt: Optimisation, study, path: str) -> None:
    rows = []
    for t in study.get_trials(deepcopy=False):
        rows.append({"number": t.number, "state": t.state.name.lower(), "design": t.user_attrs.get("design"),
                     "values": t.values, "measures": t.user_attrs.get("measures"),
                     "feasible": t.user_attrs.get("feasible"), "refused": t.user_attrs.get("refused")})
    doc = {"name": opt.name, "objectives": [o.label for o in opt.objectives], "sampler": opt.sampler,
           "trials": rows}
    atomic_write_text(path, json.dumps(strict_json(doc), indent=1, allow_nan=False) + "\n")


def strict_json(value):
    """``value`` with every NaN or ±inf as null: a JSON file another program reads holds no
    ``NaN`` (not JSON), and nothing non-finite is written (issue 33); a measure that had no value
    (a lamp without lit pixels, say) reads as null."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: strict_json(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [strict_json(v) for v in value]
    return value

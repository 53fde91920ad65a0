"""The registry of measures: a ``Measure`` is a name, a unit and words, its usual goal, whether it
needs the camera's render or photometric work (``request``), and how it is computed from a ``Trial``;
``register`` adds one, ``lookup`` finds one or says in one line which exist. The measures themselves
are in ``measures`` (of the image and the design) and ``photometric`` (of the photometric report)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..photometry.daylight import REC709_LUMINANCE
from ..scene.reading import SceneError
from ..scene.safe_text import show_key


@dataclass
class Trial:
    """A rendered trial as measures see it."""

    scene: dict
    image: np.ndarray | None  # linear (H, W, 3): RGB (paper) or XYZ (photometric); None if not rendered
    lamp_mask: np.ndarray | None  # (H, W) bool: the pixels that see a lamp
    figures: Any = None  # photometric.Figures: what the photometric measures need, worked out on the worker

    @property
    def photometric(self) -> bool:
        return self.scene.get("light_model") == "photometric"

    def luminance(self) -> np.ndarray:
        if self.photometric:
            return self.image[..., 1]
        return self.image @ np.asarray(REC709_LUMINANCE, dtype=np.float32)


@dataclass(frozen=True)
class Measure:
    name: str
    unit: str
    description: str
    needs_render: bool
    compute: Callable[[Trial, Any], float]
    prepare: Callable[[dict, str, str], Any] = field(default=lambda options, where, folder: None)
    options: tuple[str, ...] = ()  # the option keys an objective of this measure may give
    goal: str = "maximise"  # the direction an objective of it takes unless it says otherwise
    # For a photometric measure: the work its trial's task must do (``photometric.Request``) from what
    # ``prepare`` returned; None for a measure of the camera render or of the design alone.
    request: Callable[[Any], Any] | None = None

    @property
    def photometric(self) -> bool:
        return self.request is not None


MEASURES: dict[str, Measure] = {}


def register(measure: Measure) -> Measure:
    if measure.name in MEASURES:
        raise ValueError(f"measure {measure.name!r} is registered already")
    MEASURES[measure.name] = measure
    return measure


def lookup(name: Any, where: str) -> Measure:
    if not isinstance(name, str) or name not in MEASURES:
        raise SceneError(where, f"{show_key(str(name))} is not a measure; allowed {', '.join(sorted(MEASURES))}")
    return MEASURES[name]

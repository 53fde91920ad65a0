"""What an optimisation scores a trial by: named measures, each a number from the rendered trial.

A measure is a ``Measure``: its name, unit and words, whether it needs the render (a design-only
cost such as lens thickness does not), ``prepare(options, where, folder)`` which checks the
objective's own options once (a reference image is read here) and returns what ``compute`` needs,
and ``compute(trial, prepared) -> float``. ``register`` adds one: the measures of the photometric
report (homogeneity, grid margins, colour distance) plug in here, with no change to the search.

Built in:

- ``ssim``: closeness to a reference image the designer likes, the SSIM (``ssim``) of the trial and
  the reference on their display luma: both shown through one view transform at one exposure (the
  reference's auto exposure, or ``exposure`` stops); 1 is identical. Options: ``reference`` (an
  EXR or PNG of the trial's size, relative to the optimisation file; another size is refused,
  ``check_size``), ``view``, ``exposure``.
- ``lens_luminance``: mean luminance of the pixels that see a lamp (lens, bulb, reflector, socket,
  side walls: the passes other than body and background), linear; Rec. 709 Y of the image in the
  paper's light model, Y in cd/m² in the photometric one.
- ``lit_fraction``: the share of the lamp's pixels above half the brightest of them (a crude
  evenness: 1 when the whole lit lens is within a stop of its peak).
- ``lens_thickness``: the sum of the lamps' lens thickness in mm (a cost-like term: material).

The photometric report's measures (homogeneity, grid margin, colour distance, intensity at H-V) are
in ``photometric``.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..scene.reading import SceneError
from .registry import MEASURES, Measure, Trial, lookup, register

__all__ = ["MEASURES", "Measure", "Trial", "lookup", "register"]


# ---------------------------------------------------------------------------------------------
# Built-in measures


def _lens_luminance(trial: Trial, prepared: Any) -> float:
    if not trial.lamp_mask.any():
        return 0.0
    return float(trial.luminance()[trial.lamp_mask].mean())


def _lit_fraction(trial: Trial, prepared: Any) -> float:
    if not trial.lamp_mask.any():
        return 0.0
    values = trial.luminance()[trial.lamp_mask]
    peak = float(values.max())
    return float((values >= 0.5 * peak).mean()) if peak > 0 else 0.0


def _lens_thickness(trial: Trial, prepared: Any) -> float:
    return float(sum(lamp["lens"]["thickness"] for lamp in trial.scene["lamps"]))


@dataclass(frozen=True)
class Reference:
    shown_luma: np.ndarray  # (H, W) display luma of the reference
    view: Any  # display.ViewTransform
    exposure: float
    name: str = ""  # the file as the optimisation file gives it


def check_size(prepared: Any, size: tuple[int, int], where: str) -> None:
    """Refuse, naming ``size``, a reference image (``prepared`` by ``ssim``) that is not the trials'
    size: SSIM compares two images pixel by pixel, and a ``size`` changed after the reference was
    rendered gave a traceback from the first trial."""
    if not isinstance(prepared, Reference):
        return
    height, width = prepared.shown_luma.shape
    if (width, height) != tuple(size):
        raise SceneError("size", f"[{size[0]}, {size[1]}] is not the size of {where}.reference {prepared.name!r} "
                                 f"({width}x{height} px), which SSIM compares pixel by pixel; allowed "
                                 f"[{width}, {height}], or a reference of the new size")


def _prepare_ssim(options: dict, where: str, folder: str) -> Reference:
    from ..images import display
    from ..images.imageio import read_image
    from . import ssim

    path = options.get("reference")
    if not isinstance(path, str) or not path:
        raise SceneError(f"{where}.reference", "is required: the image to come close to; allowed an .exr or .png file")
    full = os.path.join(folder, os.path.expanduser(path))
    if os.path.splitext(full)[1].lower() not in (".exr", ".png"):
        raise SceneError(f"{where}.reference", f"{path!r} is not an image; allowed an .exr or .png file")
    if not os.path.isfile(full):
        raise SceneError(f"{where}.reference", f"{path!r} does not exist; allowed an existing .exr or .png file")
    image, _ = read_image(full)
    try:
        view = display.view_transform(options.get("view", display.DEFAULT_VIEW))
    except ValueError as e:
        raise SceneError(f"{where}.view", str(e)) from None
    exposure = options.get("exposure", "auto")
    if exposure != "auto" and (isinstance(exposure, bool) or not isinstance(exposure, int | float)
                               or not -display.MAX_EXPOSURE <= exposure <= display.MAX_EXPOSURE):
        raise SceneError(f"{where}.exposure", f"{exposure!r} is out of range; allowed \"auto\" or "
                                              f"-{display.MAX_EXPOSURE:g} to {display.MAX_EXPOSURE:g} stops")
    ev = display.resolve_exposure(exposure, image)
    luma = ssim.display_luma(view.to_display(image, ev))
    if min(luma.shape) < ssim.WINDOW:
        raise SceneError(f"{where}.reference", f"{path!r} is {luma.shape[1]}x{luma.shape[0]} px; allowed at least "
                                               f"{ssim.WINDOW}x{ssim.WINDOW}")
    return Reference(luma, view, ev, path)


def _ssim(trial: Trial, reference: Reference) -> float:
    from . import ssim

    shown = ssim.display_luma(reference.view.to_display(trial.image, reference.exposure))
    return ssim.ssim(shown, reference.shown_luma)


register(Measure("ssim", "", "closeness to a reference image (SSIM of the display luma, 1 = identical)", True,
                 _ssim, _prepare_ssim, ("reference", "view", "exposure")))
register(Measure("lens_luminance", "cd/m² or paper units",
                 "mean luminance of the pixels that see a lamp (linear)", True, _lens_luminance))
register(Measure("lit_fraction", "", "share of the lamp's pixels within a stop of its brightest", True,
                 _lit_fraction))
register(Measure("lens_thickness", "mm", "sum of the lamps' lens thickness (material)", False, _lens_thickness,
                 goal="minimise"))


# The photometric report's measures register themselves (they use the names above).
from . import photometric  # noqa: E402, F401

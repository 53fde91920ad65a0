"""A photometric render to files and to the screen (docs/photometric.md, "Outputs").

A photometric render's image and passes are CIE 1931 XYZ with Y in cd/m² (``raytrace.spectral``).
What leaves here:

- an .exr keeps the physical values: channels X, Y, Z (Y = luminance in cd/m²) and x, y, with the
  units in the header (``photometry.output.write_photometric_exr``);
- a .png is what a camera at EV100 shows: XYZ → linear Rec.709 (Blender's scene-linear, unclipped,
  ``spectral.display_linear``) scaled by 1 / (1.2 · 2^EV100), then Blender's view transform (AgX
  by default) as for the paper mode's images; the out-of-gamut red of a lamp is rolled off by the
  view, not clipped by us. ``stops`` brightens or darkens on top, as Blender's exposure slider;
- a false-colour .png maps log10 luminance on a ramp with a cd/m² legend
  (``photometry.output.false_colour``).

The conversion to the screen is ``display.shown``, the one every picture goes through. Several
images shown together (a study's cells, a side-by-side) take ONE EV100 there, so a brighter lamp
shows brighter.
"""

from __future__ import annotations

import os
from collections.abc import Sequence

import numpy as np

from ..photometry import output
from ..photometry.bands import Bands
from . import display
from .imageio import image_format, write_image

EV100_ATTRIBUTE = "lamp:ev100"


def is_photometric(scene: dict) -> bool:
    return display.light_model(scene) == display.PHOTOMETRIC


def ev100_for(XYZ: np.ndarray | Sequence[np.ndarray], scene: dict, override: float | str | None = None) -> float:
    """The camera EV100 of one XYZ image or of several shown together: ``override`` (a number, or
    "auto" for the project's automatic exposure as an EV100), else the scene's camera
    (``camera.exposure`` "ev100" with ``camera.ev100``, or "auto"); ``display.exposure_for``."""
    images = [np.asarray(a) for a in XYZ] if isinstance(XYZ, (list, tuple)) else [np.asarray(XYZ)]
    return display.exposure_for(images, [scene] * len(images), ev100=override).ev100


def write_render(path: str | os.PathLike, XYZ: np.ndarray, scene: dict, *, ev100: float,
                 view: display.ViewTransform | None = None, stops: float = 0.0, bands: Bands | None = None,
                 false_colour: tuple[float | None, float | None] | None = None) -> None:
    """Write a photometric image: .exr as XYZ, L... in cd/m² (units in the header), .png through
    ``view`` at camera ``ev100`` and ``stops`` more, or, with ``false_colour`` = (lo, hi) cd/m²
    (either None: from the image), as the luminance false-colour map with its legend."""
    attributes = {EV100_ATTRIBUTE: f"{ev100:g}"}
    if image_format(path) == "exr":
        output.write_photometric_exr(path, XYZ, bands=bands, scene=scene, attributes=attributes)
        return
    if false_colour is not None:
        output.write_false_colour_png(path, np.asarray(XYZ)[..., 1], *false_colour, scene=scene)
        return
    # ``stops`` go to the view as Blender's exposure slider does (lamp:exposure records them)
    linear = display.shown(XYZ, scene, view=None, fixed=display.Exposure(ev100)).pixels[0]
    write_image(path, linear, scene, view=view, exposure=stops, attributes=attributes)


def write_pass(path: str | os.PathLike, XYZ: np.ndarray, scene: dict, bands: Bands | None = None) -> None:
    """One contribution pass of a photometric render (XYZ, Y in cd/m²) as an .exr with units."""
    output.write_photometric_exr(path, XYZ, channels=("X", "Y", "Z"), bands=bands, scene=scene)

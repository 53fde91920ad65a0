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

Several images shown together (a study's cells, a side-by-side) take ONE EV100
(``spectral.exposure_ev100`` over all of them), so a brighter lamp shows brighter.
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
    return scene.get("light_model", "paper") == "photometric"


def ev100_for(XYZ: np.ndarray | Sequence[np.ndarray], scene: dict, override: float | str | None = None) -> float:
    """The camera EV100 of one XYZ image or of several shown together: ``override`` (a number, or
    "auto" for the project's automatic exposure as an EV100), else the scene's camera
    (``camera.exposure`` "ev100" with ``camera.ev100``, or "auto")."""
    from ..raytrace import spectral  # the tracer's module: loaded only for a photometric image

    images = [np.asarray(a) for a in XYZ] if isinstance(XYZ, (list, tuple)) else [np.asarray(XYZ)]
    if override is None:
        return spectral.exposure_ev100(images, scene)
    if override == "auto":
        return spectral.exposure_ev100(images, {**scene, "camera": {**scene["camera"], "exposure": "auto"}})
    return float(override)


def scene_linear(XYZ: np.ndarray, ev100: float) -> np.ndarray:
    """Blender's scene-linear (linear Rec.709, float32) of XYZ in cd/m² at camera ``ev100``."""
    from ..raytrace import spectral

    return spectral.display_linear(XYZ, ev100)


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
    write_image(path, scene_linear(XYZ, ev100), scene, view=view, exposure=stops, attributes=attributes)


def write_pass(path: str | os.PathLike, XYZ: np.ndarray, scene: dict, bands: Bands | None = None) -> None:
    """One contribution pass of a photometric render (XYZ, Y in cd/m²) as an .exr with units."""
    output.write_photometric_exr(path, XYZ, channels=("X", "Y", "Z"), bands=bands, scene=scene)


def shown_together(scenes: Sequence[dict], images: Sequence[np.ndarray], *, ev100: float | str | None = None,
                   stops: float = 0.0, exposure: float | str | None = "auto") -> tuple[list[np.ndarray], float | None,
                                                                                     float | None]:
    """(linear images ready for the view at exposure 0, the EV100 of the photometric ones, the
    stops of the paper ones) for images shown side by side (a study's cells): every photometric
    image at ONE EV100 (``ev100`` or the first photometric scene's camera; "auto" is one automatic
    exposure over all of them) and ``stops`` more; every paper-mode image at ONE ``exposure``
    ("auto": ``display.auto_exposure`` over all of them). None where there is no image of a kind."""
    photometric = [i for i, scene in enumerate(scenes) if is_photometric(scene)]
    paper = [i for i in range(len(scenes)) if i not in set(photometric)]
    shown: list[np.ndarray] = [np.asarray(a, dtype=np.float32) for a in images]
    camera = None
    if photometric:
        camera = ev100_for([shown[i] for i in photometric], scenes[photometric[0]], ev100)
        gain = np.float32(2.0 ** stops)
        for i in photometric:
            shown[i] = scene_linear(shown[i], camera) * gain
    paper_ev = None
    if paper:
        paper_ev = display.resolve_exposure(exposure, [shown[i] for i in paper])
        for i in paper:
            shown[i] = shown[i] * np.float32(2.0 ** paper_ev)
    return shown, camera, paper_ev

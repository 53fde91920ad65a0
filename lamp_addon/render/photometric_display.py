"""The photometric mode's image shown through Blender's colour management.

The tracer's photometric image is CIE XYZ with Y in cd/m² (``core_tracer.raytrace.spectral``). A
render engine hands Blender scene-linear values in the file's working space, which Blender's view
transform (AgX, Filmic, Standard, False Color) takes to the display. So the image goes to Blender as
the working space's linear RGB of the XYZ at the camera's exposure, L / (1.2 · 2^EV100) = 1 at
display white (``photometry.output.exposure_scale``), with colours outside the gamut left negative
or above 1: the view transform decides how they show, nothing is clipped here.

The EV100 is the design camera's (``camera.exposure`` "ev100"): fixed, so that two designs (a stop
and a tail lamp) under one exposure show their true difference. With "auto" it is measured once
per render on a small preview of the same view (``auto_ev100``), never changed while the image
fills in.

Working spaces: Blender 5's file working space is Linear Rec.709 (the default), Linear Rec.2020 or
ACEScg. The first two are matrices from CIE XYZ (D65) in Blender's own OpenColorIO configuration,
read from it here; ACEScg goes through a built-in transform of OpenColorIO that no Python module of
Blender exposes, so a photometric render in it is refused with the setting to change.
"""

from __future__ import annotations

import functools
import os
import re

import bpy
import numpy as np

from ...core_tracer.images import display
from ...core_tracer.scene.reading import SceneError

REC709 = "Linear Rec.709"
PREVIEW_SIDE = 96  # px of the longer side of the preview that measures an automatic EV100


def working_space() -> str:
    """The file's working space (Blender 5+), or Linear Rec.709 (Blender's scene-linear before 5.0)."""
    colorspace = getattr(bpy.data, "colorspace", None)
    return getattr(colorspace, "working_space", REC709) or REC709


def config_path() -> str:
    """Blender's OpenColorIO configuration (``OCIO`` when set, as Blender reads it)."""
    env = os.environ.get("OCIO")
    if env and os.path.isfile(env):
        return env
    return os.path.join(bpy.utils.resource_path("LOCAL"), "datafiles", "colormanagement", "config.ocio")


@functools.lru_cache(maxsize=8)
def _xyz_d65_matrix(path: str, space: str) -> np.ndarray | None:
    """The 3×3 matrix from CIE XYZ (D65) to ``space`` in the configuration at ``path``: the
    ``MatrixTransform`` after the step to "Linear CIE-XYZ D65" in its ``from_scene_reference``; None
    when the space is made otherwise."""
    with open(path, encoding="utf-8") as f:
        text = f.read()
    start = r"-\s*!<ColorSpace>\s*\n\s*name:\s*" + re.escape(space) + r"\s*\n"
    block = re.search(start + r"(.*?)(?=\n\s*-\s*!<ColorSpace>|\Z)", text, re.S)
    if block is None:
        return None
    step = re.search(r"dst:\s*Linear CIE-XYZ D65\}\s*\n\s*-\s*!<MatrixTransform>\s*\{matrix:\s*\[([^\]]*)\]",
                     block.group(1))
    if step is None:
        return None
    values = [float(x) for x in step.group(1).split(",")]
    return np.array(values, dtype=np.float64).reshape(4, 4)[:3, :3]


def from_rec709(space: str | None = None) -> np.ndarray | None:
    """The matrix from linear Rec.709 to the working space ``space`` (the file's when None); None
    for Linear Rec.709 itself. Raises ``SceneError`` for a working space made by a built-in
    transform (ACEScg)."""
    space = space or working_space()
    if space == REC709:
        return None
    path = config_path()
    target = _xyz_d65_matrix(path, space) if os.path.isfile(path) else None
    rec709 = _xyz_d65_matrix(path, REC709) if os.path.isfile(path) else None
    if target is None or rec709 is None:
        raise SceneError("light_model", f'the photometric image cannot be shown in the working space "{space}"; '
                                        "allowed Color Management > Working Space Linear Rec.709 or Linear Rec.2020")
    return target @ np.linalg.inv(rec709)


PHOTOMETRIC = {"light_model": display.PHOTOMETRIC}  # what the pixels handed to ``display.shown`` are


class Display:
    """XYZ (cd/m²) to the working space's scene-linear RGB at a fixed EV100: ``display.shown`` (the
    one way from an image to the screen), then Blender's working space when it is not Rec.709."""

    def __init__(self, ev100: float, space: str | None = None):
        self.ev100 = float(ev100)
        self._matrix = from_rec709(space)

    def linear(self, XYZ: np.ndarray) -> np.ndarray:
        """(…, 3) float32 scene-linear of XYZ in cd/m² (unclipped)."""
        rgb = display.shown(np.asarray(XYZ), PHOTOMETRIC, view=None, fixed=display.Exposure(self.ev100)).pixels[0]
        if self._matrix is not None:
            rgb = (rgb @ self._matrix.T.astype(np.float32)).astype(np.float32)
        return rgb


def auto_ev100(scene: dict) -> float:
    """The automatic EV100 of a photometric design (``display.exposure_ev100``), measured on a small
    preview of the same view."""
    from ...core_tracer import render

    width, height = scene["image"]["width"], scene["image"]["height"]
    scale = min(1.0, PREVIEW_SIDE / max(width, height))
    preview = render(scene, max(1, round(width * scale)), max(1, round(height * scale)))
    return display.exposure_for([preview], [scene]).ev100


def scene_ev100(scene: dict) -> float:
    """The EV100 a photometric scene is shown at: its camera's, or measured when it is "auto"."""
    camera = scene["camera"]
    if camera.get("exposure", "auto") == "ev100":
        return float(camera["ev100"])
    return auto_ev100(scene)


def for_scene(scene: dict) -> Display | None:
    """The display of a normalised scene: None in the paper mode (its RGB is scene-linear as it is)."""
    if scene.get("light_model", "paper") != "photometric":
        return None
    return Display(scene_ev100(scene))


def for_image(scene: dict, XYZ: np.ndarray) -> Display | None:
    """``for_scene`` of a design rendered whole before it is shown (the free-form tracer's): "auto"
    measured on the image itself rather than on a preview of the parametric lamp."""
    if scene.get("light_model", "paper") != "photometric":
        return None
    camera = scene["camera"]
    if camera.get("exposure", "auto") == "ev100":
        return Display(float(camera["ev100"]))
    return Display(display.exposure_ev100(XYZ, scene))

"""From a band image to physical outputs: XYZ, luminance in cd/m², xy; EXR with named channels;
physical exposure; a false-colour luminance map with a cd/m² legend.

Exposure (``exposure_scale``). A camera at EV100 (the exposure value at ISO 100) saturates at the
scene luminance L_max = (78 / (S q)) · N²/t = 1.2 · 2^EV100 cd/m² (S = 100, lens and vignetting
factor q = 0.65, saturation-based speed of ISO 12232): S. Lagarde, C. de Rousiers, "Moving
Frostbite to Physically Based Rendering 3.0", SIGGRAPH 2014 course notes, §5.1 (the same
derivation as colour-hdri's ``photometric_exposure_scale_factor_Lagarde2014``). Scene-linear values
are luminance / L_max, so L_max shows as display 1.0 before the view transform; one EV100 for a
whole study keeps its images comparable. ``ev100_for_average_luminance`` is the reflected-light
meter's choice, EV100 = log2(L_avg · S / K) with K = 12.5 (ISO 2720:1974), as "auto".

Colour. XYZ goes to linear Rec.709 (Blender's scene-linear space) without chromatic adaptation
and without clipping: a lamp's red outside the Rec.709 gamut keeps its negative green and blue for
the view transform (AgX, Filmic) to handle.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from .bands import Bands
from .cie import xy, xyz_matrix, xyz_to_linear_rec709

UNITS_ATTRIBUTE = "lamp:units"
BANDS_ATTRIBUTE = "lamp:bands"
CHANNEL_UNITS = {
    "X": "CIE 1931 2 deg X, same scale as Y",
    "Y": "CIE 1931 2 deg Y = luminance in cd/m2 (Km = 683.002 lm/W)",
    "Z": "CIE 1931 2 deg Z, same scale as Y",
    "L": "luminance in cd/m2",
    "x": "CIE 1931 chromaticity x",
    "y": "CIE 1931 chromaticity y",
}
SATURATION_FACTOR = 1.2  # 78 / (S q) with S = 100, q = 0.65 (Lagarde & de Rousiers 2014, §5.1)
METER_CALIBRATION_K = 12.5  # reflected-light meter constant (ISO 2720:1974)


def band_image_to_xyz(image: np.ndarray, bands: Bands) -> np.ndarray:
    """(..., 3) CIE XYZ of band-mean spectral radiance (..., K) in W/(m² sr nm); Y in cd/m²."""
    a = np.asarray(image, dtype=np.float64)
    if a.shape[-1:] != (bands.k,):
        raise ValueError(f"band image: last axis {a.shape[-1:]} is not the {bands.k} bands")
    return a @ xyz_matrix(bands)


def luminance(image: np.ndarray, bands: Bands) -> np.ndarray:
    """(...) luminance in cd/m² of a band image (..., K)."""
    return band_image_to_xyz(image, bands)[..., 1]


def chromaticity(XYZ: np.ndarray) -> np.ndarray:
    """(..., 2) CIE 1931 xy; black pixels get the D65 white point (they have no colour)."""
    return xy(XYZ)


# ---------------------------------------------------------------------------------------------
# Exposure and display


def exposure_scale(ev100: float) -> float:
    """The factor taking luminance in cd/m² to scene-linear display units: 1 / (1.2 · 2^EV100)."""
    if not (isinstance(ev100, (int, float)) and math.isfinite(ev100) and -20.0 <= ev100 <= 30.0):
        raise ValueError(f"exposure EV100: {ev100!r} is outside -20 to 30")
    return 1.0 / (SATURATION_FACTOR * 2.0 ** float(ev100))


def ev100_for_average_luminance(average_cd_m2: float) -> float:
    """The EV100 a reflected-light meter picks for a scene of average luminance L: log2(L · 100 / 12.5)."""
    if not (math.isfinite(average_cd_m2) and average_cd_m2 > 0):
        raise ValueError(f"average luminance: {average_cd_m2!r} cd/m² is not above 0")
    return math.log2(average_cd_m2 * 100.0 / METER_CALIBRATION_K)


def scene_linear_rec709(XYZ: np.ndarray, ev100: float) -> np.ndarray:
    """Linear Rec.709 (Blender's scene-linear) of XYZ in cd/m² at camera EV100, unclipped."""
    return xyz_to_linear_rec709(XYZ) * exposure_scale(ev100)


# ---------------------------------------------------------------------------------------------
# EXR with named channels and units


def photometric_channels(XYZ: np.ndarray, names: Sequence[str] = ("X", "Y", "Z", "x", "y")) -> dict[str, np.ndarray]:
    """The named channels (H, W) of an XYZ image: any of X, Y, Z, L (= Y), x, y."""
    XYZ = np.asarray(XYZ, dtype=np.float64)
    chroma = xy(XYZ) if {"x", "y"} & set(names) else None
    planes = {"X": lambda: XYZ[..., 0], "Y": lambda: XYZ[..., 1], "Z": lambda: XYZ[..., 2],
              "L": lambda: XYZ[..., 1], "x": lambda: chroma[..., 0], "y": lambda: chroma[..., 1]}
    out = {}
    for name in names:
        if name not in planes:
            raise ValueError(f"channel: {name!r} is not one of {', '.join(planes)}")
        out[name] = planes[name]()
    return out

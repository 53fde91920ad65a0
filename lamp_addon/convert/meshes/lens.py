"""The lens solid of a lamp with a flat lens, by the kind of its cuts: spherical lenslets
(``fisheye``), saw-tooth ridges (``sawtooth``) or cylindrical flutes (``flutes``)."""

from __future__ import annotations

import numpy as np

from .builder import MAX_CELL_SUBDIVISION, MeshData, chord_tolerance
from .fisheye import fisheye_lens_mesh
from .flutes import flutes_lens_mesh
from .sawtooth import sawtooth_lens_mesh


def lens_mesh(lamp: dict, segments: int, tol: float | None = None,
              max_subdivision: int = MAX_CELL_SUBDIVISION, rim: np.ndarray | None = None) -> MeshData:
    """The lens solid of one lamp, relative to its axis (``fisheye_lens_mesh`` says what it is made of;
    planar facets and flutes are exact and have modules of their own)."""
    tol = chord_tolerance(tol)
    kind = lamp["cuts"].get("type", "fisheye")
    if kind == "sawtooth":
        return sawtooth_lens_mesh(lamp, segments, tol, rim)
    if kind == "flutes":
        return flutes_lens_mesh(lamp, segments, tol, rim)
    return fisheye_lens_mesh(lamp, segments, tol, max_subdivision, rim)

"""The tracer's camera for a 3D Viewport: what the viewport shows, as ``scene["camera"]``.

Blender describes a viewport's view by two matrices: ``region_3d.view_matrix`` (world to view
space: the viewer's position and orientation) and ``region_3d.window_matrix`` (view space to
clip space: the projection over the whole region, perspective or orthographic). In camera view
(``view_perspective == 'CAMERA'``) the window matrix is the scene camera's projection widened to
the region, with the viewport's zoom and pan as an off-centre window, so the camera's own frame
sits inside the region exactly where Blender draws the camera border; nothing else is needed for
it here.

A projection matrix of either kind is a window ``[l, r] x [b, t]`` on a plane in front of the
viewer; the tracer's camera (``core_tracer.raytrace.camera``) is the same window given as the
half size of the fitted side (``fov_deg`` or ``width``) and an offset of its centre (``shift``, a
fraction of the fitted side). Reading the window back from the matrix and writing it in those
terms is exact for any region aspect and any off-centre window, as long as pixels are square
(Blender's viewport pixels always are).

The camera is expressed in the design's model space (docs/model.md §2: millimetres, the root object's
local space, see ``design.root``): ``world_from_model`` takes model millimetres to the world.
A root with a non-uniform scale distorts the lamp in a way no pinhole camera can show, and is
refused.

No ``bpy`` or ``mathutils`` here: matrices are plain nested sequences, rows first (``m[row][col]``,
as ``mathutils.Matrix`` indexes), so the tests check the mathematics without Blender.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from .units import BU_PER_MM

Matrix4 = Sequence[Sequence[float]]

# Scale and shear tolerance: Blender stores matrices in single precision.
_RIGID_TOLERANCE = 1e-4
TARGET_DISTANCE_MM = 1000.0  # the tracer only needs a direction; a metre in front of the viewer


def is_perspective(window_matrix: Matrix4) -> bool:
    """A perspective projection has (0, 0, -1, 0) as its last row, an orthographic one (0, 0, 0, 1)."""
    return abs(float(window_matrix[3][3])) < 0.5


def model_matrix(world_from_design: Matrix4 | None = None) -> np.ndarray:
    """World from model millimetres: the design root's world matrix (metres) times 1 mm in metres.
    Without a root (before the first build) the model is the world, in millimetres."""
    root = np.eye(4) if world_from_design is None else np.asarray(world_from_design, dtype=np.float64)
    return root @ np.diag([BU_PER_MM, BU_PER_MM, BU_PER_MM, 1.0])


def camera_from_view(width: int, height: int, window_matrix: Matrix4, view_matrix: Matrix4,
                     world_from_model: Matrix4 | None = None) -> dict:
    """``scene["camera"]`` (model millimetres) that shows what the viewport region of ``width`` x
    ``height`` pixels shows through ``window_matrix`` and ``view_matrix``.

    ``world_from_model`` maps model millimetres to the world (``model_matrix``); by default the
    model is the world in millimetres. Raises ``ValueError`` for a view the tracer's camera cannot
    express (a skewed projection or a non-uniformly scaled model)."""
    if width < 1 or height < 1:
        raise ValueError(f"region size {width}x{height}: both must be at least 1 pixel")
    proj = np.asarray(window_matrix, dtype=np.float64)
    to_model = model_matrix() if world_from_model is None else np.asarray(world_from_model, dtype=np.float64)
    view = np.asarray(view_matrix, dtype=np.float64) @ to_model  # model mm -> view space
    axes, scale = _view_axes(view[:3, :3])
    right, up, back = axes
    forward = -back
    position = -np.linalg.solve(view[:3, :3], view[:3, 3])  # the viewer, in model mm

    if proj[0, 1] != 0.0 or proj[1, 0] != 0.0:
        raise ValueError("the viewport's projection is skewed; the Lamp Tracer needs an upright window")
    perspective = is_perspective(proj)
    # The window's half sizes and centre, in view-space units: tangents for a perspective view
    # (x/-z = (ndc + P02) / P00), lengths for an orthographic one (x = (ndc - P03) / P00).
    half_w, half_h = 1.0 / proj[0, 0], 1.0 / proj[1, 1]
    if perspective:
        centre = (proj[0, 2] * half_w, proj[1, 2] * half_h)
    else:
        centre = (-proj[0, 3] * half_w, -proj[1, 3] * half_h)
        half_w, half_h = half_w / scale, half_h / scale  # view units -> model mm
        centre = (centre[0] / scale, centre[1] / scale)
        # An orthographic view also shows what lies behind the viewer, up to the near clip plane
        # (ndc z = -1): start the rays there, as Blender's clipping does.
        near = (-1.0 - proj[2, 3]) / proj[2, 2]  # view-space z of the near plane
        position = position + forward * (-near / scale)

    fit = "horizontal" if width >= height else "vertical"
    half_fit = half_w if fit == "horizontal" else half_h
    camera = {
        "type": "perspective" if perspective else "orthographic",
        "position": [float(v) for v in position],
        "target": [float(v) for v in position + forward * TARGET_DISTANCE_MM],
        "up": [float(v) for v in up],
        # The field used is fov_deg (perspective) or width (orthographic); the other is the same
        # window seen at the target, so that both are meaningful.
        "fov_deg": math.degrees(2.0 * math.atan(half_fit if perspective else half_fit / TARGET_DISTANCE_MM)),
        "width": 2.0 * half_fit * (TARGET_DISTANCE_MM if perspective else 1.0),
        "sensor_fit": fit,
        "shift": [centre[0] / (2.0 * half_fit), centre[1] / (2.0 * half_fit)],
    }
    return camera


def _view_axes(rotation_scale: np.ndarray) -> tuple[tuple[np.ndarray, np.ndarray, np.ndarray], float]:
    """The view's right, up and back axes in model space, and the model-to-view scale.

    The rows of the model-to-view 3x3 are the view axes written in model coordinates, each
    times the scale; they must be orthogonal and of one length."""
    rows = [rotation_scale[i] for i in range(3)]
    lengths = [float(np.linalg.norm(r)) for r in rows]
    scale = lengths[0]
    unit = [r / n for r, n in zip(rows, lengths, strict=True)]
    uniform = max(abs(n / scale - 1.0) for n in lengths) < _RIGID_TOLERANCE
    orthogonal = max(abs(float(unit[i] @ unit[j])) for i, j in ((0, 1), (0, 2), (1, 2))) < _RIGID_TOLERANCE
    mirrored = float(np.linalg.det(rotation_scale)) < 0.0
    if not (uniform and orthogonal) or mirrored:
        raise ValueError("the design root is scaled unevenly, sheared or mirrored; the Lamp Tracer can "
                         "show it only with one positive scale on all three axes")
    return (unit[0], unit[1], unit[2]), scale

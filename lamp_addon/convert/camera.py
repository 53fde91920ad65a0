"""Camera mathematics between the scene description's camera and Blender's (no ``bpy``).

The scene's camera (``scene["camera"]``, millimetres, docs/model.md §2) follows Blender's own camera
code (``BKE_camera_params_compute_viewplane``): the sensor size is ``sensor_height`` for a vertical
fit and ``sensor_width`` otherwise; AUTO fits the larger of the render's pixel dimensions times the
pixel aspect; the lens shift is a fraction of the fitted side; an orthographic ``ortho_scale`` spans
the fitted side. The tracer's eye rays (``core_tracer.raytrace.camera``) use the same conventions.

``frame_view`` moves a camera so that a box (the lamp body) fills its image with a margin, keeping
the camera's viewing direction and image up: the framing of the add-on's "Lamp Camera".
"""

from __future__ import annotations

import math
from collections.abc import Sequence

Vec3 = tuple[float, float, float]

FRAME_MARGIN = 0.1  # framing leaves this fraction of the half image free around the body
MIN_ORTHO_DISTANCE_MM = 100.0  # an orthographic camera stands at least this far in front of the body


# ---------------------------------------------------------------------------------------------
# Sizes and lenses


def render_size(resolution_x: int, resolution_y: int, percentage: int) -> tuple[int, int]:
    """The rendered size in pixels, as Blender computes it (integer division by 100)."""
    return resolution_x * percentage // 100, resolution_y * percentage // 100


def fitted_side(sensor_fit: str, width: float, height: float) -> str:
    """``"horizontal"`` or ``"vertical"``: the image side the field of view spans.

    ``width`` and ``height`` are the pixel counts times the pixel aspect (Blender's
    ``BKE_camera_sensor_fit``: AUTO picks horizontal when width >= height)."""
    if sensor_fit == "auto":
        return "horizontal" if width >= height else "vertical"
    return sensor_fit


def sensor_size(sensor_fit: str, sensor_width: float, sensor_height: float) -> float:
    """The sensor size the lens is fitted to (``BKE_camera_sensor_size``: AUTO uses the width)."""
    return sensor_height if sensor_fit == "vertical" else sensor_width


def fov_from_lens(lens_mm: float, sensor_mm: float) -> float:
    """Full field of view in degrees across a sensor of ``sensor_mm`` for a focal length."""
    return math.degrees(2.0 * math.atan(sensor_mm / (2.0 * lens_mm)))


def lens_from_fov(fov_deg: float, sensor_mm: float) -> float:
    """Focal length in mm giving ``fov_deg`` across ``sensor_mm``."""
    return sensor_mm / (2.0 * math.tan(math.radians(fov_deg) / 2.0))


# ---------------------------------------------------------------------------------------------
# Vectors and camera axes


def _sub(a: Sequence[float], b: Sequence[float]) -> Vec3:
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def _cross(a: Sequence[float], b: Sequence[float]) -> Vec3:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _dot(a: Sequence[float], b: Sequence[float]) -> float:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _unit(a: Sequence[float]) -> Vec3:
    n = math.sqrt(_dot(a, a))
    return (a[0] / n, a[1] / n, a[2] / n)


def look_at_axes(position: Sequence[float], target: Sequence[float], up: Sequence[float]) -> tuple[Vec3, Vec3, Vec3]:
    """The camera's local X (right), Y (up) and Z (back) axes in world space.

    A Blender camera looks along its local -Z with +Y up in the image."""
    forward = _unit(_sub(target, position))
    right = _unit(_cross(forward, up))
    true_up = _cross(right, forward)
    back = (-forward[0], -forward[1], -forward[2])
    return right, true_up, back


def view_from_axes(position_mm: Sequence[float], y_axis: Sequence[float], z_axis: Sequence[float],
                   target_distance_mm: float) -> dict:
    """Position, target and up of the scene camera from the camera's world axes.

    ``up`` is written as world +Z when the camera has no roll (its right axis is horizontal and
    its image up points upward), so that a camera made from ``up = [0, 0, 1]`` reads back as
    such; otherwise it is the camera's own (unit) up axis."""
    forward = _unit((-z_axis[0], -z_axis[1], -z_axis[2]))
    cam_up = _unit(y_axis)
    right = _cross(forward, cam_up)
    level = abs(right[2]) < 1e-6 and cam_up[2] > 1e-6
    up = (0.0, 0.0, 1.0) if level else cam_up
    target = tuple(p + target_distance_mm * f for p, f in zip(position_mm, forward, strict=True))
    return {"position": [float(x) for x in position_mm], "target": [float(x) for x in target],
            "up": [float(x) for x in up]}


def looking_along(camera: dict, forward: Sequence[float], up: Sequence[float]) -> dict:
    """A copy of ``camera`` that keeps its target and distance but looks along ``forward`` with image
    up ``up`` (a 3D View's direction, to be framed next)."""
    distance = math.dist(camera["position"], camera["target"])
    f = _unit(forward)
    position = [t - distance * c for t, c in zip(camera["target"], f, strict=True)]
    return {**camera, "position": position, "up": [float(x) for x in _unit(up)]}


# ---------------------------------------------------------------------------------------------
# Projection and framing


def window(camera: dict, size: tuple[int, int]) -> tuple[tuple[float, float], tuple[float, float]]:
    """The image window ``((left, right), (bottom, top))`` in units of the fitted side: image-plane
    coordinates divided by the fitted side's full extent (2 tan(fov/2) at unit distance for a
    perspective camera, ``width`` mm for an orthographic one), the lens shift included."""
    width, height = size
    if fitted_side(camera["sensor_fit"], width, height) == "horizontal":
        half_x, half_y = 0.5, 0.5 * height / width
    else:
        half_x, half_y = 0.5 * width / height, 0.5
    sx, sy = camera["shift"]
    return (sx - half_x, sx + half_x), (sy - half_y, sy + half_y)


def fitted_extent(camera: dict) -> float:
    """The full extent of the fitted side: 2 tan(fov/2) per mm of depth (perspective) or mm (orthographic)."""
    if camera["type"] == "orthographic":
        return float(camera["width"])
    return 2.0 * math.tan(math.radians(camera["fov_deg"]) / 2.0)


def project(camera: dict, size: tuple[int, int], points: Sequence[Sequence[float]]) -> list[tuple[float, float, float]]:
    """Where ``points`` (mm) fall in the image: ``(column, row, depth)`` in pixels, row 0 at the top,
    as the tracer's eye rays (pixel centres at half-integers); depth in mm along the view."""
    right, up, back = look_at_axes(camera["position"], camera["target"], camera["up"])
    (left, right_edge), (bottom, top) = window(camera, size)
    extent = fitted_extent(camera)
    width, height = size
    out = []
    for q in points:
        v = _sub(q, camera["position"])
        depth = -_dot(v, back)
        scale = extent if camera["type"] == "orthographic" else extent * depth
        u, w = _dot(v, right) / scale, _dot(v, up) / scale
        out.append(((u - left) / (right_edge - left) * width, (top - w) / (top - bottom) * height, depth))
    return out


def box_corners(lo: Sequence[float], hi: Sequence[float]) -> list[Vec3]:
    """The 8 corners of the axis-aligned box from ``lo`` to ``hi``."""
    return [(x, y, z) for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]


def body_box(scene: dict) -> tuple[Vec3, Vec3]:
    """The lamp body's box in model space (mm, docs/model.md §2): the front face at y = 0, depth into +y.
    Every part of a valid design lies in it (the lenses inside the front face, the reflectors and
    bulbs within its depth)."""
    body = scene["body"]
    (bx, bz), (w, h) = body["center"], body["size"]
    return (bx - w / 2, 0.0, bz - h / 2), (bx + w / 2, float(body["depth"]), bz + h / 2)


def _scale_needed(coordinate: float, lo: float, hi: float) -> float:
    """The smallest scale s with ``coordinate / s`` in [lo, hi] (lo < 0 < hi): the one of the two
    bounds that has the coordinate's sign."""
    return max(coordinate / hi, coordinate / lo)


def frame_view(camera: dict, box: tuple[Sequence[float], Sequence[float]], size: tuple[int, int],
               margin: float = FRAME_MARGIN) -> dict:
    """A copy of ``camera`` (a normalised scene camera) that shows the whole ``box`` (mm) with
    ``margin`` of the half image free around it, from the same direction with the same up.

    The camera is re-aimed at the box centre and moved along its viewing direction: a perspective
    camera to the smallest distance at which the 8 corners project inside the shrunken window
    (``window`` / (1 + margin), lens shift and sensor fit included); an orthographic camera keeps
    its distance (at least ``MIN_ORTHO_DISTANCE_MM`` in front of the box) and gets the smallest
    ``width`` that holds the corners. A shift that moves the window off the view axis is not
    framed around (the result is then framed as if unshifted)."""
    right, up, back = look_at_axes(camera["position"], camera["target"], camera["up"])
    forward = (-back[0], -back[1], -back[2])
    centre = tuple((a + b) / 2 for a, b in zip(box[0], box[1], strict=True))
    (left, right_edge), (bottom, top) = window(camera, size)
    if not (left < 0 < right_edge and bottom < 0 < top):
        unshifted = window({**camera, "shift": [0.0, 0.0]}, size)
        (left, right_edge), (bottom, top) = unshifted
    shrink = 1.0 + margin
    left, right_edge, bottom, top = left / shrink, right_edge / shrink, bottom / shrink, top / shrink
    corners = [_sub(q, centre) for q in box_corners(*box)]
    reach = max(abs(_dot(v, forward)) for v in corners)  # how far the box extends along the view
    out = dict(camera)
    if camera["type"] == "orthographic":
        # Image coordinate / width must lie in the window.
        out["width"] = max(max(_scale_needed(_dot(v, right), left, right_edge),
                               _scale_needed(_dot(v, up), bottom, top)) for v in corners)
        distance = max(math.dist(camera["position"], camera["target"]), reach + MIN_ORTHO_DISTANCE_MM)
    else:
        # Image coordinate / ((distance + depth beyond the aim point) * extent) must lie in the window.
        extent = fitted_extent(camera)
        distance = max(max(_scale_needed(_dot(v, right), left, right_edge),
                           _scale_needed(_dot(v, up), bottom, top)) / extent - _dot(v, forward) for v in corners)
        distance = max(distance, reach * (1.0 + 1e-3))  # every corner stays in front of the camera
    out["target"] = [float(c) for c in centre]
    out["position"] = [float(c - distance * f) for c, f in zip(centre, forward, strict=True)]
    return out

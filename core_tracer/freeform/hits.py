"""How a ray finds its surface in a free-form design: Embree's nearest triangle (``embree``), never
the one the segment starts on, the hit recomputed in double precision on that triangle's plane,
and the smooth normal interpolated from the corner normals there.

Normals: the side a ray meets a lens from is told by the triangle's geometric normal (outward);
Fresnel, Snell, mirror and shading use the normal interpolated from the corner normals (smooth
shading), turned toward the incident side (``toward``, ``on_side``).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ..raytrace import optics
from .cache import GeometryCache
from .embree import EmbreeScene
from .geometry import Geometry
from .meshes import MeshData

SELF_HIT_RETRIES = 2


def nearest(g: Geometry, embree: EmbreeScene, o: np.ndarray, d: np.ndarray, start_triangle: np.ndarray
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each ray's next triangle (-1 for none), the distance to it and the barycentric (u, v) of
    the hit of rays ``o``, ``d``, never the triangle each starts on (``start_triangle``, -1 for an
    eye ray): a self-hit is skipped by asking again from just beyond it."""
    on_surface = np.nonzero(start_triangle >= 0)[0]
    if len(on_surface):
        # Query from just off the surface, on the side the ray leaves to; the segment itself
        # starts on the surface (``hit_point`` measures from there: exact path lengths).
        n = g.normal[start_triangle[on_surface]]
        side = np.where((optics.dot(d[on_surface], n) >= 0.0)[:, None], n, -n)
        o = o.copy()
        o[on_surface] += g.epsilon * side
    t, tri, uv = embree.nearest(o, d)
    for _ in range(SELF_HIT_RETRIES):
        again = np.nonzero((tri == start_triangle) & (tri >= 0))[0]
        if len(again) == 0:
            break
        skip = t[again] + g.epsilon
        t2, tri2, uv2 = embree.nearest(o[again] + skip[:, None] * d[again], d[again])
        t[again] = t2 + skip
        tri[again] = tri2
        uv[again] = uv2
    return t, tri, uv


def hit_point(g: Geometry, o: np.ndarray, d: np.ndarray, t: np.ndarray, tri: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray]:
    """The hit in double precision on the triangle's plane (Embree's distance is single precision):
    distance and point."""
    n = g.normal[tri]
    p0 = g.vertices[g.triangles[tri, 0]]
    denom = optics.dot(d, n)
    plane_t = optics.dot(p0 - o, n) / np.where(denom != 0.0, denom, 1.0)
    t = np.where((denom != 0.0) & np.isfinite(plane_t), plane_t, t)
    return t, o + t[:, None] * d


def shading_normal(g: Geometry, tri: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """The corner normals interpolated at the hit (barycentric ``uv`` of the second and third
    corners), unit, on the geometric normal's side (a smooth normal that disagrees with the face,
    at a silhouette of a coarse mesh, gives way to it)."""
    c = g.corner_normals[tri]
    u, v = uv[:, 0:1], uv[:, 1:2]
    n = (1.0 - u - v) * c[:, 0] + u * c[:, 1] + v * c[:, 2]
    length = np.linalg.norm(n, axis=1)
    geometric = g.normal[tri]
    ok = (length > 1e-12) & (optics.dot(n, geometric) > 0.0)
    n = np.where(ok[:, None], n / np.where(length > 1e-12, length, 1.0)[:, None], geometric)
    return n


def on_side(new: np.ndarray, d: np.ndarray, geometric: np.ndarray, by_face: Callable[[np.ndarray], np.ndarray],
             same: bool) -> np.ndarray:
    """Child directions ``new`` of rays ``d`` at faces of normal ``geometric``, kept on the side the
    branch belongs to (``same``: on through the face, as a transmitted ray; else back, as a
    reflected one). An interpolated normal can tip a grazing child across the face, which would put
    it on the wrong side of the medium it is said to be in: there ``by_face(selection)``, the same
    law with the face's own normal, decides."""
    want = np.sign(optics.dot(d, geometric)) * (1.0 if same else -1.0)  # the side, along the face normal
    wrong = optics.dot(new, geometric) * want <= 0.0
    if wrong.any():
        sel = np.nonzero(wrong)[0]
        new = new.copy()
        new[sel] = by_face(sel)
        # Grazing (refraction at the critical angle): the face's own law gives a direction in the
        # face's plane, or a rounding off it; tip it just onto the right side.
        still = sel[optics.dot(new[sel], geometric[sel]) * want[sel] <= 1e-9]
        if len(still):
            n = geometric[still]
            along = optics.dot(new[still], n) - 1e-6 * want[still]
            new[still] = optics.normalize(new[still] - along[:, None] * n)
    return new


def toward(n: np.ndarray, d: np.ndarray) -> np.ndarray:
    """``n`` turned to face the ray's incident side (against ``d``)."""
    return np.where((optics.dot(n, d) > 0.0)[:, None], -n, n)


def surface_hits(scene: dict, meshes: dict[str, MeshData], o: np.ndarray, d: np.ndarray,
                 geometry_cache: GeometryCache | None = None) -> dict[str, np.ndarray]:
    """The first surface each ray (``o``, unit ``d``, (N, 3) mm) meets, as the tracer finds it:
    ``t`` (inf for none), ``triangle`` (-1), ``part`` (index into freeform.parts, -1), ``point``
    and the smooth ``normal`` there (outward for a lens)."""
    cache = geometry_cache if geometry_cache is not None else GeometryCache()
    geometry, embree, _ = cache.get(scene, meshes)
    o = np.asarray(o, np.float64)
    d = np.asarray(d, np.float64)
    t, tri, uv = embree.nearest(o, d)
    hit = np.nonzero(tri >= 0)[0]
    point = np.full((len(o), 3), np.nan)
    normal = np.full((len(o), 3), np.nan)
    th, point[hit] = hit_point(geometry, o[hit], d[hit], t[hit], tri[hit])
    t = t.copy()
    t[hit] = th
    normal[hit] = shading_normal(geometry, tri[hit], uv[hit])
    part = np.where(tri >= 0, geometry.part[np.maximum(tri, 0)], -1)
    return {"t": t, "triangle": tri, "part": part, "point": point, "normal": normal}

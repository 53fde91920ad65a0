"""The Embree kernel through ``embreex``: one scene of all triangles, nearest-hit queries.

Embree works in single precision; the tracer takes from it only which triangle a ray hits and
recomputes the hit point in double precision on that triangle's plane (``render``)."""

from __future__ import annotations

import numpy as np


def embree_missing() -> str | None:
    """None where embreex imports, else the reason in one line."""
    try:
        import embreex.mesh_construction  # noqa: F401
        import embreex.rtcore_scene  # noqa: F401
    except ImportError as e:  # not installed, or no wheel for this platform
        return (f"free-form rendering needs the embreex package, which is not available here ({e}); "
                "install embreex 4.4 (wheels for CPython 3.11 on Linux x86-64, Windows x64, macOS arm64)")
    return None


class EmbreeScene:
    """All triangles of a design in one Embree scene; ``nearest`` returns (t, triangle index)."""

    def __init__(self, vertices: np.ndarray, triangles: np.ndarray):
        from embreex import mesh_construction, rtcore_scene

        self._scene = rtcore_scene.EmbreeScene()
        self._mesh = mesh_construction.TriangleMesh(self._scene, np.ascontiguousarray(vertices, np.float32),
                                                    np.ascontiguousarray(triangles, np.int32))
        # Embree builds its hierarchy on the first query: make that part of the build, not of a render.
        self._scene.run(np.zeros((1, 3), np.float32), np.array([[0.0, 0.0, 1.0]], np.float32))

    def nearest(self, o: np.ndarray, d: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Distance along each ray (inf for a miss), the triangle hit (-1 for a miss) and the
        barycentric weights (u, v) of its second and third corners at the hit, (N, 2)."""
        if len(o) == 0:
            return np.zeros(0), np.zeros(0, np.int64), np.zeros((0, 2))
        out = self._scene.run(np.ascontiguousarray(o, np.float32), np.ascontiguousarray(d, np.float32), output=1)
        prim = out["primID"].astype(np.int64)
        t = np.where(prim >= 0, out["tfar"].astype(np.float64), np.inf)
        return t, prim, np.stack([out["u"], out["v"]], axis=1).astype(np.float64)

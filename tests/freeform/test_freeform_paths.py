"""Table 1 on meshes: every transition the free-form tracer records is one of the paper's, or one
of the documented additions (class 20, a body reached, 0 a segment only meshes allow). A ray said to be in
the lens must be in it: an interpolated normal that tipped a child across its face would show as
a lens class followed by an air class (⑧ reflected to ③)."""

from __future__ import annotations

import numpy as np
import pytest
from needs import require

from core_tracer.freeform import render_passes, shapes
from core_tracer.freeform.meshes import MeshData
from core_tracer.freeform.render import NOT_IN_TABLE, TO_BODY
from core_tracer.raytrace import paths as P
from core_tracer.scene.validate import parse_scene

pytestmark = pytest.mark.slow

require("embreex")


def squashed(mesh: MeshData, centre, scale) -> MeshData:
    """A smooth sphere scaled into an ellipsoid (a pillow lens), its normals transformed to match."""
    c = np.asarray(centre, float)
    v = (mesh.vertices - c) * scale + c
    n = mesh.corner_normals / np.asarray(scale, float)
    n /= np.linalg.norm(n, axis=2, keepdims=True)
    return MeshData(mesh.name, v, mesh.triangles, n)


@pytest.mark.parametrize("lens_shape", ["slab", "pillow"])
def test_every_transition_is_table_1s_or_a_documented_addition(lens_shape):
    f, R, rim = 18.0, 45.0, 6.0
    vy = rim + R * R / (4 * f)
    if lens_shape == "slab":
        lens = shapes.box("Lens", (-46, 0, -46), (46, 3, 46))
    else:  # smooth, curved both sides: interpolated normals everywhere
        lens = squashed(shapes.uv_sphere("Lens", (0, 2.5, 0), 1.0, 96), (0, 2.5, 0), (46, 2.5, 46))
    meshes = [lens, shapes.paraboloid_dish("Reflector", f, R, vy, 32, 96),
              shapes.uv_sphere("Bulb", (0, vy - f, 0), 8, 48), shapes.cylinder("Socket", (0, 0), 5, vy - f, vy + 1),
              shapes.box("Housing", (-60, vy + 1, -60), (60, vy + 5, 60))]
    roles = ["lens", "reflector", "bulb", "socket", "body"]
    scene = parse_scene({"schema": "lamp-scene/2", "lamps": [{}], "image": {"width": 96, "height": 96},
                         "camera": {"position": [120, -500, 90], "target": [0, 10, 0], "fov_deg": 14},
                         "freeform": {"mesh_file": "l.glb", "parts": [
                             {"object": m.name, "role": r, **({"lens": {"ior": 1.6}} if r == "lens" else {})}
                             for m, r in zip(meshes, roles, strict=True)]}})
    result = render_passes(scene, {m.name: m for m in meshes}, record_transitions=True)
    seen = result.stats["transitions"]
    # A segment outside the table (0) may be followed by anything its end allows.
    odd = {t for t in seen if not (t[2] in (TO_BODY, NOT_IN_TABLE) or t[0] == NOT_IN_TABLE
                                   or (t[0] in P.TABLE_1 and P.allowed(*t)))}
    assert not odd, sorted(odd)
    # The paper's main walk is there: through the lens to the reflector, the bulb, and back out.
    assert {(1, 1, 2), (2, 1, 3), (3, 0, 5), (5, 1, 6), (6, 1, 10)} <= seen
    assert result.image.max() > 0


def test_the_body_is_a_surface_of_its_own():
    """The mesh body's surface id lies beyond every parametric surface (the LED and guide merges added
    LED and GUIDE after the housing, and BODY = HOUSING + 1 had become the LEDs' id: every free-form
    render failed building its class table)."""
    from core_tracer.freeform import render
    from core_tracer.freeform.geometry import BODY

    assert BODY > max(P.OUTER, P.CUT, P.REFLECTOR, P.WALL, P.BULB, P.SOCKET, P.NOTHING, P.PLATE_FRONT, P.RINGS,
                      P.HOUSING, P.LED, P.GUIDE)
    assert render.CLASS[P.IN_AIR, P.OUTER, BODY] == TO_BODY

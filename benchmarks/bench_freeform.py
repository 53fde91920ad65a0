"""How fast is the free-form tracer? The four-lamp preset as meshes (the add-on's own bpy-free
tessellation, ``lamp_addon/convert/meshes/``, at its 0.05 mm chord tolerance) rendered at
512x512, the acceleration structure built once and reused (build and render reported
separately), and the build of a 1-million-triangle lens.

    .venv/bin/python benchmarks/bench_freeform.py [--runs 5] [--size 512]

Targets: <= 1.0 s render at 512x512 on 2 cores; <= 1 s build of a 1-million-triangle lens.
The machine may be shared: each figure is the minimum over the runs (the least disturbed one).
"""

from __future__ import annotations

import importlib
import importlib.util
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from benchmarks.common import arguments  # noqa: E402
from core_tracer.freeform import GeometryCache, render_passes  # noqa: E402
from core_tracer.freeform.meshes import MeshData  # noqa: E402
from core_tracer.freeform.shapes import uv_sphere  # noqa: E402
from core_tracer.scene.derived import lamp_geometry  # noqa: E402
from core_tracer.scene.validate import load_scene, parse_scene  # noqa: E402


def convert_module():
    """``lamp_addon.convert.meshes`` imported without Blender (the package's __init__ needs bpy): its
    modules, as attributes of the package."""
    spec = importlib.util.spec_from_file_location("lamp_styling", ROOT / "__init__.py",
                                                  submodule_search_locations=[str(ROOT)])
    sys.modules.setdefault("lamp_styling", importlib.util.module_from_spec(spec))
    for name in ("builder", "lens", "parts"):
        importlib.import_module(f"lamp_styling.lamp_addon.convert.meshes.{name}")
    return importlib.import_module("lamp_styling.lamp_addon.convert.meshes")


def triangulated(name: str, mesh, offset=(0.0, 0.0, 0.0), flat_group: int = -1) -> MeshData:
    """A polygon mesh with smoothing groups as triangles with corner normals: within a group, the
    area-weighted mean of the group's face normals at the vertex; flat faces keep their own."""
    v = np.asarray(mesh.verts, np.float64) + offset
    tris, face_of = [], []
    for f, face in enumerate(mesh.faces):
        for k in range(1, len(face) - 1):
            tris.append((face[0], face[k], face[k + 1]))
            face_of.append(f)
    t = np.array(tris, np.int64)
    face_of = np.array(face_of)
    p = v[t]
    area_normal = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    group = np.asarray(mesh.group)[face_of]
    keys = group.astype(np.int64)[:, None] * (len(v) + 1) + t  # (group, vertex) of each corner
    uniq, inverse = np.unique(keys.ravel(), return_inverse=True)
    sums = np.zeros((len(uniq), 3))
    np.add.at(sums, inverse, np.repeat(area_normal, 3, axis=0))
    corner = sums[inverse].reshape(-1, 3, 3)
    flat = group == flat_group
    corner[flat] = area_normal[flat][:, None, :]
    corner /= np.maximum(np.linalg.norm(corner, axis=2, keepdims=True), 1e-300)
    return MeshData(name, v, t.astype(np.int32), corner)


def without_collar(meshes_mod, lens):
    """The lens solid without the open collar above the cuts (the add-on's mesh carries it for the
    side wall's look): a lens role needs the closed glass only."""
    v = np.asarray(lens.verts)
    keep = [i for i, face in enumerate(lens.faces)
            if not (lens.material[i] == meshes_mod.builder.LENS_SIDE_WALL and v[list(face), 1].min() > 0.0)]
    return type(lens)(v, [lens.faces[i] for i in keep], lens.material[keep], lens.group[keep])


def front_with_holes(name: str, scene: dict, rims: list[np.ndarray]) -> MeshData:
    """The body: front face y = 0 with one opening per lamp (each lamp's square cell joined to its rim
    polygon by a ring of quads: the four-lamp preset's lamps tile the face in 120 mm squares), and the
    box's other faces."""
    body = scene["body"]
    (bx, bz), (w, h), depth = body["center"], body["size"], body["depth"]
    verts, tris = [], []
    for lamp, rim in zip(scene["lamps"], rims, strict=True):
        cx, cz = lamp["center"]
        s = h / 2
        n = len(rim)
        d = rim - [cx, cz]
        scale = s / np.max(np.abs(d), axis=1)
        outer = d * scale[:, None] + [cx, cz]
        base = len(verts)
        verts += [(x, 0.0, z) for x, z in rim] + [(x, 0.0, z) for x, z in outer]
        for i in range(n):
            j = (i + 1) % n
            a, b, c, e = base + i, base + j, base + n + j, base + n + i
            tris += [(a, b, c), (a, c, e)]
        # The square's corners, missing from the projected ring unless a rim vertex points at them.
        for corner in ((1, 1), (-1, 1), (-1, -1), (1, -1)):
            q = np.array([cx + corner[0] * s, cz + corner[1] * s])
            k = int(np.argmin(np.linalg.norm(outer - q, axis=1)))
            verts.append((q[0], 0.0, q[1]))
            for kk in (k - 1, k):
                a, b = base + n + kk % n, base + n + (kk + 1) % n
                tris.append((a, b, len(verts) - 1))
    x0, x1, z0, z1 = bx - w / 2, bx + w / 2, bz - h / 2, bz + h / 2
    base = len(verts)
    verts += [(x, y, z) for x in (x0, x1) for y in (0.0, depth) for z in (z0, z1)]
    c = {(i, j, k): base + 4 * i + 2 * j + k for i in (0, 1) for j in (0, 1) for k in (0, 1)}
    for quad in ([c[0, 1, 0], c[0, 1, 1], c[1, 1, 1], c[1, 1, 0]], [c[0, 0, 0], c[0, 0, 1], c[0, 1, 1], c[0, 1, 0]],
                 [c[1, 0, 0], c[1, 1, 0], c[1, 1, 1], c[1, 0, 1]], [c[0, 0, 0], c[0, 1, 0], c[1, 1, 0], c[1, 0, 0]],
                 [c[0, 0, 1], c[1, 0, 1], c[1, 1, 1], c[0, 1, 1]]):
        tris += [(quad[0], quad[1], quad[2]), (quad[0], quad[2], quad[3])]
    v = np.array(verts, np.float64)
    t = np.array(tris, np.int32)
    p = v[t]
    normal = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    front = np.abs(p[:, :, 1]).max(axis=1) == 0.0
    flip = front & (normal[:, 1] > 0)  # the front faces the viewer (-y)
    t[flip] = t[flip][:, ::-1]
    keep = np.linalg.norm(normal, axis=1) > 1e-12
    return MeshData(name, v, t[keep], None)


def four_lamp_design(preset: Path) -> tuple[dict, dict[str, MeshData]]:
    """The preset's lamps as meshes with roles: a free-form design like the converted preset."""
    meshes_mod = convert_module()
    scene = load_scene(preset)
    meshes: dict[str, MeshData] = {}
    parts: list[dict] = []
    rims = []
    for i, lamp in enumerate(scene["lamps"]):
        g = lamp_geometry(lamp)
        cx, cz = lamp["center"]
        axis = (cx, 0.0, cz)
        R = lamp["lens"]["radius"]
        reflector = meshes_mod.parts.reflector_mesh(lamp, meshes_mod.builder.circle_segments(R))
        n = len(reflector.verts) and meshes_mod.builder.circle_segments(R)
        lens = without_collar(meshes_mod, meshes_mod.lens.lens_mesh(lamp, n))
        bulb = meshes_mod.parts.sphere_mesh(lamp["bulb"]["radius"])
        bx, by, bz = g["bulb_center"]
        socket = meshes_mod.parts.socket_mesh(lamp["socket"]["radius"], g["vertex"], by)
        lens_values = {k: lamp["lens"][k] for k in ("ior", "diffuse_color", "specular", "shininess")}
        lens_values.update({k: lamp["lens"][k] for k in ("absorption", "transmitted_color", "reference_thickness")
                            if k in lamp["lens"]})
        for role, mesh, offset, values in (
                ("lens", lens, axis, lens_values),
                ("reflector", reflector, axis, {k: lamp["reflector"][k] for k in
                                                ("color", "reflectance", "scatter", "shininess")}),
                ("bulb", bulb, (cx + bx, by, cz + bz), {"intensity": lamp["bulb"]["intensity"],
                                                        "on": lamp["bulb"]["on"]}),
                ("socket", socket, axis, {"color": lamp["socket"]["color"]})):
            name = f"Lamp {i + 1} {role}"
            meshes[name] = triangulated(name, mesh, offset)
            parts.append({"object": name, "role": role, role: values})
        rims.append(meshes_mod.builder.rim_polygon(R, n) + np.array([cx, cz]))
    meshes["Body"] = front_with_holes("Body", scene, rims)
    parts.append({"object": "Body", "role": "body",
                  "body": {k: scene["body"][k] for k in ("color", "specular", "shininess")}})
    doc = {k: v for k, v in scene.items() if k != "schema"}
    doc["schema"] = "lamp-scene/2"
    doc["freeform"] = {"mesh_file": "four-lamp.glb", "parts": parts}
    return parse_scene(doc), meshes


def timed(work) -> tuple[float, float]:
    """(wall seconds, CPU seconds of all the process's threads) of ``work()``."""
    wall, cpu = time.perf_counter(), time.process_time()
    work()
    return time.perf_counter() - wall, time.process_time() - cpu


def shown(times: list[tuple[float, float]]) -> str:
    walls = sorted(w for w, _ in times)
    return (f"wall min {walls[0]:.3f} s (median {walls[len(walls) // 2]:.3f} s), CPU min "
            f"{min(c for _, c in times):.3f} s; load average {os.getloadavg()[0]:.1f}")


def main() -> int:
    parser = arguments(__doc__, "four-lamp-rear-combination.json", runs=5, size=512)
    parser.add_argument("--save", metavar="PNG", help="also write the last render as PNG")
    args = parser.parse_args()

    scene, meshes = four_lamp_design(Path(args.preset))
    triangles = sum(len(m.triangles) for m in meshes.values())
    print(f"four-lamp mesh design: {len(meshes)} meshes, {triangles} triangles; {os.cpu_count()} cores; "
          f"minimum of {args.runs} runs (shared machine)")
    builds, renders = [], []
    for _ in range(args.runs):
        cache = GeometryCache()
        builds.append(timed(lambda: cache.get(scene, meshes)))  # noqa: B023
    cache = GeometryCache()
    cache.get(scene, meshes)
    for _ in range(args.runs):
        renders.append(timed(lambda: render_passes(scene, meshes, args.size, args.size, geometry_cache=cache)))
    result = render_passes(scene, meshes, args.size, args.size, geometry_cache=cache)
    assert result.stats["build_seconds"] == 0.0  # reused
    print(f"  build (checks + Embree): {shown(builds)}")
    print(f"  render {args.size}x{args.size}: {shown(renders)}; {result.stats['segments']} segments, "
          f"max depth {result.stats['max_depth']}")
    from core_tracer import render
    preset = load_scene(Path(args.preset))
    parametric = render(preset, args.size, args.size)
    print(f"  the parametric tracer on the same preset, same load: "
          f"{shown([timed(lambda: render(preset, args.size, args.size)) for _ in range(args.runs)])}")
    lum = lambda im: im @ np.array([0.2126, 0.7152, 0.0722])  # noqa: E731
    a, b = lum(result.image), lum(parametric)
    seen = np.maximum(a, b) > 1e-3 * b.max()
    rel = np.abs(a - b)[seen] / np.maximum(a, b)[seen]
    print(f"  against the parametric tracer (same preset): {np.mean(rel <= 0.02) * 100:.1f} % of the lit pixels "
          f"within 2 %, {np.mean(rel <= 0.10) * 100:.1f} % within 10 % (cut creases and silhouettes differ by "
          "the meshes' chord error)")
    if args.save:
        from core_tracer.images.imageio import write_image
        write_image(args.save, result.image, scene)

    # A 1-million-triangle lens: a smooth UV sphere of 1000 x 500 segments.
    lens = uv_sphere("Big lens", (0.0, 40.0, 0.0), 30.0, segments=1000)
    big = parse_scene({"schema": "lamp-scene/2", "lamps": [{}], "freeform": {"mesh_file": "big.glb", "parts": [
        {"object": "Big lens", "role": "lens"}]}})
    times = [timed(lambda: GeometryCache().get(big, {"Big lens": lens})) for _ in range(args.runs)]
    print(f"  {len(lens.triangles)}-triangle lens, build (checks + Embree): {shown(times)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""A brute-force tracer written from docs/model.md alone: one ray at a time, float64, every direction
and normal renormalised, and the cut surface found by testing every cell under the ray's path
through the cut slab (no cell walk). Slow, but independent of ``core_tracer.tracer``'s wavefront,
so the tests can check the fast tracer pixel by pixel.

    .venv/bin/python tests/reference_tracer.py [preset] [--size 96x72] [--set lamps[0].lens.ior=2.4 ...]

prints how many lens pixels of the fast tracer differ from this reference and by how much.
"""

from __future__ import annotations

import copy
import math
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from core_tracer.raytrace.camera import eye_rays, make_camera  # noqa: E402

# No distance threshold against self-intersection: each ray knows the surface it leaves, and the
# root that is that surface is excluded by the geometry (a plane is not met again, a convex cap
# left outward is not met again, a cap left inward or the reflector only at their other root).
CUTOFF = 1e-3  # docs/model.md §5: a branch below 0.1 % (max over RGB) is dropped
MAX_SEGMENTS = 64  # docs/model.md §5: the depth cap, counting the eye segment


def _unit(v: np.ndarray) -> np.ndarray:
    return v / math.sqrt(float(v @ v))


def fresnel(cos_i: float, n1: float, n2: float) -> float:
    """Exact unpolarised Fresnel reflectance by angles; total internal reflection gives 1."""
    cos_i = min(1.0, max(0.0, cos_i))
    sin_i = math.sqrt(max(0.0, 1.0 - cos_i * cos_i))
    sin_t = n1 / n2 * sin_i
    if sin_t >= 1.0:
        return 1.0
    cos_t = math.sqrt(1.0 - sin_t * sin_t)
    rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t)
    rp = (n1 * cos_t - n2 * cos_i) / (n1 * cos_t + n2 * cos_i)
    return 0.5 * (rs * rs + rp * rp)


def phong(normal, view, light, diffuse, light_color, ambient, w, n) -> np.ndarray:
    """docs/model.md §4, eq. (1): no specular term where the light is behind the surface."""
    cos_t = float(normal @ light)
    half = _unit(view + light)
    cos_b = max(0.0, float(normal @ half))
    spec = w * cos_b**n if cos_t > 0 else 0.0
    return (ambient + (1 - ambient) * max(0.0, cos_t)) * np.asarray(diffuse) + spec * np.asarray(light_color)


def _roots(a: float, b: float, c: float) -> list[float]:
    """Real roots of a t^2 + b t + c by the cancellation-free formula."""
    if a == 0.0:
        return [-c / b] if b != 0.0 else []
    disc = b * b - 4 * a * c
    if disc < 0:
        return []
    q = -0.5 * (b + math.copysign(math.sqrt(disc), b))
    if q == 0.0:
        return [0.0]
    return [q / a, c / q]


@dataclass
class Lamp:
    """One lamp's parts in its local frame (docs/model.md §3, derived here from the JSON, not from
    ``scene.lamp_geometry``)."""

    lamp: dict

    def __post_init__(self):
        L = self.lamp
        self.R = L["lens"]["radius"]
        self.t = L["lens"]["thickness"]
        self.h = L["cuts"]["height"]
        self.p = L["cuts"]["pitch"]
        self.n = L["lens"]["ior"]
        lens = L["lens"]
        if "absorption" in lens:
            self.A = np.array(lens["absorption"])
        else:
            self.A = -np.log(np.array(lens["transmitted_color"])) / lens["reference_thickness"]
        c = self.p / math.sqrt(2)
        self.rho = (c * c + self.h * self.h) / (2 * self.h) if self.h > 0 else math.inf
        self.f = L["reflector"]["focal_length"]
        self.rim = self.t + self.h + L["reflector"]["gap"]
        self.rect = lens.get("outline", "round") == "rectangular"
        if self.rect:  # a rounded rectangle: half sizes and the corner circles' radius
            self.hw, self.hh, self.rc = lens["width"] / 2, lens["height"] / 2, lens["corner_radius"]
            # the paraboloid meets the rim plane at the outline's farthest point, a corner circle's
            reach = math.hypot(self.hw - self.rc, self.hh - self.rc) + self.rc
        else:
            reach = self.R
        self.vertex = self.rim + reach**2 / (4 * self.f)
        off = L["bulb"]["offset"]
        self.bulb = np.array([off[0], self.vertex - self.f + off[1], off[2]])
        self.rb = L["bulb"]["radius"]
        self.I0 = np.array(L["bulb"]["intensity"]) if L["bulb"]["on"] else np.zeros(3)
        self.rs = L["socket"]["radius"]

    # -- surfaces: (t, normal) or None ---------------------------------------------------------

    def inside_outline(self, x: float, z: float) -> bool:
        if not self.rect:
            return x * x + z * z <= self.R**2
        qx, qz = abs(x) - (self.hw - self.rc), abs(z) - (self.hh - self.rc)
        if qx <= 0 or qz <= 0:
            return abs(x) <= self.hw and abs(z) <= self.hh
        return qx * qx + qz * qz <= self.rc**2

    def wall(self, o, d):
        a = d[0] ** 2 + d[2] ** 2
        if a == 0:
            return None
        if self.rect:
            return self._rect_wall(o, d)
        roots = _roots(a, 2 * (o[0] * d[0] + o[2] * d[2]), o[0] ** 2 + o[2] ** 2 - self.R**2)
        t = max(roots) if roots else -1
        return (t, None) if t > 0 else None

    def _rect_wall(self, o, d):
        """The extruded rounded rectangle left from inside: every one of its eight pieces (four
        planes, four quarter cylinders) tested, the nearest hit beyond the origin kept."""
        hw, hh, r = self.hw, self.hh, self.rc
        a, b = hw - r, hh - r
        ts = []
        for axis, half, other, span in ((0, hw, 2, b), (2, hh, 0, a)):
            for side in (-1.0, 1.0):
                if d[axis] != 0:
                    t = (side * half - o[axis]) / d[axis]
                    if abs(o[other] + t * d[other]) <= span + 1e-12:
                        ts.append(t)
        if r > 0:
            for sx in (-1.0, 1.0):
                for sz in (-1.0, 1.0):
                    cx, cz = sx * a, sz * b
                    ax, az = o[0] - cx, o[2] - cz
                    for t in _roots(d[0] ** 2 + d[2] ** 2, 2 * (ax * d[0] + az * d[2]), ax * ax + az * az - r * r):
                        x, z = o[0] + t * d[0], o[2] + t * d[2]
                        if sx * (x - cx) >= -1e-12 and sz * (z - cz) >= -1e-12:
                            ts.append(t)
        ts = [t for t in ts if t > 0]
        return (min(ts), None) if ts else None

    def outer(self, o, d, src):
        if d[1] >= 0 or src == "outer":
            return None
        t = -o[1] / d[1]
        return (t, np.array([0.0, -1.0, 0.0])) if t > 0 else None

    def cuts(self, o, d, t_max, src, in_lens):
        """Nearest cut-surface hit before ``t_max``: (t, normal out of the lens material, cell)."""
        base = self.t
        if self.h == 0:
            if d[1] == 0 or src == "cut":
                return None
            t = (base - o[1]) / d[1]
            return (t, np.array([0.0, 1.0, 0.0]), None) if 0 < t < t_max else None
        top = base + self.h
        # the part of the ray inside the slab base <= y <= top, clipped at t_max
        if d[1] == 0:
            if not base <= o[1] <= top:
                return None
            t0, t1 = 0.0, t_max
        else:
            ta, tb = (base - o[1]) / d[1], (top - o[1]) / d[1]
            t0, t1 = max(0.0, min(ta, tb)), min(t_max, max(ta, tb))
        if t0 > t1 or not math.isfinite(t1):
            return None
        xs = (o[0] + t0 * d[0], o[0] + t1 * d[0])
        zs = (o[2] + t0 * d[2], o[2] + t1 * d[2])
        p = self.p
        best = None
        for i in range(math.floor(min(xs) / p + 0.5) - 1, math.floor(max(xs) / p + 0.5) + 2):
            for j in range(math.floor(min(zs) / p + 0.5) - 1, math.floor(max(zs) / p + 0.5) + 2):
                # sphere of radius rho whose top is the apex (i p, top, j p); relative to the apex
                # the equation is |a + t d|^2 + 2 rho (a_y + t d_y) = 0, free of rho^2 terms
                a = np.array([o[0] - i * p, o[1] - top, o[2] - j * p])
                roots = _roots(1.0, 2 * (float(a @ d) + self.rho * d[1]), float(a @ a) + 2 * self.rho * a[1])
                if src == ("cut", i, j):  # leaving this cap: outward never again, inward only the far root
                    roots = [max(roots)] if in_lens and roots else []
                for t in roots:
                    if not 0 < t < t_max or (best is not None and t >= best[0]):
                        continue
                    hit = a + t * d
                    tol = 1e-9 * p
                    if abs(hit[0]) <= p / 2 + tol and abs(hit[2]) <= p / 2 + tol and -self.h - tol <= hit[1] <= tol:
                        best = (t, _unit(np.array([hit[0], hit[1] + self.rho, hit[2]])), ("cut", i, j))
        return best

    def reflector(self, o, d, src):
        k = 1 / (4 * self.f)
        roots = _roots((d[0] ** 2 + d[2] ** 2) * k, d[1] + 2 * (o[0] * d[0] + o[2] * d[2]) * k,
                       o[1] + (o[0] ** 2 + o[2] ** 2) * k - self.vertex)
        if src == "reflector":  # leaving the mirror: the root nearest 0 is the mirror itself
            roots = [max(roots, key=abs)] if len(roots) == 2 else []
        ts = sorted(t for t in roots if t > 0 and o[1] + t * d[1] >= self.rim - 1e-9)
        if self.rect:  # the paraboloid trimmed to the outline's prism
            ts = [t for t in ts if self.inside_outline(*(o[[0, 2]] + t * d[[0, 2]]) / (1 + 1e-12))]
        if not ts:
            return None
        hit = o + ts[0] * d
        return ts[0], _unit(np.array([-hit[0] / (2 * self.f), -1.0, -hit[2] / (2 * self.f)]))

    def bulb_hit(self, o, d):
        oc = o - self.bulb
        roots = _roots(1.0, 2 * float(oc @ d), float(oc @ oc) - self.rb**2)
        ts = sorted(t for t in roots if t > 0)
        return (ts[0], None) if ts else None

    def socket(self, o, d):
        """docs/model.md §3: a solid cylinder from the vertex to the bulb-centre plane, closed there by a disk."""
        y0, y1 = self.bulb[1], self.vertex
        best = math.inf
        a = d[0] ** 2 + d[2] ** 2
        if a > 0:
            for t in _roots(a, 2 * (o[0] * d[0] + o[2] * d[2]), o[0] ** 2 + o[2] ** 2 - self.rs**2):
                if 0 < t < best and y0 <= o[1] + t * d[1] <= y1:
                    best = t
        if d[1] != 0:
            t = (y0 - o[1]) / d[1]
            if 0 < t < best and (o[0] + t * d[0]) ** 2 + (o[2] + t * d[2]) ** 2 <= self.rs**2:
                best = t
        return (best, None) if math.isfinite(best) else None


class Reference:
    def __init__(self, scene: dict, width: int, height: int):
        self.scene = scene
        self.camera = make_camera(scene["camera"], width, height)
        self.lamps = [Lamp(lamp) for lamp in scene["lamps"]]
        light = scene["light"]
        self.light = _unit(np.array(light["direction"], dtype=float))
        self.background = np.array(scene["background"], dtype=float)
        self.escapes = 0  # segments that found no surface inside a lamp (impossible if exact)

    def pixel(self, index: int) -> tuple[np.ndarray, bool]:
        """(RGB of the pixel, whether its eye ray reaches a lens)."""
        o, d = eye_rays(self.camera, np.array([index]))
        o, d = o[0], _unit(d[0])
        body = self.scene["body"]
        lo = np.array([body["center"][0] - body["size"][0] / 2, 0.0, body["center"][1] - body["size"][1] / 2])
        hi = np.array([body["center"][0] + body["size"][0] / 2, body["depth"], body["center"][1] + body["size"][1] / 2])
        t_near, t_far, face = -math.inf, math.inf, -1
        for ax in range(3):
            if d[ax] == 0:
                if not lo[ax] <= o[ax] <= hi[ax]:
                    return self.background.copy(), False
                continue
            t1, t2 = (lo[ax] - o[ax]) / d[ax], (hi[ax] - o[ax]) / d[ax]
            if min(t1, t2) > t_near:
                t_near, face = min(t1, t2), ax
            t_far = min(t_far, max(t1, t2))
        if not (t_near <= t_far and t_near > 0):
            return self.background.copy(), False
        p = o + t_near * d
        light = self.scene["light"]
        if face == 1 and d[1] > 0:
            for L, lamp in zip(self.lamps, self.scene["lamps"], strict=True):
                local = np.array([p[0] - lamp["center"][0], 0.0, p[2] - lamp["center"][1]])
                if L.inside_outline(local[0], local[2]):
                    return self._lens(L, local, d), True
        normal = np.zeros(3)
        normal[face] = -math.copysign(1.0, d[face])
        return phong(normal, -d, self.light, body["color"], light["color"], light["ambient"],
                     body["specular"], body["shininess"]), False

    def _lens(self, L: Lamp, local: np.ndarray, d: np.ndarray) -> np.ndarray:
        lens = L.lamp["lens"]
        light = self.scene["light"]
        normal = np.array([0.0, -1.0, 0.0])
        r = fresnel(d[1], 1.0, L.n)
        out = r * phong(normal, -d, self.light, lens["diffuse_color"], light["color"], light["ambient"],
                        lens["specular"], lens["shininess"]) + r * self.background
        k = np.full(3, 1 - r)
        if k.max() >= CUTOFF:
            out = out + self._trace(L, local, self._refract(d, normal, 1 / L.n), k, True, False, 2, "outer")
        return out

    @staticmethod
    def _refract(d, facing, eta):
        cos_i = -float(d @ facing)
        cos_t = math.sqrt(max(0.0, 1 - eta * eta * (1 - cos_i * cos_i)))
        return _unit(eta * d + (eta * cos_i - cos_t) * facing)

    def _trace(self, L: Lamp, o, d, k, in_lens: bool, seen: bool, segment: int, src) -> np.ndarray:
        if segment > MAX_SEGMENTS:
            return np.zeros(3)
        wall = L.wall(o, d)
        t_wall = wall[0] if wall else math.inf
        hits = [("wall", wall), ("cut", L.cuts(o, d, t_wall, src, in_lens))]
        hits += [("outer", L.outer(o, d, src))] if in_lens else [
            ("reflector", L.reflector(o, d, src)), ("bulb", L.bulb_hit(o, d)), ("socket", L.socket(o, d))]
        hits = [(h[0], kind, h[1], h[2] if len(h) > 2 else kind) for kind, h in hits if h is not None]
        if not hits:
            self.escapes += 1
            return np.zeros(3)
        t, kind, normal, here = min(hits, key=lambda x: x[0])
        if kind == "cut" and here is None:
            here = "cut"
        if in_lens:
            k = k * np.exp(-L.A * t)  # eq. (2)
        hit = o + t * d
        lamp = L.lamp
        if kind == "wall":
            return k * np.array(lamp["lens"]["side_wall_color"])
        if kind == "bulb":
            return k * L.I0
        if kind == "socket":
            return k * np.array(lamp["socket"]["color"])
        if kind == "reflector":
            refl = lamp["reflector"]
            out = np.zeros(3) if seen else k * np.array(refl["color"])
            half = _unit(-d + _unit(L.bulb - hit))
            out = out + k * refl["scatter"] * max(0.0, float(normal @ half)) ** refl["shininess"] * L.I0
            k2 = k * refl["reflectance"]
            if k2.max() >= CUTOFF:
                out = out + self._trace(L, hit, _unit(d - 2 * float(d @ normal) * normal), k2, False, True,
                                        segment + 1, "reflector")
            return out
        # a lens surface: Fresnel split (docs/model.md §5)
        facing = -normal if in_lens else normal
        n1, n2 = (L.n, 1.0) if in_lens else (1.0, L.n)
        r = fresnel(-float(d @ facing), n1, n2)
        out = np.zeros(3)
        kr = k * r
        if kr.max() >= CUTOFF:
            out = out + self._trace(L, hit, _unit(d - 2 * float(d @ facing) * facing), kr, in_lens, seen, segment + 1,
                                    here)
        kt = k * (1 - r)
        if r < 1:
            if kind == "outer":
                out = out + kt * self.background
            elif kt.max() >= CUTOFF:
                out = out + self._trace(L, hit, self._refract(d, facing, n1 / n2), kt, not in_lens, seen,
                                        segment + 1, here)
        return out


def nudged(scene: dict, distance: float) -> dict:
    """The scene with the camera moved sideways by ``distance`` mm."""
    out = copy.deepcopy(scene)
    out["camera"]["position"][0] += distance
    return out


def compare(scene: dict, width: int, height: int, threshold: float = 1e-5, nudge: float = 1e-9) -> dict:
    """Every lens pixel of the fast tracer against this reference: how many differ by more than
    ``threshold`` and by 0.1 %, and the largest error, relative to the reference pixel's largest
    channel. A pixel counts only where it is *stable*: where moving the camera by ``nudge`` mm
    changes the reference by at most ``threshold``. Deep total-internal-reflection paths in a
    clear lens are chaotic (a curved cap multiplies a position error about threefold per bounce):
    there even one unit in the last place of the camera position changes the pixel, and a tracer
    that restarts rays a hair off each surface cannot be compared pixel by pixel."""
    from core_tracer import render

    image = render(scene, width, height)
    ref, ref2 = Reference(scene, width, height), Reference(nudged(scene, nudge), width, height)
    lens = unstable = wrong = wrong_1e3 = 0
    worst, where = 0.0, None
    for index in range(width * height):
        value, on_lens = ref.pixel(index)
        if not on_lens:
            continue
        lens += 1
        scale = max(value.max(), 1e-12)
        if np.abs(ref2.pixel(index)[0] - value).max() / scale > threshold:
            unstable += 1
            continue
        row, col = divmod(index, width)
        err = float(np.abs(image[row, col] - value).max() / scale)
        wrong += err > threshold
        wrong_1e3 += err > 1e-3
        if err > worst:
            worst, where = err, (row, col)
    return {"lens_pixels": lens, "unstable": unstable, "wrong": wrong, "wrong_by_0.1%": wrong_1e3,
            "max_error": worst, "worst_pixel": where, "escapes": ref.escapes}


def main(argv: list[str]) -> int:
    import argparse
    import json

    from helpers import scene_with

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", default="96x72")
    parser.add_argument("--set", action="append", default=[], help="dotted.path=JSON value")
    parser.add_argument("--threshold", type=float, default=1e-5)
    parser.add_argument("--nudge", type=float, default=1e-9, help="camera move (mm) that decides stability")
    args = parser.parse_args(argv)
    w, h = (int(x) for x in args.size.split("x"))
    edits = {k: json.loads(v) for k, v in (s.split("=", 1) for s in args.set)}
    print(compare(scene_with(**edits), w, h, args.threshold, args.nudge))
    return 0


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    raise SystemExit(main(sys.argv[1:]))

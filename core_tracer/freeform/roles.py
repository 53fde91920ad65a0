"""The role values of a free-form design's parts as arrays, as ``raytrace.lamp_table`` does for
lamps: refractive index and absorption of lenses, colours, Phong and Blinn values, and which bulbs
each reflector scatters toward (docs/model.md §5.2)."""

from __future__ import annotations

import numpy as np

from ..scene.derived import lens_absorption
from .geometry import Geometry


class PartTable:
    """Every part's role values as arrays indexed by part number (gathered per ray)."""

    def __init__(self, scene: dict, geometry: Geometry):
        parts = scene["freeform"]["parts"]
        n = len(parts)
        self.ior = np.ones(n)
        self.absorption = np.zeros((n, 3))
        self.color = np.zeros((n, 3))  # diffuse / constant / terminal colour of the role
        self.specular = np.zeros(n)
        self.shininess = np.zeros(n)
        self.reflectance = np.zeros(n)
        self.scatter = np.zeros(n)
        bulbs = []
        for i, part in enumerate(parts):
            v = part[part["role"]]
            role = part["role"]
            if role == "lens":
                self.ior[i] = v["ior"]
                self.absorption[i] = lens_absorption(v)
                self.color[i] = v["diffuse_color"]
                self.specular[i], self.shininess[i] = v["specular"], v["shininess"]
            elif role == "reflector":
                self.color[i] = v["color"]
                self.reflectance[i], self.scatter[i], self.shininess[i] = v["reflectance"], v["scatter"], v["shininess"]
            elif role == "bulb":
                self.color[i] = v["intensity"] if v["on"] else (0.0, 0.0, 0.0)
                bulbs.append(i)
            elif role in ("socket", "side_wall"):
                self.color[i] = v["color"]
            elif role == "body":
                self.color[i] = v["color"]
                self.specular[i], self.shininess[i] = v["specular"], v["shininess"]
        # A bulb's centre is its mesh's centroid (area-weighted over the surface). Each reflector
        # scatters toward the bulbs whose centre lies in its bounding box, else toward the nearest
        # bulb: in a multi-lamp design each reflector sees its own bulb, as in the parametric lamp.
        self.bulb_center = np.zeros((len(bulbs), 3))
        for b, i in enumerate(bulbs):
            c = geometry.corners(geometry.part == i)
            area = 0.5 * np.linalg.norm(np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0]), axis=1)
            self.bulb_center[b] = (c.mean(axis=1) * area[:, None]).sum(axis=0) / max(area.sum(), 1e-300)
        self.bulb_intensity = self.color[bulbs] if bulbs else np.zeros((0, 3))
        self.bulbs_of = np.zeros((n, max(1, len(bulbs))), bool)  # [reflector part, bulb]
        for i, part in enumerate(parts):
            if part["role"] != "reflector" or not bulbs:
                continue
            c = geometry.corners(geometry.part == i).reshape(-1, 3)
            lo, hi = c.min(axis=0), c.max(axis=0)
            inside = np.all((self.bulb_center >= lo) & (self.bulb_center <= hi), axis=1)
            if inside.any():
                self.bulbs_of[i, : len(bulbs)] = inside
            else:
                centre = (lo + hi) / 2
                self.bulbs_of[i, int(np.argmin(np.linalg.norm(self.bulb_center - centre, axis=1)))] = True

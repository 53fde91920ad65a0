"""The role values of a free-form design's parts as arrays, as ``raytrace.lamp_table`` and
``raytrace.spectral.photometric_lamps`` do for lamps: refractive index and absorption of lenses,
colours, Phong and Blinn values, and which bulbs each reflector scatters toward (docs/model.md §5.2).

The values have one column per channel the rays carry (``Lighting.channels``): R, G, B in the paper
mode, the wavelength bands in the photometric one (docs/photometric.md), where the same roles take
their physical values: a lens's n(λ) and filter, a reflector's finish ρ(λ) split into mirror and
glow, a bulb's luminance (its flux over the mesh's area, a Lambertian emitter), the body's paint;
sockets and side walls are unlit. The walk (``render``) is the same in both modes.
"""

from __future__ import annotations

import math

import numpy as np

from ..raytrace import spectral
from ..scene.derived import lens_absorption
from .geometry import Geometry


def part_areas(geometry: Geometry, part: int) -> tuple[np.ndarray, np.ndarray]:
    """(triangle centroids (T, 3), triangle areas (T,)) of one part's mesh."""
    c = geometry.corners(geometry.part == part)
    area = 0.5 * np.linalg.norm(np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0]), axis=1)
    return c.mean(axis=1), area


class PartTable:
    """Every part's role values as arrays indexed by part number (gathered per ray)."""

    def __init__(self, scene: dict, geometry: Geometry, photometric: spectral.Photometric | None = None):
        parts = scene["freeform"]["parts"]
        n = len(parts)
        channels = 3 if photometric is None else photometric.channels
        self.ior = np.ones(n)  # the index the ray's direction follows (photometric: n_d)
        # photometric: n per band for Fresnel (dispersion in Fresnel only, as the parametric lens)
        self.band_ior = None if photometric is None else np.ones((n, channels))
        self.absorption = np.zeros((n, channels))  # per mm (eq. 2; photometric: Beer-Lambert per band)
        self.color = np.zeros((n, channels))  # the diffuse / constant / terminal value of the role
        self.specular = np.zeros(n)
        self.shininess = np.zeros(n)
        self.mirror = np.zeros((n, channels))  # the share a reflector mirrors (photometric: (1 - s) ρ(λ))
        self.scatter = np.zeros(n)  # w of eq. (3) (photometric: the glow's share on the normalised lobe)
        self.glow_tint = np.ones((n, channels))  # the glow's colour (photometric: the finish's ρ(λ))
        bulbs = []
        for i, part in enumerate(parts):
            v = part[part["role"]]
            role = part["role"]
            where = f"freeform.parts[{i}].{role}"
            if role == "lens":
                self.specular[i], self.shininess[i] = v["specular"], v["shininess"]
                if photometric is None:
                    self.ior[i] = v["ior"]
                    self.absorption[i] = lens_absorption(v)
                    self.color[i] = v["diffuse_color"]
                else:  # as ``spectral.photometric_lamps``: no appearance colour of its own
                    self.ior[i] = spectral.index_of(v)[0]
                    self.band_ior[i] = spectral.band_index(v, photometric.bands)
                    self.absorption[i] = spectral.absorption(v, photometric.bands, where)
            elif role == "reflector":
                self.shininess[i] = v["shininess"]
                if photometric is None:
                    self.color[i] = v["color"]
                    self.mirror[i], self.scatter[i] = v["reflectance"], v["scatter"]
                else:
                    finish = spectral.finish_reflectance(v, photometric.bands)
                    share = v["scatter_share"]
                    self.mirror[i] = (1.0 - share) * finish
                    # the glow's share on the normalised Blinn lobe (n + 8)/(8 pi) (Akenine-Moeller et
                    # al., Real-Time Rendering, 3rd ed. 2008, eq. 7.49), as the parametric reflector's
                    self.scatter[i] = share * (v["shininess"] + 8.0) / (8.0 * math.pi)
                    self.glow_tint[i] = finish
            elif role == "bulb":
                bulbs.append(i)
                if photometric is None:
                    self.color[i] = v["intensity"] if v["on"] else (0.0, 0.0, 0.0)
                else:
                    self.color[i] = emitter_radiance(v, emitting_area(v, geometry, i), photometric, where)
            elif role in ("socket", "side_wall"):
                if photometric is None:  # photometric: unlit, as the parametric socket and side wall
                    self.color[i] = v["color"]
            elif role == "body":
                self.color[i] = v["color"] if photometric is None else photometric.reflectance(v["color"])
                self.specular[i], self.shininess[i] = v["specular"], v["shininess"]
        # A bulb's centre is its mesh's centroid (area-weighted over the surface). Each reflector
        # scatters toward the bulbs whose centre lies in its bounding box, else toward the nearest
        # bulb: in a multi-lamp design each reflector sees its own bulb, as in the parametric lamp.
        self.bulb_center = np.zeros((len(bulbs), 3))
        self.bulb_radius = np.zeros(len(bulbs))  # of the sphere of the mesh's area (its solid angle)
        for b, i in enumerate(bulbs):
            centre, area = part_areas(geometry, i)
            self.bulb_center[b] = (centre * area[:, None]).sum(axis=0) / max(area.sum(), 1e-300)
            self.bulb_radius[b] = math.sqrt(emitting_area(parts[i]["bulb"], geometry, i) / (4.0 * math.pi))
        self.bulb_radiance = self.color[bulbs] if bulbs else np.zeros((0, channels))
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


def emitting_area(source: dict, geometry: Geometry, part: int) -> float:
    """mm² of a bulb part's emitting surface: the sphere it stands for (``radius``, as Convert to
    Free-form gives a converted bulb: the parametric bulb's, whose tessellation is a little smaller),
    else the mesh's own area."""
    radius = source.get("radius", 0.0)
    return 4.0 * math.pi * radius * radius if radius > 0.0 else float(part_areas(geometry, part)[1].sum())


def emitter_radiance(source: dict, area_mm2: float, photometric: spectral.Photometric, where: str) -> np.ndarray:
    """(K,) spectral radiance, W/(m² sr nm), of a Lambertian emitter of ``area_mm2`` giving a source
    section's flux and spectrum (``spectral.bulb_spectrum``): L = Φ / (π A) with the spectrum's shape,
    which for a sphere of radius r is the parametric bulb's Φ / (4π² r²). 0 when it is off."""
    if not source["on"] or area_mm2 <= 0.0:
        return np.zeros(photometric.channels)
    flux, spectrum = spectral.bulb_spectrum(source, where)
    # the radiance of a sphere of the same area: bulb_spectral_radiance's Φ/(4π² r²) = Φ/(π A)
    return spectral.sources.bulb_spectral_radiance(flux, spectrum, math.sqrt(area_mm2 / (4.0 * math.pi)),
                                                   photometric.bands)

"""Every lamp's parameters as arrays indexed by lamp number, gathered per ray by the parts and
the tracer (MODEL.md §3: lens, cuts, reflector, bulb, socket of each lamp)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..scene.derived import cut_sphere_radius, lamp_geometry, lens_absorption
from .outline import Outline


@dataclass(frozen=True)
class LampTable:
    """Every lamp's parameters as arrays indexed by lamp number (gathered per ray)."""

    center: np.ndarray  # (L, 2) [x, z] of the axis in the world
    radius: np.ndarray
    rectangular: np.ndarray  # 1.0 for a rectangular outline (``outline``), 0.0 for a round one
    half_size: np.ndarray  # (L, 2) half width and half height of the outline (R, R when round)
    corner: np.ndarray  # corner radius of the outline (R when round)
    plane_a: np.ndarray  # y of the cut base (= lens thickness)
    plane_b: np.ndarray  # y of the cut apexes
    pitch: np.ndarray
    cut_radius: np.ndarray  # rho of the lenslet spheres (inf for a flat inner face)
    ior: np.ndarray
    absorption: np.ndarray  # (L, 3) per mm
    wall_color: np.ndarray  # (L, 3)
    lens_diffuse: np.ndarray  # (L, 3)
    lens_specular: np.ndarray
    lens_shininess: np.ndarray
    focal: np.ndarray
    rim: np.ndarray
    vertex: np.ndarray
    reflector_color: np.ndarray  # (L, 3)
    reflectance: np.ndarray
    scatter: np.ndarray
    scatter_shininess: np.ndarray
    bulb_center: np.ndarray  # (L, 3) local
    bulb_radius: np.ndarray
    bulb_intensity: np.ndarray  # (L, 3), zero when the bulb is off
    socket_radius: np.ndarray
    socket_color: np.ndarray  # (L, 3)

    @classmethod
    def from_scene(cls, scene: dict) -> LampTable:
        rows = []
        for lamp in scene["lamps"]:
            g = lamp_geometry(lamp)
            lens, cuts, refl, bulb = lamp["lens"], lamp["cuts"], lamp["reflector"], lamp["bulb"]
            h = cuts["height"]
            shape = Outline.of_lens(lens)
            rows.append(dict(
                center=lamp["center"], radius=lens["radius"], rectangular=0.0 if shape.round else 1.0,
                half_size=[shape.half_w, shape.half_h], corner=shape.corner, plane_a=g["plane_a"], plane_b=g["plane_b"],
                pitch=cuts["pitch"], cut_radius=cut_sphere_radius(cuts["pitch"], h) if h > 0 else np.inf,
                ior=lens["ior"], absorption=lens_absorption(lens), wall_color=lens["side_wall_color"],
                lens_diffuse=lens["diffuse_color"], lens_specular=lens["specular"],
                lens_shininess=lens["shininess"], focal=refl["focal_length"], rim=g["rim"], vertex=g["vertex"],
                reflector_color=refl["color"], reflectance=refl["reflectance"], scatter=refl["scatter"],
                scatter_shininess=refl["shininess"], bulb_center=g["bulb_center"], bulb_radius=bulb["radius"],
                bulb_intensity=bulb["intensity"] if bulb["on"] else [0.0, 0.0, 0.0],
                socket_radius=lamp["socket"]["radius"], socket_color=lamp["socket"]["color"],
            ))
        return cls(**{k: np.array([r[k] for r in rows], dtype=np.float64) for k in rows[0]})

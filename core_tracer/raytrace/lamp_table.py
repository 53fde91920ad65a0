"""Every lamp's parameters as arrays indexed by lamp number, gathered per ray by the parts and
the tracer (docs/model.md §3: lens, cuts, reflector, bulb, socket of each lamp)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..scene.derived import cut_sphere_radius, flute_radius, lamp_geometry, lens_absorption, lens_cylinder
from ..scene.led_array import LedArray, uses_leds
from ..scene.outline import Outline
from ..scene.prism_profile import ring_slopes
from .guide_table import GuideTable

CYLINDER_KEYS = ("axis_x", "radius", "side", "base", "apex", "phi_center", "corner")


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
    sawtooth: np.ndarray  # 1 where the cuts are saw-tooth ridges (parts.sawtooth), else 0
    flutes: np.ndarray  # 1 where the cuts are cylindrical flutes (parts.flutes), else 0
    flute_radius: np.ndarray  # radius of the flutes' cylinders (inf for a flat inner face)
    tooth_slope: np.ndarray  # tan of the saw-tooth facets' angle to the lens plane
    ridge_across: np.ndarray  # (L, 2) [x, z] unit vector across the ridges, the way the facets rise
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
    # what a ray that meets the bulb sees, zero when the bulb is off: the paper mode's bulb intensity I0
    # (eq. 3, R, G, B); photometric, its spectral radiance L(λ) in W/(m² sr nm) per band (``spectral``)
    bulb_radiance: np.ndarray  # (L, 3) or (L, K)
    socket_radius: np.ndarray
    socket_color: np.ndarray  # (L, 3)
    # A cylindrical lens (``scene.derived.lens_cylinder``): 1.0 where the lamp has one, and its
    # geometry in ``cyl_<key>`` for the keys of CYLINDER_KEYS (NaN for a flat lens).
    cylindrical: np.ndarray
    cyl_axis_x: np.ndarray
    cyl_radius: np.ndarray
    cyl_side: np.ndarray
    cyl_base: np.ndarray
    cyl_apex: np.ndarray
    cyl_phi_center: np.ndarray
    cyl_corner: np.ndarray

    @property
    def any_cylindrical(self) -> bool:
        return bool(self.cylindrical.any())

    def cylinder_of(self, lamp: np.ndarray) -> dict[str, np.ndarray]:
        """Per ray, the cylinder geometry of its lamp (keys of CYLINDER_KEYS)."""
        return {k: getattr(self, "cyl_" + k)[lamp] for k in CYLINDER_KEYS}
    # The prism plate (docs/model.md, the prism plate): a lamp without one has its planes at +inf, so no
    # ray meets it; a lamp with one has its reflector's rim at +inf, so no ray meets the reflector.
    plate_front: np.ndarray  # y of the flat front face
    plate_base: np.ndarray  # y of the ring bottoms (plane A of the ring walk)
    plate_peak: np.ndarray  # y of the highest ring top (plane B)
    plate_pitch: np.ndarray
    plate_ior: np.ndarray
    plate_absorption: np.ndarray  # (L, 3) per mm
    housing_back: np.ndarray  # y of the housing's back
    housing_color: np.ndarray  # (L, 3)
    ring_slopes: np.ndarray  # (L, most rings) facet slope of each ring (``prism_profile``), 0 past the last
    ring_count: np.ndarray  # (L,) rings of each plate (0 without one)
    # The LED dies (``scene.led_array``; docs/photometric.md, "LED sources"): a lamp whose source is
    # its LEDs has led_columns > 0, its bulb and socket out of reach (``has_bulb`` 0, bulb radius 0).
    has_bulb: np.ndarray  # 1 where the lamp's source is its bulb
    led_center: np.ndarray  # (L, 3) the array's centre
    led_normal: np.ndarray  # (L, 3) the side the dies emit from
    led_across: np.ndarray  # (L, 3)
    led_up: np.ndarray  # (L, 3)
    led_half: np.ndarray  # (L, 2) half width and half height of a die
    led_pitch: np.ndarray  # (L, 2)
    led_columns: np.ndarray  # dies across (0: no LEDs)
    led_rows: np.ndarray
    # The luminance of a die seen straight on, per channel: the paper mode's bulb intensity (RGB),
    # photometric: the spectral radiance of a Lambertian die of its flux (``spectral.led_radiance``);
    # times ``led_patterns[lamp].factor`` in other directions. 0 when the lamp is off.
    led_radiance: np.ndarray  # (L, 3) or (L, K)
    # The photometric mode's values per lamp and band (``spectral.photometric_lamps``; None in the
    # paper mode): the lens's and the plate's refractive index per band for Fresnel (their ``ior``
    # being n_d, which the rays' directions follow), and the reflector finish's spectral reflectance.
    ior_bands: np.ndarray | None = None
    plate_ior_bands: np.ndarray | None = None
    reflector_bands: np.ndarray | None = None
    led_patterns: tuple = ()  # per lamp its dies' ``photometry.far_field.Pattern`` (() in the paper mode: Lambertian)
    # The lamps' light guides (``guide_table``); None when no lamp has one (every lamp renders as before).
    guide: GuideTable | None = None

    @property
    def any_leds(self) -> bool:
        return bool(self.led_columns.any())

    @classmethod
    def from_scene(cls, scene: dict) -> LampTable:
        rows = []
        for lamp in scene["lamps"]:
            g = lamp_geometry(lamp)
            lens, cuts, refl, bulb = lamp["lens"], lamp["cuts"], lamp["reflector"], lamp["bulb"]
            h = cuts["height"]
            cyl = lens_cylinder(lamp)
            shape = Outline.of_lens(lens)
            saw = cuts.get("type", "fisheye") == "sawtooth"
            flutes = cuts.get("type", "fisheye") == "flutes"
            ridge = math.radians(cuts.get("orientation", 0.0))
            row = dict(
                center=lamp["center"], radius=lens["radius"], rectangular=0.0 if shape.round else 1.0,
                half_size=[shape.half_w, shape.half_h], corner=shape.corner, plane_a=g["plane_a"], plane_b=g["plane_b"],
                pitch=cuts["pitch"],
                cut_radius=cut_sphere_radius(cuts["pitch"], h) if h > 0 and not saw and not flutes else np.inf,
                sawtooth=float(saw), flutes=float(flutes),
                flute_radius=flute_radius(cuts["pitch"], h) if h > 0 else np.inf,
                tooth_slope=math.tan(math.radians(cuts.get("tooth_angle", 0.0))),
                ridge_across=[-math.sin(ridge), math.cos(ridge)],
                ior=lens["ior"], absorption=lens_absorption(lens), wall_color=lens["side_wall_color"],
                lens_diffuse=lens["diffuse_color"], lens_specular=lens["specular"],
                lens_shininess=lens["shininess"], focal=refl["focal_length"], rim=g["rim"], vertex=g["vertex"],
                reflector_color=refl["color"], reflectance=refl["reflectance"], scatter=refl["scatter"],
                scatter_shininess=refl["shininess"], bulb_center=g["bulb_center"], bulb_radius=bulb["radius"],
                bulb_radiance=bulb["intensity"] if bulb["on"] else [0.0, 0.0, 0.0],
                socket_radius=lamp["socket"]["radius"], socket_color=lamp["socket"]["color"],
                cylindrical=cyl is not None, **{"cyl_" + k: math.nan if cyl is None else cyl[k] for k in CYLINDER_KEYS},
            )
            row.update(_plate_row(lamp, g))
            row.update(_led_row(lamp, row))
            rows.append(row)
        slopes = [r.pop("ring_slopes") for r in rows]
        table = np.zeros((len(rows), max(len(s) for s in slopes)))
        for row, s in zip(table, slopes, strict=True):
            row[:len(s)] = s
        guide = GuideTable.from_scene(scene)
        return cls(ring_slopes=table, guide=guide if guide.any else None,
                   **{k: np.array([r[k] for r in rows], dtype=np.float64) for k in rows[0]})


def _led_row(lamp: dict, row: dict) -> dict:
    """The LED entries of one lamp's row; a lamp lit by LEDs has no bulb to meet, glow toward or
    trace light from (its radius 0), and the paper's Blinn glow toward the bulb is off."""
    if not uses_leds(lamp):
        zero3 = [0.0, 0.0, 0.0]
        return dict(has_bulb=1.0, led_center=zero3, led_normal=[0.0, -1.0, 0.0], led_across=[1.0, 0.0, 0.0],
                    led_up=[0.0, 0.0, 1.0], led_half=[0.0, 0.0], led_pitch=[1.0, 1.0], led_columns=0, led_rows=0,
                    led_radiance=zero3)
    leds = LedArray.of(lamp["led"])
    return dict(has_bulb=0.0, bulb_radius=0.0, scatter=0.0, led_center=leds.center, led_normal=leds.normal,
                led_across=leds.across, led_up=leds.up, led_half=leds.half_size, led_pitch=leds.pitch,
                led_columns=leds.columns, led_rows=leds.rows, led_radiance=row["bulb_radiance"])


def _plate_row(lamp: dict, g: dict) -> dict:
    """The prism plate's entries of one lamp's row, and the reflector's rim moved out of reach."""
    if lamp.get("collection", "reflector") != "prism_plate":
        inf = np.inf
        return dict(plate_front=inf, plate_base=inf, plate_peak=inf, plate_pitch=1.0, plate_ior=1.0,
                    plate_absorption=[0.0, 0.0, 0.0], housing_back=inf, housing_color=[0.0, 0.0, 0.0],
                    ring_slopes=np.zeros(1), ring_count=0)
    plate = lamp["prism_plate"]
    slopes = ring_slopes(lamp["lens"]["radius"], plate["pitch"], plate["focal_length"], plate["ior"])
    return dict(rim=np.inf, plate_front=g["plate_front"], plate_base=g["plate_base"], plate_peak=g["plate_peak"],
                plate_pitch=plate["pitch"], plate_ior=plate["ior"], plate_absorption=plate["absorption"],
                housing_back=g["vertex"], housing_color=plate["housing_color"], ring_slopes=slopes,
                ring_count=len(slopes))

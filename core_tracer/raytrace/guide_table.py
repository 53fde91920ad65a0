"""The light guides of a design's lamps as arrays indexed by lamp number (docs/photometric.md, light
guides): where each guide lies in its lamp's frame, its cross-section and its extraction prisms (its
LEDs are the lamp's own dies). A lamp without a guide has ``present`` 0 and no ray meets its row."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class GuideTable:
    """Per lamp (L rows): a straight rod from its first end face (``start``, s = 0) along ``axis`` to
    s = ``length``; u across it in the lens plane, v along the lamp axis (+y, the guide's back).
    Material: the lamp's second dielectric (``LampTable.plate_ior``, ``plate_absorption``): a lamp
    has a prism plate or a guide, never both."""

    present: np.ndarray  # (L,) 1 where the lamp has a guide
    start: np.ndarray  # (L, 3) centre of the first end face, lamp frame
    axis: np.ndarray  # (L, 3) unit vector along the guide
    across: np.ndarray  # (L, 3) unit vector across it in the lens plane (u)
    round: np.ndarray  # (L,) 1 for a round rod (radius half_u), 0 for a rectangular one
    half_u: np.ndarray  # half width across (the radius when round)
    half_v: np.ndarray  # half thickness along y (the radius when round)
    length: np.ndarray
    pitch: np.ndarray  # prism spacing along s
    prism_depth: np.ndarray  # 0: no prisms
    slope: np.ndarray  # tan of the facets' angle to the axis
    prisms: np.ndarray  # (L,) number of prisms
    first_prism: np.ndarray  # s of the first prism's apex line
    # lit_ends "both": the lamp's LED array has a mirror image through the plane s = L/2 (``mirror``)
    both_ends: np.ndarray  # (L,) 1 where the guide is lit at both ends
    middle: np.ndarray  # (L, 3) the middle of the guide's axis (s = L/2)
    # An arc guide (path "arc", rectangular): its axis P(φ) = C + R (sin φ · axis − cos φ · across),
    # |φ| <= Φ/2, so that ``axis`` is its tangent at the middle and it bends toward ``across``; s = R (φ + Φ/2)
    arc: np.ndarray  # (L,) 1 for an arc guide
    arc_centre: np.ndarray  # (L, 3) C, at the guide's depth
    radius: np.ndarray  # R
    sweep: np.ndarray  # Φ (rad)

    @property
    def any(self) -> bool:
        return bool(self.present.any())

    @classmethod
    def from_scene(cls, scene: dict) -> GuideTable:
        rows = [_row(lamp.get("light_guide")) for lamp in scene["lamps"]]
        return cls(**{key: np.array([r[key] for r in rows], dtype=np.float64) for key in rows[0]})

    def mirror(self, points: np.ndarray, directions: np.ndarray, lamp: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Points and directions (N, 3) reflected through their lamps' guides' middle planes s = L/2:
        x' = x − 2 ((x − m)·a) a, d' = d − 2 (d·a) a, with a the axis (at the middle) and m the middle."""
        axis = self.axis.take(lamp, axis=0)
        middle = self.middle.take(lamp, axis=0)
        off = np.einsum("ij,ij->i", points - middle, axis)
        along = np.einsum("ij,ij->i", directions, axis)
        return points - 2.0 * off[:, None] * axis, directions - 2.0 * along[:, None] * axis

    def along(self, points: np.ndarray, lamp: np.ndarray) -> np.ndarray:
        """s of points (N, 3) in their lamps' guides: along the axis from the first end face (of an arc
        guide, R (φ + Φ/2) with φ the points' angle about its centre from the middle)."""
        rel = points - self.start.take(lamp, axis=0)
        s = np.einsum("ij,ij->i", rel, self.axis.take(lamp, axis=0))
        arc = np.nonzero(self.arc.take(lamp) > 0)[0]
        if len(arc):
            index = lamp.take(arc)
            rel = points.take(arc, axis=0) - self.arc_centre.take(index, axis=0)
            phi = np.arctan2(np.einsum("ij,ij->i", rel, self.axis.take(index, axis=0)),
                             -np.einsum("ij,ij->i", rel, self.across.take(index, axis=0)))
            s[arc] = self.radius.take(index) * (phi + 0.5 * self.sweep.take(index))
        return s


def prism_layout(length: float, pitch: float, depth: float, slope: float) -> tuple[int, float]:
    """(number of prisms, s of the first apex): V grooves of depth ``depth`` whose facets rise at
    ``slope`` (tan) are 2 depth / slope wide; as many as fit along ``length`` at ``pitch``, the row
    centred on the guide."""
    if depth <= 0.0:
        return 0, 0.0
    width = 2.0 * depth / slope
    if width > length:
        return 0, 0.0
    count = int(math.floor((length - width) / pitch + 1e-9)) + 1
    return count, 0.5 * (length - (count - 1) * pitch)


def _row(guide: dict | None) -> dict:
    if not guide or not guide.get("enabled"):
        zero3 = [0.0, 0.0, 0.0]
        return dict(present=0.0, start=zero3, axis=[1.0, 0.0, 0.0], across=[0.0, 0.0, 1.0], round=1.0, half_u=1.0,
                    half_v=1.0, length=1.0, pitch=1.0, prism_depth=0.0, slope=1.0, prisms=0.0, first_prism=0.0,
                    both_ends=0.0, middle=zero3, arc=0.0, arc_centre=zero3, radius=1.0, sweep=1.0)
    theta = math.radians(guide["orientation"])
    axis = [math.cos(theta), 0.0, math.sin(theta)]
    across = [-math.sin(theta), 0.0, math.cos(theta)]
    cx, cz = guide["center"]
    middle = [cx, guide["depth"], cz]
    arc = guide.get("path", "straight") == "arc"
    radius, sweep = guide.get("arc_radius", 1.0), math.radians(guide.get("arc_sweep", 60.0))
    centre = [cx + radius * across[0], guide["depth"], cz + radius * across[2]]
    if arc:  # the first end face's centre: P(−Φ/2)
        length = radius * sweep
        start = [centre[i] + radius * (-math.sin(0.5 * sweep) * axis[i] - math.cos(0.5 * sweep) * across[i])
                 for i in range(3)]
        start[1] = guide["depth"]
    else:
        length = guide["length"]
        start = [cx - 0.5 * length * axis[0], guide["depth"], cz - 0.5 * length * axis[2]]
    if guide["section"] == "round":
        half_u = half_v = 0.5 * guide["diameter"]
    else:
        half_u, half_v = 0.5 * guide["width"], 0.5 * guide["thickness"]
    slope = math.tan(math.radians(guide["prism_angle"]))
    count, first = prism_layout(length, guide["prism_pitch"], guide["prism_depth"], slope)
    return dict(present=1.0, start=start, axis=axis, across=across, round=float(guide["section"] == "round"),
                half_u=half_u, half_v=half_v, length=length, pitch=guide["prism_pitch"],
                prism_depth=guide["prism_depth"] if count else 0.0, slope=slope, prisms=float(count), first_prism=first,
                both_ends=float(guide.get("lit_ends", "one") == "both"), middle=middle, arc=float(arc),
                arc_centre=centre, radius=radius, sweep=sweep)
